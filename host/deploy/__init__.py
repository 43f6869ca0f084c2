"""``pmactl deploy``: ship a bundle release to a rig (a local path or ``ssh://``), check it
there, flip ``current`` atomically, roll back by itself when the new release is not healthy.

The steps on the rig run as ``python -m host.deploy.agent`` of the pmactl installed there, which
needs the ``edge`` extra only; this package imports nothing from the host extra outside
:mod:`host.deploy.transport` (asyncssh) and :mod:`host.deploy.deploy`.
"""

from __future__ import annotations

from edge.errors import PmactlError


class DeployError(PmactlError, OSError):
    """A deploy, rollback or listing that could not be done; the running release is untouched."""
