"""Reading telemetry back: what can be read is read, and what was skipped is said.

A power cut leaves a partial last row (ignored and counted); a damaged header or event line is
reported in :attr:`Telemetry.problems`. When nothing at all can be read, :class:`DataError`
says why in one line.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from edge.errors import DataError
from edge.runtime.telemetry import MAGIC, MAGIC_V1, events_path

HEADER_MAX_BYTES = 1 << 20


@dataclass
class Telemetry:
    """A telemetry file read back: header, rows (structured, one per tick) and events."""

    header: dict[str, object]
    rows: np.ndarray
    events: list[dict[str, object]]
    truncated_bytes: int = 0
    problems: list[str] = field(default_factory=list)

    @property
    def columns(self) -> list[str]:
        return list(self.rows.dtype.names or ())

    def column(self, name: str) -> np.ndarray:
        """One column as float64 (codes included)."""
        if name not in self.columns:
            raise DataError(f"telemetry has no column {name!r}; it has {', '.join(self.columns)}")
        return self.rows[name].astype(np.float64)


def _dtype(header: dict[str, object], source: Path, v1: bool) -> np.dtype:
    columns = header.get("columns")
    if not isinstance(columns, list) or not columns or not all(isinstance(c, str) for c in columns):
        raise DataError(f"{source}: header has no column list; the file cannot be decoded")
    if v1:
        if header.get("dtype") not in ("<f8", "float64"):
            raise DataError(f"{source}: header dtype {header.get('dtype')!r} is not <f8; the file cannot be decoded")
        return np.dtype([(c, "<f8") for c in columns])
    descr = header.get("dtype")
    try:
        if not isinstance(descr, list):
            raise TypeError("not a list of (name, type) pairs")
        dtype = np.dtype([tuple(item) for item in descr])
    except (TypeError, ValueError) as exc:
        raise DataError(
            f"{source}: header dtype {descr!r} is not a row type ({exc}); the file cannot be decoded"
        ) from exc
    if list(dtype.names or ()) != columns or dtype.itemsize == 0:
        raise DataError(f"{source}: header dtype does not match its columns; the file cannot be decoded")
    return dtype


def read_events(source: Path) -> tuple[list[dict[str, object]], list[str]]:
    """The event log beside ``source``; damaged lines are skipped and named."""
    log = events_path(source)
    events: list[dict[str, object]] = []
    problems: list[str] = []
    if not log.is_file():
        return events, problems
    for number, line in enumerate(log.read_bytes().decode("utf-8", "replace").splitlines(), 1):
        if not line.strip():
            continue
        try:
            event = json.loads(line)
            if not isinstance(event, dict) or not {"t", "kind", "text"} <= set(event):
                raise ValueError("not an event object")
            events.append(event)
        except ValueError:
            problems.append(f"{log.name} line {number} is damaged and was skipped")
    return events, problems


def read_telemetry(path: str | Path) -> Telemetry:
    """Read a telemetry file (see the module docstring)."""
    source = Path(path)
    if source.is_dir():
        raise DataError(f"{source}: is a directory; give the .pmt file written by pmactl edge run --telemetry")
    try:
        data = source.read_bytes()
    except FileNotFoundError as exc:
        raise DataError(f"{source}: no such telemetry file") from exc
    except OSError as exc:
        raise DataError(f"{source}: cannot read ({exc.strerror})") from exc
    v1 = data.startswith(MAGIC_V1)
    if not (data.startswith(MAGIC) or v1):
        if MAGIC.startswith(data[: len(MAGIC)]) and len(data) < len(MAGIC):
            raise DataError(f"{source}: cut off inside its first line ({len(data)} bytes); no rows to read")
        raise DataError(f"{source}: not a pmactl telemetry file (written by pmactl edge run --telemetry)")
    start = len(MAGIC)
    end = data.find(b"\n", start, start + HEADER_MAX_BYTES)
    if end < 0:
        raise DataError(f"{source}: cut off inside its header ({len(data)} bytes); no rows to read")
    try:
        header = json.loads(data[start:end])
        if not isinstance(header, dict):
            raise ValueError("not an object")
    except ValueError as exc:
        raise DataError(f"{source}: header is not valid JSON ({exc}); the rows cannot be decoded") from exc
    dtype = _dtype(header, source, v1)
    body = memoryview(data)[end + 1 :]
    whole = len(body) // dtype.itemsize * dtype.itemsize
    rows = np.frombuffer(body[:whole], dtype=dtype)
    events, problems = read_events(source)
    if len(body) != whole:
        problems.append(f"{len(body) - whole} bytes of a partial last row ignored")
    return Telemetry(header, rows, events, len(body) - whole, problems)
