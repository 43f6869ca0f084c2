"""Rig configs shipped with the HIL (``docs/examples/hil-rig.toml`` links here)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

HIL_RIG_CONFIG = Path(str(resources.files(__package__) / "hil-rig.toml"))
HIL_JOINT_CONFIG = Path(str(resources.files(__package__) / "hil-joint.toml"))
