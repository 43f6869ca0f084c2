"""``python -m host.cli`` runs the pmactl command line."""

from host.cli import main

raise SystemExit(main())
