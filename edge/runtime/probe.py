"""``pmactl edge probe``: read every input channel of the rig with the valve disabled, for
checking the wiring, and the two-point calibration of one channel.

The rig is opened as for a run and vented at once; nothing is ever written to the valve. Each
tick (at ``rate_hz``, on the rig's clock and the same scheduler as the loop) reads every device
and starts the next conversions; per channel the probe keeps the latest raw value (volts for
an analog input, recovered from the config's calibration: ``volts = value / scale + zero``;
0/1 for a line), the scaled value, its min and max, and the device's read errors. A display
callback runs every ``refresh_s``. On an emulated lockstep rig the probe keeps pace with the
wall clock, so values move at the speed a person watches them.

Calibration (:func:`two_point`): the channel at two known values ``v1``, ``v2`` reads mean
volts ``V1``, ``V2``; then ``scale = (v2 - v1) / (V2 - V1)`` and ``zero = V1 - v1 / scale``,
the config's ``value = (volts - zero) * scale``.
"""

from __future__ import annotations

import errno
import gc
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from edge.errors import DataError
from edge.runtime.config import RigConfig, fastest_period_s
from edge.runtime.frame import frame_layout
from edge.runtime.rig import open_rig
from edge.runtime.rigspec import ANALOG_IN, LINE_IN, ChannelSpec
from edge.runtime.scheduler import TickScheduler

SPIN_S = 300e-6
MIN_SPAN_SIGMAS = 20.0  # the two calibration points must differ by this many noise sigmas
MIN_RATE_HZ = 1.0  # slowest --rate: a read (and a look at the stop request) at least once a second


@dataclass
class ChannelStats:
    """What the probe has seen on one input channel since it started (or since :meth:`reset`)."""

    channel: ChannelSpec
    value: float = math.nan
    raw: float = math.nan
    minimum: float = math.inf
    maximum: float = -math.inf
    errors: int = 0
    last_error: str = ""
    samples: list[float] = field(default_factory=list)  # raw values while averaging for a calibration

    def raw_of(self, value: float) -> float:
        c = self.channel
        return value / c.scale + c.zero if c.kind == ANALOG_IN else value

    def reset(self) -> None:
        self.minimum, self.maximum, self.errors = math.inf, -math.inf, 0


class Probe:
    """The rig of ``config`` opened for reading only (see the module docstring).

    Args:
        config: the validated rig config.
        rate_hz: reads per second (default: the config's loop rate); at most what the wires allow.
    """

    def __init__(self, config: RigConfig, rate_hz: float | None = None) -> None:
        rate = config.loop.rate_hz if rate_hz is None else rate_hz
        fastest = fastest_period_s(config)
        if not (math.isfinite(rate) and MIN_RATE_HZ <= rate <= 1.0 / fastest + 1e-9):
            raise DataError(
                f"--rate {rate:g} must be at least {MIN_RATE_HZ:g} Hz (slower would not see Ctrl-C or the wires move) "
                f"and at most {1.0 / fastest:.0f} Hz (what this rig's wires allow)"
            )
        self.config, self.rate_hz, self.period_s = config, rate, 1.0 / rate
        self.layout = frame_layout(config.rig)
        self.frame = self.layout.new()
        self.rig = open_rig(config, self.layout)
        self.rig.vent()
        spec = config.rig
        self.channels = [ChannelStats(c) for c in spec.channels if c.kind in (ANALOG_IN, LINE_IN)]
        status = {dev: rd for dev, rd, _ in self.layout.status_fields}
        self._reads = [(s, s.channel.field, status[s.channel.device]) for s in self.channels]
        self.scheduler = TickScheduler(self.rig.clock, self.period_s, 0.0 if self.rig.lockstep else SPIN_S)
        self.averaging: ChannelStats | None = None
        self.t = 0.0

    def channel(self, name: str) -> ChannelStats:
        for stats in self.channels:
            if stats.channel.name == name:
                if stats.channel.kind != ANALOG_IN:
                    raise DataError(f"--calibrate {name}: a line (0/1) has no scale to calibrate; pick an analog input")
                return stats
        names = ", ".join(s.channel.name for s in self.channels if s.channel.kind == ANALOG_IN)
        raise DataError(f"--calibrate {name}: no such input channel in {self.config.source}; have {names}")

    def run(
        self,
        duration_s: float | None,
        on_refresh: Callable[[Probe], bool],
        refresh_s: float = 0.2,
        stop: Callable[[], bool] = lambda: False,
        pace: bool = True,
    ) -> None:
        """Read until ``duration_s`` [s] (None: until ``stop()`` or ``on_refresh`` returns False)."""
        rig, frame = self.rig, self.frame
        wall0 = time.monotonic()
        rig.read(frame)
        rig.prepare(frame)
        gc.collect()
        gc.freeze()  # as the loop does: no collector pauses between ticks
        try:
            self._loop(duration_s, on_refresh, refresh_s, stop, pace, wall0)
        finally:
            gc.unfreeze()

    def _loop(
        self,
        duration_s: float | None,
        on_refresh: Callable[[Probe], bool],
        refresh_s: float,
        stop: Callable[[], bool],
        pace: bool,
        wall0: float,
    ) -> None:
        rig, frame, reads, scheduler = self.rig, self.frame, self._reads, self.scheduler
        next_refresh = 0.0
        scheduler.start()
        while not stop():
            t, _ = scheduler.wait()
            if duration_s is not None and t >= duration_s - 1e-9:
                break
            self.t = t
            rig.read(frame)
            for stats, name, status in reads:
                code = getattr(frame, status)
                if code:
                    stats.errors += 1
                    stats.last_error = errno.errorcode.get(code, str(code))
                    continue
                value = getattr(frame, name)
                stats.value = value
                stats.raw = raw = stats.raw_of(value)
                if value < stats.minimum:
                    stats.minimum = value
                if value > stats.maximum:
                    stats.maximum = value
                if stats is self.averaging:
                    stats.samples.append(raw)
            rig.prepare(frame)
            if t >= next_refresh:
                next_refresh = t + refresh_s
                if pace and rig.lockstep:  # an emulated rig moves at a watcher's speed
                    time.sleep(max(0.0, t - (time.monotonic() - wall0)))
                if not on_refresh(self):
                    break

    def close(self) -> None:
        """Vent (again) and release the rig."""
        self.rig.close()


def two_point(value_1: float, volts_1: float, value_2: float, volts_2: float) -> tuple[float, float]:
    """``(scale, zero)`` through the two points (see the module docstring)."""
    scale = (value_2 - value_1) / (volts_2 - volts_1)
    return scale, volts_1 - value_1 / scale


def check_points(name: str, unit: str, points: list[tuple[float, float, float]]) -> None:
    """One line if two calibration points ``(value, mean volts, volts sd)`` cannot define a line."""
    (v1, m1, s1), (v2, m2, s2) = points
    if v1 == v2:
        raise DataError(f"--calibrate {name}: both points were given as {v1:g} {unit}; use two different known values")
    noise = max(s1, s2, 1e-6)
    if abs(m2 - m1) < MIN_SPAN_SIGMAS * noise:
        raise DataError(
            f"--calibrate {name}: the two points read {m1:.5f} V and {m2:.5f} V, within the noise ({noise:.5f} V); "
            "move the sensor further apart between the points (is it wired to this input?)"
        )
