"""Three more excitation protocols [input units, 0..peak] and a full-range conditioning start.

The four protocols of :mod:`bench.plants.protocols` are reused; these add what a different lab
would run: a random-level staircase whose ramps have random slopes, a PRBS-like pressure
pattern that switches between a few levels with holds, and damped sine bursts with rests.
Every record starts vented and makes one full 0 -> peak -> 0 cycle before the protocol.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bench.plants.grids import time_grid
from bench.plants.protocols import PROTOCOLS, Protocol

Array = NDArray[np.float64]


def staircase_ramps(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Random levels in 0.05-1 ``peak`` reached by ramps of 0.05-2 ``peak``/s, held 1-12 s."""
    t = time_grid(duration_s, dt_s)
    knots_t, knots_u = [0.0], [0.4 * peak]
    while knots_t[-1] < duration_s:
        target = float(rng.uniform(0.05, 1.0) * peak)
        slope = float(rng.uniform(0.05, 2.0) * peak)
        ramp = abs(target - knots_u[-1]) / slope
        hold = float(rng.uniform(1.0, 12.0))
        knots_t += [knots_t[-1] + ramp, knots_t[-1] + ramp + hold]
        knots_u += [target, target]
    return np.interp(t, knots_t, knots_u)


def prbs_levels(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """PRBS-like: 3 random levels, switched at multiples of a 0.4-1.2 s clock (1-8 clocks held),
    each edge through a 0.1 s valve ramp."""
    t = time_grid(duration_s, dt_s)
    levels = np.sort(rng.uniform(0.1, 1.0, 3)) * peak
    levels[0], levels[-1] = min(levels[0], 0.25 * peak), max(levels[-1], 0.85 * peak)
    clock = float(rng.uniform(0.4, 1.2))
    knots_t, knots_u = [0.0], [float(levels[1])]
    while knots_t[-1] < duration_s:
        hold = clock * int(rng.integers(1, 9))
        level = float(levels[int(rng.integers(0, 3))])
        knots_t += [knots_t[-1] + hold, knots_t[-1] + hold + 0.1]
        knots_u += [knots_u[-1], level]
    return np.interp(t, knots_t, knots_u)


def sine_bursts(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Bursts of 0.1-2 Hz sines around a random level, decaying over 3-10 s, with 2-6 s rests."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start, level = 0.0, 0.5 * peak
    while start < duration_s:
        length = float(rng.uniform(6.0, 18.0))
        rest = float(rng.uniform(2.0, 6.0))
        centre = float(rng.uniform(0.35, 0.65) * peak)
        amp = min(centre, peak - centre) * float(rng.uniform(0.6, 0.98))
        freq, decay = float(rng.uniform(0.1, 2.0)), float(rng.uniform(3.0, 10.0))
        mask = (t >= start) & (t < start + length + rest)
        tt = t[mask] - start
        entry = np.clip(tt / 0.5, 0.0, 1.0)  # half a second from the previous rest level
        burst = centre + amp * np.exp(-tt / decay) * np.sin(2 * np.pi * freq * tt) * (tt < length)
        out[mask] = level + (burst - level) * entry
        level, start = centre, start + length + rest
    return out


FRESH_PROTOCOLS: dict[str, Protocol] = {
    **PROTOCOLS,
    "staircase_ramps": staircase_ramps,
    "prbs_levels": prbs_levels,
    "sine_bursts": sine_bursts,
}


def vented_full_cycle(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """2 s vented, 0 -> peak in 5 s, peak -> 0 in 5 s, a 1 s ramp, then ``protocol`` [0..peak]."""
    cond_t = time_grid(12.0, dt_s)
    cond = peak * np.clip(np.where(cond_t < 7.0, (cond_t - 2.0) / 5.0, 1.0 - (cond_t - 7.0) / 5.0), 0.0, 1.0)
    body = np.clip(FRESH_PROTOCOLS[protocol](duration_s - 13.0, dt_s, peak, rng), 0.0, peak)
    join = np.linspace(0.0, body[0], int(round(1.0 / dt_s)), endpoint=False)
    return np.concatenate([cond, join, body])[: int(round(duration_s / dt_s))]
