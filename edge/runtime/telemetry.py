"""Per-tick telemetry: a bounded ring the tick writes into, drained to a file by a thread.

The tick only stores one row into a preallocated array and bumps a counter: it never waits for
the disk. A writer thread copies finished rows to the file every ``flush_interval_s``. If the
disk stalls for longer than the ring holds, the oldest unwritten rows are overwritten and
counted in ``dropped`` (the tick still never blocks). :meth:`TelemetryWriter.close` drains
everything and fsyncs, so a normal stop or SIGTERM leaves a complete file.

File layout: a magic line ``PMACTL-TELEMETRY 1``, one JSON header line (columns, codes, run
information), then rows of little-endian float64, one per tick. Events (arming, faults, notes)
go to ``<file>.events.jsonl`` as they happen, one JSON object per line.
"""

from __future__ import annotations

import json
import os
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from edge.errors import DataError

MAGIC = b"PMACTL-TELEMETRY 1\n"
COLUMNS = (
    "t",
    "reference_mm",
    "contraction_mm",
    "pressure_bar",
    "u_ff_bar",
    "u_nn_bar",
    "u_fb_bar",
    "u_bar",
    "state",
    "fault",
    "lateness_us",
)
ROW_DTYPE = np.dtype("<f8")


def events_path(path: str | Path) -> Path:
    return Path(f"{path}.events.jsonl")


class TelemetryWriter:
    """Ring buffer + writer thread (see module docstring).

    Args:
        path: telemetry file to create (replaced if present).
        header: run information stored in the header line (JSON-serialisable).
        ring_ticks: rows the ring holds.
        flush_interval_s: how often the writer drains the ring [s].
    """

    def __init__(
        self,
        path: str | Path,
        header: dict[str, object],
        ring_ticks: int = 65_536,
        flush_interval_s: float = 0.1,
    ) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = self.path.open("wb")
            self._events_file = events_path(self.path).open("w")
        except OSError as exc:
            raise DataError(f"{self.path}: cannot write telemetry ({exc.strerror}); choose a writable path") from exc
        self._ring = np.zeros((ring_ticks, len(COLUMNS)), dtype=ROW_DTYPE)
        self._size = ring_ticks
        self._head = 0  # rows the tick has written (monotonic)
        self._tail = 0  # rows the writer has taken
        self.dropped = 0
        self.written = 0
        self._events: list[str] = []
        self._lock = threading.Lock()  # guards _events only; the ring is single-producer
        self._file.write(MAGIC + json.dumps({"columns": COLUMNS, "dtype": ROW_DTYPE.str, **header}).encode() + b"\n")
        self._file.flush()
        self._stop = threading.Event()
        self._interval = flush_interval_s
        self._thread = threading.Thread(target=self._run, name="pmactl-telemetry", daemon=True)
        self._thread.start()

    # tick side --------------------------------------------------------------------------------
    def record(self, row: tuple[float, ...]) -> None:
        """Store one tick's row (values in :data:`COLUMNS` order). Never blocks."""
        self._ring[self._head % self._size] = row
        self._head += 1

    def event(self, t: float, kind: str, text: str) -> None:
        """A state change, fault or note, written within one flush interval."""
        line = json.dumps({"t": round(t, 6), "kind": kind, "text": text})
        with self._lock:
            self._events.append(line)

    # writer side ------------------------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.wait(self._interval):
            self._drain()

    def _drain(self) -> None:
        head = self._head
        if head - self._tail > self._size:
            self.dropped += head - self._tail - self._size
            self._tail = head - self._size
        start, stop = self._tail % self._size, head % self._size
        if head > self._tail:
            if start < stop:
                chunk = self._ring[start:stop].copy()
            else:
                chunk = np.concatenate([self._ring[start:], self._ring[:stop]])
            self._file.write(chunk.tobytes())
            self.written += len(chunk)
            self._tail = head
        self._file.flush()
        with self._lock:
            events, self._events = self._events, []
        if events:
            self._events_file.write("\n".join(events) + "\n")
            self._events_file.flush()

    def close(self) -> None:
        """Stop the writer, write every remaining row and event, fsync."""
        if self._file.closed:
            return
        self._stop.set()
        self._thread.join()
        self._drain()
        for handle in (self._file, self._events_file):
            os.fsync(handle.fileno())
            handle.close()


@dataclass
class Telemetry:
    """A telemetry file read back: header, rows (one per tick) and events."""

    header: dict[str, object]
    rows: np.ndarray
    events: list[dict[str, object]]
    truncated_bytes: int = 0

    def column(self, name: str) -> np.ndarray:
        return self.rows[:, list(self.header["columns"]).index(name)]  # type: ignore[call-overload]


def read_telemetry(path: str | Path) -> Telemetry:
    """Read a telemetry file; a partly written last row (power cut) is ignored and counted."""
    source = Path(path)
    try:
        data = source.read_bytes()
    except FileNotFoundError as exc:
        raise DataError(f"{source}: no such telemetry file") from exc
    if not data.startswith(MAGIC):
        raise DataError(f"{source}: not a pmactl telemetry file (written by pmactl edge run --telemetry)")
    end = data.index(b"\n", len(MAGIC))
    header = json.loads(data[len(MAGIC) : end])
    body = memoryview(data)[end + 1 :]
    width = len(header["columns"]) * ROW_DTYPE.itemsize
    whole = len(body) // width * width
    rows = np.frombuffer(body[:whole], dtype=header["dtype"]).reshape(-1, len(header["columns"]))
    events = []
    log = events_path(source)
    if log.exists():
        events = [json.loads(line) for line in log.read_text().splitlines() if line.strip()]
    return Telemetry(header, rows, events, len(body) - whole)
