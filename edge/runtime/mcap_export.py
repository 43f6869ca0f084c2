"""Telemetry to MCAP (``pmactl edge telemetry run.pmt --mcap run.mcap``), for Foxglove and
PlotJuggler: topic ``/pmactl/tick`` carries one JSON message per tick (every column, log time
= run start + t), ``/pmactl/events`` the event log, and the header goes in as metadata."""

from __future__ import annotations

import calendar
import json
import math
import time
from pathlib import Path

from edge.errors import DataError
from edge.runtime.telemetry_read import Telemetry

TICK_TOPIC, TICK_SCHEMA_NAME = "/pmactl/tick", "pmactl.Tick"
EVENT_TOPIC, EVENT_SCHEMA_NAME = "/pmactl/events", "pmactl.Event"
EVENT_SCHEMA = {
    "type": "object",
    "properties": {"t": {"type": "number"}, "kind": {"type": "string"}, "text": {"type": "string"}},
}


def tick_schema_of(columns: list[str] | tuple[str, ...]) -> dict[str, object]:
    """The JSON schema of one tick message: every column a number (null for NaN)."""
    return {"type": "object", "properties": {c: {"type": ["number", "null"]} for c in columns}}


def tick_message(columns: list[str] | tuple[str, ...], values: list[float]) -> dict[str, float | None]:
    """One tick as the JSON object both the MCAP export and the live view send."""
    return {c: _number(float(v)) for c, v in zip(columns, values)}


def _start_ns(header: dict[str, object]) -> int:
    started = header.get("started_utc")
    if isinstance(started, str):
        try:
            return calendar.timegm(time.strptime(started, "%Y-%m-%dT%H:%M:%SZ")) * 1_000_000_000
        except ValueError:
            pass
    return 0


def _number(value: float) -> float | None:
    return value if math.isfinite(value) else None  # JSON has no NaN


def export_mcap(record: Telemetry, path: Path) -> int:
    """Write ``record`` to ``path``; returns the number of messages."""
    from mcap.writer import Writer

    columns = record.columns
    start = _start_ns(record.header)
    tick_schema, event_schema = tick_schema_of(columns), EVENT_SCHEMA
    try:
        stream = path.open("wb")
    except OSError as exc:
        raise DataError(f"{path}: cannot write the MCAP file ({exc.strerror})") from exc
    count = 0
    with stream:
        writer = Writer(stream)
        writer.start(profile="", library="pmactl")
        tick_id = writer.register_channel(
            topic=TICK_TOPIC,
            message_encoding="json",
            schema_id=writer.register_schema(TICK_SCHEMA_NAME, "jsonschema", json.dumps(tick_schema).encode()),
        )
        event_id = writer.register_channel(
            topic=EVENT_TOPIC,
            message_encoding="json",
            schema_id=writer.register_schema(EVENT_SCHEMA_NAME, "jsonschema", json.dumps(event_schema).encode()),
        )
        values = {c: record.rows[c].tolist() for c in columns}
        times = values.get("t", [i * 0.001 for i in range(len(record.rows))])
        for i, t in enumerate(times):
            stamp = start + int(round(float(t) * 1e9))
            message = tick_message(columns, [values[c][i] for c in columns])
            writer.add_message(
                tick_id, log_time=stamp, data=json.dumps(message).encode(), publish_time=stamp, sequence=i
            )
            count += 1
        for i, event in enumerate(record.events):
            stamp = start + int(round(float(event.get("t", 0.0)) * 1e9))  # type: ignore[arg-type]
            data = {k: event[k] for k in ("t", "kind", "text") if k in event}
            writer.add_message(event_id, log_time=stamp, data=json.dumps(data).encode(), publish_time=stamp, sequence=i)
            count += 1
        header = {k: v if isinstance(v, str) else json.dumps(v) for k, v in record.header.items() if k != "dtype"}
        writer.add_metadata("pmactl.header", header)
        writer.finish()
    return count
