"""Real-time mode: the emulated rig on the wall clock, serving the serial DAQ on a pty.

Run as ``pmactl hil serve``; prints ``pty: /dev/pts/N`` (flushed) and serves until SIGTERM or
SIGINT, then prints what it sent and exits 0.
"""

from __future__ import annotations

import signal
import time

import numpy as np

from edge.hal.clock import MonotonicClock
from hil.daq_server import DaqServer, open_pty
from hil.effects import apply_effect
from hil.plant import PlantParams
from hil.rig import HilRig


def serve(effect: str = "none", seed: int = 0, rate_hz: float = 1000.0, duration_s: float | None = None) -> int:
    params, _ = apply_effect(effect, PlantParams(), np.random.default_rng(seed), duration_s or 3600.0)
    clock = MonotonicClock()
    rig = HilRig(params, clock=clock, seed=seed)
    master, path = open_pty()
    server = DaqServer(rig, master, rate_hz)
    stop = False

    def request_stop(*_: object) -> None:
        nonlocal stop
        stop = True

    signal.signal(signal.SIGTERM, request_stop)
    signal.signal(signal.SIGINT, request_stop)
    print(f"pty: {path}", flush=True)
    start = clock.now()
    period = 1.0 / rate_hz
    next_tick = start
    while not stop and (duration_s is None or clock.now() - start < duration_s):
        server.service()
        next_tick += period
        remaining = next_tick - clock.now()
        if remaining > 0:
            time.sleep(remaining)
        else:
            next_tick = clock.now()  # fell behind: do not try to catch up in a burst
    print(f"served {server.sent} frames, {server.commands} commands, {server.overruns} overruns", flush=True)
    return 0
