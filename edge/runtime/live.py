"""The live view: ``--live [HOST:]PORT`` on ``pmactl edge run`` and ``record`` serves the
Foxglove WebSocket protocol (the ``foxglove-sdk`` package), so Foxglove opens a running rig
exactly as it opens a recording: the same topics and schemas as the MCAP export
(:mod:`edge.runtime.mcap_export`), ``/pmactl/tick`` (one JSON object per published tick, every
frame column) and ``/pmactl/events`` (arming, warnings, faults, the end).

Off the tick path: the tick copies its frame into a ring at most :data:`LIVE_HZ` times a second
(one comparison per tick otherwise, :class:`edge.runtime.telemetry.SampledRing`); a thread
turns the rows into JSON and hands them to the server every ``flush_interval_s``. A viewer that
connects, lags or leaves never touches the loop, and a failing server is not a fault.
"""

from __future__ import annotations

import json
import math
import threading
import time
from pathlib import Path

import numpy as np

from edge.errors import DataError
from edge.runtime.mcap_export import (
    EVENT_SCHEMA,
    EVENT_SCHEMA_NAME,
    EVENT_TOPIC,
    TICK_SCHEMA_NAME,
    TICK_TOPIC,
    tick_message,
    tick_schema_of,
)
from edge.runtime.telemetry import SampledRing

LIVE_HZ = 200.0  # published ticks per second (at most the loop rate)
FLUSH_S = 0.02  # how often the publishing thread drains the ring
CLOSE_GRACE_S = 0.2  # after the run, before the server stops: the last messages go out


def parse_address(text: str) -> tuple[str, int]:
    """``[HOST:]PORT`` -> (host, port); the host defaults to 127.0.0.1 (this machine only)."""
    host, sep, port_text = text.rpartition(":")
    host = host if sep else "127.0.0.1"
    try:
        port = int(port_text)
    except ValueError:
        port = -1
    if not 0 < port < 65536 or (sep and not host):
        raise DataError(f"--live {text!r}: give [HOST:]PORT, e.g. 8765 or 0.0.0.0:8765 (every interface)")
    return host, port


class LiveView(SampledRing):
    """A Foxglove WebSocket server fed from the loop's frames (see the module docstring).

    Args:
        address: ``[HOST:]PORT`` to listen on.
        dtype: the frame's row type (its columns are the tick message's keys).
        rate_hz: the loop rate [Hz] (the view publishes at most :data:`LIVE_HZ` of it).
        name: the server's name as Foxglove shows it.
    """

    _what = "live view"

    def __init__(self, address: str, dtype: np.dtype, rate_hz: float, name: str = "pmactl") -> None:
        import foxglove

        host, port = parse_address(address)
        self.host = host
        self.failure = None
        self.columns = list(dtype.names or ())
        self.context = foxglove.Context()
        try:
            self.server = foxglove.start_server(name=name, host=host, port=port, context=self.context)
        except Exception as exc:  # noqa: BLE001 - the SDK raises its own error types for a taken port
            raise DataError(f"--live {address}: cannot listen there ({exc}); choose another port") from exc
        self.port = self.server.port
        self.path = Path(self.url)  # RingWriter names its target in failures
        schema = foxglove.Schema
        tick_schema = tick_schema_of(self.columns)
        self.tick_channel = foxglove.Channel(
            TICK_TOPIC,
            schema=schema(name=TICK_SCHEMA_NAME, encoding="jsonschema", data=json.dumps(tick_schema).encode()),
            message_encoding="json",
            context=self.context,
        )
        self.event_channel = foxglove.Channel(
            EVENT_TOPIC,
            schema=schema(name=EVENT_SCHEMA_NAME, encoding="jsonschema", data=json.dumps(EVENT_SCHEMA).encode()),
            message_encoding="json",
            context=self.context,
        )
        self.published = 0
        self._every = max(1, int(round(rate_hz / LIVE_HZ)))
        self._start_ns = time.time_ns()
        self._events: list[tuple[float, str, str]] = []
        self._lock = threading.Lock()
        self._start_ring(dtype, 8192, FLUSH_S)

    def event(self, t: float, kind: str, text: str, **_: object) -> None:
        """Publish an event (from any thread) within one flush interval."""
        with self._lock:
            self._events.append((t, kind, text))

    def _stamp(self, t: float) -> int:
        return self._start_ns + int(round(t * 1e9))

    def _write_rows(self, chunk: np.ndarray) -> None:
        channel = self.tick_channel
        if not channel.has_sinks():
            return  # nobody is watching: nothing to encode
        values = [chunk[c].astype(np.float64).tolist() for c in self.columns]
        times = values[self.columns.index("t")] if "t" in self.columns else [0.0] * len(chunk)
        for i, t in enumerate(times):
            channel.log(tick_message(self.columns, [v[i] for v in values]), log_time=self._stamp(t))
        self.published += len(times)

    def _after_drain(self) -> None:
        with self._lock:
            events, self._events = self._events, []
        for t, kind, text in events:
            self.event_channel.log(
                {"t": t if math.isfinite(t) else 0.0, "kind": kind, "text": text}, log_time=self._stamp(t)
            )

    def _fail(self, exc: OSError) -> None:
        self.failure = f"live view failed ({exc})"

    def _drain(self) -> None:
        try:
            super()._drain()
        except Exception as exc:  # noqa: BLE001 - a viewer must never stop the rig
            self.failure = f"live view failed ({exc}); the run goes on without it"

    def _close_files(self) -> None:
        if self.event_channel.has_sinks():
            time.sleep(CLOSE_GRACE_S)  # the last events (the end of the run) reach the viewers
        self.server.stop()

    @property
    def url(self) -> str:
        """Where Foxglove connects (Open connection -> Foxglove WebSocket)."""
        return f"ws://{self.host}:{self.port}"
