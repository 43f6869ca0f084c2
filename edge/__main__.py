"""``python -m edge run --config RIG.toml --bundle DIR``: the runtime without the host tools."""

import sys

from edge.cli import main

sys.exit(main())
