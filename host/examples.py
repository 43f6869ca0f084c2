"""The example data shipped with pmactl, recorded on the HIL emulator.

``pma_triangles.csv``: Ai2019's protocol (triangles 0 -> 1, 2, 3, 4 bar at 0.05 Hz, 80 s);
``pma_mixed.csv``: every protocol in turn (60 s). Both from the default rig (no hidden effect)
at 100 Hz. Regenerate with ``python -m host.examples [OUT_DIR]``, which runs the same as::

    pmactl hil record --scenario triangles --seed 1 --duration 80 --out pma_triangles.csv
    pmactl hil record --scenario mixed --seed 2 --duration 60 --out pma_mixed.csv
"""

from __future__ import annotations

import sys
from importlib import resources
from pathlib import Path

from hil.record import record, write_recording

EXAMPLES = {"train": ("pma_triangles.csv", "triangles", 1, 80.0), "test": ("pma_mixed.csv", "mixed", 2, 60.0)}


def example_path(role: str) -> Path:
    """Path of a shipped example recording: ``role`` is ``"train"`` or ``"test"``."""
    return Path(str(resources.files("host") / "example_data" / EXAMPLES[role][0]))


def main(argv: list[str] | None = None) -> int:
    """Write the example recordings to ``argv[0]`` (default: the package's example_data)."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else example_path("train").parent
    for name, scenario, seed, duration in EXAMPLES.values():
        path = write_recording(record(scenario, seed, duration), out / name)
        path.with_name(path.stem + ".truth.json").unlink()  # no effect hidden: nothing to tell
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
