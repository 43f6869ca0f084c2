"""Per-tick telemetry: a bounded ring the tick copies its frame into, drained to a file by a
thread.

The tick only copies one row (its frame, :mod:`edge.runtime.frame`) into a preallocated ring
and bumps a counter: it never waits for the disk. A writer thread appends finished rows to the
file every ``flush_interval_s``. If the disk stalls for longer than the ring holds, the oldest
unwritten rows are overwritten and counted in ``dropped``. A write that fails (a full disk)
stops the writer and sets :attr:`TelemetryWriter.failure`; the runtime turns it into a fault
(the valve vents, the summary is still printed). :meth:`TelemetryWriter.close` drains
everything and fsyncs, so a normal stop or SIGTERM leaves a complete file.

A run never overwrites another: the file is created exclusively (an existing path is refused).

File layout: a magic line ``PMACTL-TELEMETRY 2``, one JSON header line (``columns``, ``dtype``
as numpy's ``descr``, codes, run information), then packed little-endian rows of that dtype,
one per tick. Events (arming, faults, the end of the run with its summary) go to
``<file>.events.jsonl`` as they happen, one JSON object per line. Version 1 files (all columns
float64) are still read.
"""

from __future__ import annotations

import ctypes
import json
import os
import threading
from pathlib import Path
from typing import Any

import numpy as np

from edge.errors import DataError

MAGIC = b"PMACTL-TELEMETRY 2\n"
MAGIC_V1 = b"PMACTL-TELEMETRY 1\n"


def events_path(path: str | Path) -> Path:
    return Path(f"{path}.events.jsonl")


class RingWriter:
    """A bounded ring the tick copies its frame into, drained by a thread every
    ``flush_interval_s``: the template of :class:`TelemetryWriter` and of the recording CSV
    (:mod:`edge.runtime.recorder`). A subclass opens its files, calls :meth:`_start_ring`, and
    implements :meth:`_write_rows` (a chunk of finished rows), :meth:`_after_drain` (flush,
    events) and :meth:`_close_files`."""

    path: Path
    dropped: int
    written: int
    failure: str | None

    def _start_ring(self, dtype: np.dtype, ring_ticks: int, flush_interval_s: float) -> None:
        self.dtype = dtype
        self._ring = np.zeros(ring_ticks, dtype=dtype)
        self._base = self._ring.ctypes.data
        self._ring_bytes = self._ring.view(np.uint8).data
        self._source: memoryview | None = None
        self._row_bytes = dtype.itemsize
        self._size = ring_ticks
        self._head = 0  # rows the tick has written (monotonic)
        self._tail = 0  # rows the writer has taken
        self.dropped = 0
        self.written = 0
        self._stop = threading.Event()
        self._interval = flush_interval_s
        self._thread = threading.Thread(target=self._run, name=f"pmactl-{type(self).__name__}", daemon=True)
        self._thread.start()

    # tick side --------------------------------------------------------------------------------
    def record(self, frame: Any) -> None:
        """Copy one tick's frame (a ctypes row of :attr:`dtype`) into the ring. Never blocks."""
        ctypes.memmove(
            self._base + (self._head % self._size) * self._row_bytes, ctypes.addressof(frame), self._row_bytes
        )
        self._head += 1

    def bind(self, frame_bytes: memoryview) -> None:
        """The frame :meth:`record_bound` copies (its bytes, ``FrameLayout.bytes_view``)."""
        if len(frame_bytes) != self._row_bytes:
            raise ValueError(f"frame of {len(frame_bytes)} bytes, rows of {self._row_bytes}")
        self._source = frame_bytes

    def record_bound(self) -> None:
        """Copy the bound frame into the ring (a slice copy: ~0.3 us). Never blocks."""
        start = (self._head % self._size) * self._row_bytes
        self._ring_bytes[start : start + self._row_bytes] = self._source  # type: ignore[assignment]
        self._head += 1

    def record_array(self, row: np.ndarray) -> None:
        """Store one row given as a numpy structured scalar/array of :attr:`dtype`."""
        self._ring[self._head % self._size] = row
        self._head += 1

    # writer side ------------------------------------------------------------------------------
    def _run(self) -> None:
        while not self._stop.wait(self._interval) and self.failure is None:
            self._drain()

    def _fail(self, exc: OSError) -> None:
        if self.failure is None:
            self.failure = (
                f"{self._what} write to {self.path} failed ({exc.strerror or exc}); rows from here on are lost"
            )

    _what = "telemetry"

    def _drain(self) -> None:
        if self.failure is not None:
            return
        head = self._head
        if head - self._tail > self._size:
            self.dropped += head - self._tail - self._size
            self._tail = head - self._size
        start, stop = self._tail % self._size, head % self._size
        try:
            if head > self._tail:
                if start < stop:
                    chunk = self._ring[start:stop].copy()
                else:
                    chunk = np.concatenate([self._ring[start:], self._ring[:stop]])
                self._write_rows(chunk)
                self.written += len(chunk)
                self._tail = head
            self._after_drain()
        except OSError as exc:
            self._fail(exc)

    def _write_rows(self, chunk: np.ndarray) -> None:
        raise NotImplementedError

    def _after_drain(self) -> None:
        raise NotImplementedError

    def _close_files(self) -> None:
        raise NotImplementedError

    def close(self) -> None:
        """Stop the writer, write every remaining row, fsync and close (as far as the disk lets)."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join()
        self._drain()
        self._close_files()

    def _sync_close(self, handle: Any) -> None:
        try:
            handle.flush()
            os.fsync(handle.fileno())
        except OSError as exc:
            self._fail(exc)
        try:
            handle.close()
        except OSError as exc:  # a buffered write that still cannot go out
            self._fail(exc)


class SampledRing(RingWriter):
    """A ring that keeps the first tick at or after every ``_every`` periods (by the frame's
    ``t``, so a tick skipped by an overrun moves that row to the next tick, with its true time).
    A subclass sets ``_every`` (ticks per row) before :meth:`bind_frame`."""

    _every = 1
    _next_t = 0.0
    _frame: Any = None
    _sample_s = _half_tick = 0.0

    def bind_frame(self, frame: Any, period_s: float) -> None:
        """The frame (a ctypes row) :meth:`record_bound` samples, and the loop's period [s]."""
        self.bind(memoryview(frame).cast("B"))
        self._frame, self._sample_s = frame, self._every * period_s
        self._half_tick = 0.5 * period_s

    def record_bound(self) -> None:
        """Copy the bound frame into the ring when a sample is due. Never blocks."""
        t = self._frame.t
        if t + self._half_tick >= self._next_t:
            RingWriter.record_bound(self)
            self._next_t += self._sample_s * (1 + int((t + self._half_tick - self._next_t) // self._sample_s))


class TelemetryWriter(RingWriter):
    """Ring buffer + writer thread (see module docstring).

    Args:
        path: telemetry file to create (refused if it exists).
        header: run information stored in the header line (JSON-serialisable).
        dtype: the row type (a frame's structured dtype).
        ring_ticks: rows the ring holds.
        flush_interval_s: how often the writer drains the ring [s].
    """

    def __init__(
        self,
        path: str | Path,
        header: dict[str, object],
        dtype: np.dtype,
        ring_ticks: int = 65_536,
        flush_interval_s: float = 0.1,
    ) -> None:
        self.path = Path(path)
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise DataError(f"{self.path}: cannot write telemetry ({exc.strerror}); choose a writable path") from exc
        try:
            self._file = self.path.open("xb")
        except FileExistsError as exc:
            raise DataError(
                f"{self.path}: exists, and a run never overwrites another; choose a new path "
                "(a {time} in the name is replaced by the start time)"
            ) from exc
        except OSError as exc:
            raise DataError(f"{self.path}: cannot write telemetry ({exc.strerror}); choose a writable path") from exc
        try:
            self._events_file = events_path(self.path).open("x")
        except OSError as exc:
            self._file.close()
            self.path.unlink()
            raise DataError(f"{events_path(self.path)}: cannot create the event log ({exc.strerror})") from exc
        self.dtype = dtype
        self.failure = None  # set once when a write fails (the runtime trips on it)
        self._events: list[str] = []
        self._lock = threading.Lock()  # guards _events only; the ring is single-producer
        self._write_header(header)
        self._start_ring(dtype, ring_ticks, flush_interval_s)

    def _write_header(self, header: dict[str, object]) -> None:
        meta = {"columns": list(self.dtype.names or ()), "dtype": self.dtype.descr, **header}
        try:
            self._file.write(MAGIC + json.dumps(meta).encode() + b"\n")
            self._file.flush()
        except OSError as exc:
            self._fail(exc)

    def event(self, t: float, kind: str, text: str, **extra: object) -> None:
        """A state change, fault or note, written within one flush interval."""
        line = json.dumps({"t": round(t, 6), "kind": kind, "text": text, **extra})
        with self._lock:
            self._events.append(line)

    def _write_rows(self, chunk: np.ndarray) -> None:
        self._file.write(chunk.tobytes())

    def _after_drain(self) -> None:
        self._file.flush()
        with self._lock:
            events, self._events = self._events, []
        if events:
            self._events_file.write("\n".join(events) + "\n")
            self._events_file.flush()

    def _close_files(self) -> None:
        if self._file.closed:
            return
        for handle in (self._file, self._events_file):
            self._sync_close(handle)


def read_telemetry(path: str | Path) -> Any:
    """Read a telemetry file back (:func:`edge.runtime.telemetry_read.read_telemetry`)."""
    from edge.runtime.telemetry_read import read_telemetry as read

    return read(path)
