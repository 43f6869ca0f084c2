"""Real-time mode: the emulated rig on the wall clock, serving the serial DAQ on a pty.

Run as ``pmactl hil serve [--config RIG.toml]``; prints ``pty: /dev/pts/N`` (flushed) and serves until SIGTERM or
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


def serve(
    effect: str = "none",
    seed: int = 0,
    rate_hz: float = 1000.0,
    duration_s: float | None = None,
    config_path: str | None = None,
) -> int:
    """``config_path``: wire the sensors and the valve as that rig config's serial DAQ channels
    say (the calibration the edge will use), instead of the default wiring."""
    wiring = None
    if config_path is not None:
        from edge.runtime.config import load_config
        from hil.plugin import wiring_from_config

        config = load_config(config_path)
        wiring = wiring_from_config(config, {d.name for d in config.rig.devices if d.driver == "serial-daq"})
    params, _ = apply_effect(effect, PlantParams(), np.random.default_rng(seed), duration_s or 3600.0)
    clock = MonotonicClock()
    rig = HilRig(params, clock=clock, seed=seed, wiring=wiring)
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
