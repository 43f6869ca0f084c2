"""The recording CSV of ``pmactl edge record``: the measured-data form every host tool reads
(``pmactl fit``, ``train``, ``diagnose``, ``identify``) written while the rig runs.

Columns (:func:`csv_columns`): ``t`` [s]; ``u`` the command the valve got after the config's
limits (bar; on a joint the commanded angle [deg] that the static inversion turned into the two
valve commands); ``y`` the contraction [mm] (joint: angle [deg]); ``p`` the measured pressure
[bar]; every other analog input by its channel name (``load``, ``temperature``); on a joint
``u1``/``u2`` the valve commands and ``p1``/``p2`` the muscle pressures [bar]. The units, which
column is ``u`` and how the run ended go into ``<name>.meta.json`` beside it.

Like telemetry, the tick copies its frame into a ring (the first tick at or after every
``every`` periods: the CSV is sampled at ``loop rate / every``) and a thread appends rows and flushes every
``flush_interval_s``, so a fault or a killed process loses at most that much. Only ticks that
commanded the protocol are written (the tick that vents is not), and a tick whose sensors could
not be read (NaN) is skipped and counted in ``skipped``.
"""

from __future__ import annotations

import io
import json
import math
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from edge.errors import DataError
from edge.runtime.rigspec import ANALOG_IN, RigSpec
from edge.runtime.safety import RUNNING_CODE
from edge.runtime.telemetry import SampledRing


@dataclass(frozen=True)
class Column:
    name: str
    field: str
    unit: str
    meaning: str


def csv_columns(rig: RigSpec) -> list[Column]:
    """The recording's columns for ``rig`` (see the module docstring)."""
    if rig.is_joint:
        columns = [
            Column("t", "t", "s", "time since arming"),
            Column("u", "u_ff_deg", "deg", "commanded angle (static inversion to the two valves)"),
            Column("y", "angle_deg", "deg", "measured joint angle"),
            Column("u1", "u_bar", "bar", "valve A command"),
            Column("u2", "valve_b_bar", "bar", "valve B command"),
        ]
        named = {"pressure": ("p1", "muscle A measured pressure"), "pressure_b": ("p2", "muscle B measured pressure")}
    else:
        columns = [
            Column("t", "t", "s", "time since arming"),
            Column("u", "u_bar", "bar", "commanded pressure (the valve command after the config's limits)"),
            Column("y", "contraction_mm", "mm", "measured contraction"),
        ]
        named = {"pressure": ("p", "measured pressure")}
    for channel in rig.channels:
        if channel.kind != ANALOG_IN or channel.field == rig.output_field:
            continue
        name, meaning = named.get(channel.name, (channel.name, f"channel {channel.name}"))
        columns.append(Column(name, channel.field, channel.unit, meaning))
    return columns


def meta_path(csv_path: str | Path) -> Path:
    """``run.csv`` -> ``run.meta.json``."""
    path = Path(csv_path)
    return path.with_name(path.stem + ".meta.json")


class CsvRecorder(SampledRing):
    """Ring + writer thread into a new CSV (see the module docstring).

    Args:
        path: the CSV to create (an existing file is refused, never overwritten).
        rig: the rig (its columns, :func:`csv_columns`).
        dtype: the frame's row type.
        every: keep every ``every``-th tick.
        meta: what goes into the sidecar (protocol, config, rates); the columns, row count and
            end of the run are added.
    """

    _what = "recording"

    def __init__(
        self,
        path: str | Path,
        rig: RigSpec,
        dtype: np.dtype,
        every: int,
        meta: dict[str, object],
        ring_ticks: int = 65_536,
        flush_interval_s: float = 0.1,
    ) -> None:
        self.path = Path(path)
        self.columns = csv_columns(rig)
        self.meta = {
            **meta,
            "columns": {c.name: {"unit": c.unit, "meaning": c.meaning, "frame_field": c.field} for c in self.columns},
            "u": self.columns[1].meaning,
        }
        self.failure = None
        self.skipped = 0
        self.rows = 0
        self.last_t = math.nan
        parent = self.path.parent if str(self.path.parent) else Path(".")
        if not parent.is_dir():
            raise DataError(f"--out {self.path}: directory {parent} does not exist; create it first")
        for target in (self.path, meta_path(self.path)):
            if target.exists() or target.is_symlink():
                raise DataError(
                    f"--out {self.path}: {target} exists, and a recording never overwrites one; choose a new name"
                )
        try:
            self._file = self.path.open("x", encoding="utf-8", newline="")
            self._file.write(",".join(c.name for c in self.columns) + "\n")
            self._file.flush()
        except OSError as exc:
            raise DataError(f"--out {self.path}: cannot write it ({exc.strerror}); choose a writable path") from exc
        self._fields = [c.field for c in self.columns]
        self._every = every
        try:
            self._write_meta(complete=False)
        except DataError:
            self._file.close()
            raise
        self._start_ring(dtype, ring_ticks, flush_interval_s)

    def _write_rows(self, chunk: np.ndarray) -> None:
        chunk = chunk[chunk["state"] == RUNNING_CODE]
        table = np.column_stack([chunk[f].astype(np.float64) for f in self._fields])
        finite = np.all(np.isfinite(table), axis=1)
        self.skipped += int(np.count_nonzero(~finite))
        table = table[finite]
        if len(table):
            text = io.StringIO()
            np.savetxt(text, table, delimiter=",", fmt=["%.6f"] + ["%.7g"] * (len(self._fields) - 1))
            self._file.write(text.getvalue())
            self.last_t = float(table[-1, 0])
            self.rows += len(table)

    def _after_drain(self) -> None:
        self._file.flush()

    def _close_files(self) -> None:
        if not self._file.closed:
            self._sync_close(self._file)

    def finish(self, end: dict[str, object]) -> None:
        """Close the CSV and write the sidecar with how the run ended."""
        self.close()
        self.meta.update(end)
        self._write_meta(complete=True)

    def _write_meta(self, complete: bool) -> None:
        meta = {
            **self.meta,
            "rows": self.rows,
            "rows_skipped_unreadable": self.skipped,
            "complete": complete,
        }
        target = meta_path(self.path)
        temporary = target.with_name(target.name + ".tmp")
        try:
            temporary.write_text(json.dumps(meta, indent=2) + "\n")
            os.replace(temporary, target)
        except OSError as exc:
            if complete:
                self._fail(exc)
            else:
                raise DataError(f"{target}: cannot write the recording's sidecar ({exc.strerror})") from exc
