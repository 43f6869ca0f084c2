"""``--live``: a real WebSocket client (the ``websockets`` package) sees the Foxglove server of
a running ``pmactl edge run`` / ``record``: the MCAP export's topics and schemas, at least 100
tick messages a second, and the run's end event."""

from __future__ import annotations

import asyncio
import json
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest
import websockets

from edge.runtime.mcap_export import EVENT_SCHEMA_NAME, EVENT_TOPIC, TICK_SCHEMA_NAME, TICK_TOPIC
from tests.edge_helpers import HIL_RIG, fit_bundle

PMACTL = [sys.executable, "-m", "host.cli"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def realtime_rig(tmp_path: Path) -> Path:
    """The emulated rig on the wall clock at 200 Hz; overruns of a loaded test machine tolerated
    (this test is about the viewer, not the schedule)."""
    text = HIL_RIG.read_text().replace("sim://rig?clock=lockstep", "sim://rig?clock=realtime")
    text = text.replace("rate_hz = 1000", "rate_hz = 200").replace("overrun_streak = 5", "overrun_streak = 1000")
    path = tmp_path / "rig.toml"
    path.write_text(text)
    return path


async def watch(port: int, seconds: float) -> dict:
    """Connect (retrying while the server starts), subscribe to every channel, count."""
    for _ in range(200):
        try:
            ws = await websockets.connect(f"ws://127.0.0.1:{port}", subprotocols=["foxglove.sdk.v1"])
            break
        except OSError:
            await asyncio.sleep(0.05)
    else:
        raise AssertionError("no server")
    channels: dict[int, dict] = {}
    subscriptions: dict[int, str] = {}
    seen: dict[str, list[tuple[float, bytes]]] = {TICK_TOPIC: [], EVENT_TOPIC: []}
    end = time.monotonic() + seconds
    async with ws:
        while time.monotonic() < end:
            try:
                message = await asyncio.wait_for(ws.recv(), timeout=0.5)
            except TimeoutError:
                continue
            except websockets.ConnectionClosed:
                break
            if isinstance(message, str):
                op = json.loads(message)
                if op["op"] == "advertise":
                    for channel in op["channels"]:
                        channels[channel["id"]] = channel
                        subscriptions[len(subscriptions) + 1] = channel["topic"]
                        request = {"id": len(subscriptions), "channelId": channel["id"]}
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": [request]}))
            elif message[0] == 1:  # message data: subscription id, log time, payload
                subscription, _ = struct.unpack_from("<IQ", message, 1)
                seen[subscriptions[subscription]].append((time.monotonic(), message[13:]))
    return {"channels": list(channels.values()), "seen": seen}


@pytest.mark.parametrize("command", ["run", "record"])
def test_a_websocket_client_sees_the_live_run(tmp_path: Path, command: str) -> None:
    port = free_port()
    config = realtime_rig(tmp_path)
    if command == "run":
        args = ["edge", "run", "--config", str(config), "--bundle", str(fit_bundle(tmp_path / "b")), "--duration", "5"]
    else:
        args = ["edge", "record", "--config", str(config), "--protocol", "steps:levels=1,hold=2.5"]
        args += ["--out", str(tmp_path / "r.csv")]
    process = subprocess.Popen([*PMACTL, *args, "--live", str(port)], stderr=subprocess.PIPE, text=True)
    try:
        result = asyncio.run(watch(port, 15.0))
    finally:
        _, err = process.communicate(timeout=60)
    assert process.returncode == 0, err
    assert f"live view: ws://127.0.0.1:{port}" in err
    advertised = {(c["topic"], c["schemaName"], c["encoding"]) for c in result["channels"]}
    assert advertised == {(TICK_TOPIC, TICK_SCHEMA_NAME, "json"), (EVENT_TOPIC, EVENT_SCHEMA_NAME, "json")}
    ticks = result["seen"][TICK_TOPIC]
    assert len(ticks) > 200
    rate = (len(ticks) - 1) / (ticks[-1][0] - ticks[0][0])
    assert rate >= 100, rate
    first = json.loads(ticks[0][1])
    assert {"t", "u_bar", "contraction_mm", "pressure_bar", "state", "fault"} <= set(first)
    events = [json.loads(payload)["kind"] for _, payload in result["seen"][EVENT_TOPIC]]
    assert events[-1:] == ["end"], events


def test_the_shipped_layout_is_the_generated_one_and_names_real_columns() -> None:
    import re

    from edge.runtime.frame import frame_layout
    from edge.runtime.live_layout import layout_json
    from tests.edge_helpers import rig_config

    shipped = (HIL_RIG.parent / "foxglove-layout.json").read_text().strip()
    assert shipped == layout_json()
    columns = set(frame_layout(rig_config().rig).names)
    fields = set(re.findall(re.escape(TICK_TOPIC) + r"\.(\w+)", shipped))
    assert fields and fields <= columns, fields - columns
    assert EVENT_TOPIC in shipped
