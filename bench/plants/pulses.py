"""A small rate-independent muscle driven by pressure pulses, for tests of single diagnosis forms.

Three play operators and a curved spring (stroke in mm for pressure in bar), driven by pressure
steps with 15 ms edges and random holds of 0.3-1.5 s after a one-second sweep over the range.
A test adds one effect to :func:`muscle_stroke` of :func:`pulse_pressure` (or to its input reading) and asks
whether the diagnosis names it; the plant itself is as plain as a hysteresis gets.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from edge.hysteresis.pi import play_outputs
from host.data import Measurement
from host.diagnose.features import first_order

Array = NDArray[np.float64]


def pulse_pressure(rate_hz: float, seconds: float, seed: int = 3) -> tuple[float, Array]:
    """``(dt, pressure)`` [s, bar]: a sweep 0-5 bar in the first second, then steps to 0.3-5 bar
    held 0.3-1.5 s, through a 15 ms valve lag."""
    rng = np.random.default_rng(seed)
    dt = 1.0 / rate_hz
    n = int(seconds / dt)
    pressure = np.zeros(n)
    k = int(1 / dt)
    while k < n:
        hold = int(rng.uniform(0.3, 1.5) / dt)
        pressure[k : k + hold] = rng.uniform(0.3, 5.0)
        k += hold
    pressure = first_order(pressure, dt, 0.015)
    pressure[: int(1 / dt)] = np.linspace(0.0, 5.0, int(1 / dt))
    return dt, pressure


def muscle_stroke(pressure: Array) -> Array:
    """The rate-independent stroke [mm]: three plays (0.1, 0.35, 0.8 bar) and ``2 p^1.3``."""
    plays = play_outputs(pressure, np.array([0.1, 0.35, 0.8]), np.full(3, pressure[0]))
    return np.asarray(6.0 * plays.sum(axis=1) + 2.0 * pressure**1.3, dtype=np.float64)


def pulse_record(dt: float, pressure: Array, stroke: Array, name: str, seed: int = 11) -> Measurement:
    """The recording of ``stroke`` [mm] driven by ``pressure`` [bar]: the pressure read with 2 mbar
    and the stroke with 10 um of white noise (seeded by ``seed``)."""
    rng = np.random.default_rng(seed)
    n = stroke.size
    u = pressure + rng.normal(0.0, 0.002, n)
    return Measurement(np.arange(n) * dt, u, stroke + rng.normal(0.0, 0.01, n), {}, source=name)
