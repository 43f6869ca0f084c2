"""Small HIL recordings for the neural-model tests, written once per session as CSV files."""

from __future__ import annotations

from pathlib import Path

from hil.record import record, write_recording


def hil_csv(directory: Path, scenario: str, seed: int, duration_s: float, effect: str = "none") -> Path:
    """``pmactl hil record`` in-process: ``directory/<scenario>_<effect>_<seed>.csv``."""
    path = directory / f"{scenario}_{effect}_{seed}.csv"
    if not path.exists():
        write_recording(record(scenario, seed, duration_s, effect=effect), path)
    return path
