"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a shakedown.

What labs qualifying actuators for structures, vibration rigs and simple benches run: an
*ATC-24 incremental* cyclic test (the seismic testing protocol: triangles from a low base to
amplitude levels that grow step by step, three cycles per level while small, two once large, at
one ramp speed per run); *sine-on-random* (the vibration-test standard: a band-limited random
pressure about mid range with a sine of 2-6 Hz on top); a *hand pump with a bleed valve*
(strokes of a hand pump raising the pressure in increments, a hold, a bleed through a needle
valve decaying exponentially, pumping again from where it stopped); *leak-down tests* (a fill
to a level, the valve closed and the pressure decaying through a calibrated leak for 8-20 s,
then vented and rested, as leak testing of muscles does); and a *cycloidal cam* (a cam-driven
regulator: cycloidal rise, dwell, cycloidal return, dwell, the cam's speed and lift changed per
block).

Every record starts vented (0.5-1 s) and is *shaken down* in its first ~7 s
(:func:`with_shakedown`): four trapezoids 0 -> 0.97-1 ``peak`` -> 0 (linear ramps of 0.4-0.6
s, 0.3 s at the top, 0.2 s vented), 0.3 s vented and a 0.5 s linear ramp to the protocol's
first value.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass
from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def _knots(duration_s: float, dt_s: float, peak: float, knots_t: list[float], knots_u: list[float]) -> Array:
    return np.asarray(peak * np.clip(knotted(duration_s, dt_s, knots_t, knots_u), 0.0, 1.0), dtype=np.float64)


def atc24_incremental(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Runs of triangles from a base of 0.02-0.08 ``peak`` to levels growing by 0.1-0.18
    ``peak`` from 0.12-0.25 above the base up to the top; three cycles per level up to 0.6
    ``peak``, two above; ramps at 0.25-0.7 ``peak``/s (one speed per run)."""
    knots_t, knots_u = [0.0], [0.05]
    while knots_t[-1] < duration_s:
        base, speed = float(rng.uniform(0.02, 0.08)), float(rng.uniform(0.25, 0.7))
        level, grow = base + float(rng.uniform(0.12, 0.25)), float(rng.uniform(0.1, 0.18))
        knots_t.append(knots_t[-1] + abs(knots_u[-1] - base) / speed + 0.01)
        knots_u.append(base)
        while level <= 1.0:
            for _ in range(3 if level <= 0.6 else 2):
                for target in (level, base):
                    knots_t.append(knots_t[-1] + abs(target - knots_u[-1]) / speed)
                    knots_u.append(target)
            level += grow
    return _knots(duration_s, dt_s, peak, knots_t, knots_u)


def sine_on_random(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """``0.5 + r(t) + a sin(2 pi f t)`` ``peak``: ``r`` white noise through two lags (0.3-1 s)
    scaled to 0.12-0.2 RMS, a sine of 2-6 Hz and 0.03-0.07 ``peak``; clipped to 0.02..1."""
    t = time_grid(duration_s, dt_s)
    tau = float(rng.uniform(0.3, 1.0))
    noise = lowpass(lowpass(rng.normal(0.0, 1.0, t.size), dt_s, tau), dt_s, tau)
    noise = noise - float(np.mean(noise))
    noise *= float(rng.uniform(0.12, 0.2)) / max(float(np.std(noise)), 1e-12)
    f, amp = float(rng.uniform(2.0, 6.0)), float(rng.uniform(0.03, 0.07))
    out = 0.5 + noise + amp * np.sin(2.0 * np.pi * f * t + float(rng.uniform(0.0, 6.3)))
    return np.asarray(peak * np.clip(out, 0.02, 1.0), dtype=np.float64)


def hand_pump_bleed(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Pump strokes every 0.8-1.6 s, each adding 0.06-0.12 ``peak`` in its first 0.3 s, up to a
    top of 0.7-1 ``peak``; held 2-5 s; bled through a needle valve (``exp(-t / tau)``, tau 3-8
    s) for 4-12 s; pumping resumes from where the bleed stopped."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    now, level, i = 0.0, 0.03, 0
    while i < t.size:
        top = float(rng.uniform(0.7, 1.0))
        while level < top and i < t.size:  # pump strokes
            period, add = float(rng.uniform(0.8, 1.6)), float(rng.uniform(0.06, 0.12))
            gain = min(add, 1.0 - level)
            while i < t.size and t[i] < now + period:
                s = min((t[i] - now) / 0.3, 1.0)
                out[i] = level + gain * 0.5 * (1.0 - np.cos(np.pi * s))
                i += 1
            now, level = now + period, level + gain
        hold = float(rng.uniform(2.0, 5.0))
        while i < t.size and t[i] < now + hold:
            out[i] = level
            i += 1
        now += hold
        tau, bleed = float(rng.uniform(3.0, 8.0)), float(rng.uniform(4.0, 12.0))
        while i < t.size and t[i] < now + bleed:
            out[i] = level * np.exp(-(t[i] - now) / tau)
            i += 1
        now, level = now + bleed, level * float(np.exp(-bleed / tau))
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def leak_down_tests(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Tests: a fill in 0.4-1 s to 0.45-1 ``peak``, the valve closed and the pressure decaying
    through the leak (``exp(-t / tau)``, tau 6-20 s) for 8-20 s, a vent in 0.3 s to 0-0.08
    ``peak``, a rest of 2-4 s."""
    knots_t, knots_u = [0.0], [0.02]
    while knots_t[-1] < duration_s:
        level, tau, test = float(rng.uniform(0.45, 1.0)), float(rng.uniform(6.0, 20.0)), float(rng.uniform(8.0, 20.0))
        knots_t.append(knots_t[-1] + float(rng.uniform(0.4, 1.0)))
        knots_u.append(level)
        start = knots_t[-1]
        for s in np.linspace(0.0, test, 25)[1:].tolist():
            knots_t.append(start + s)
            knots_u.append(level * float(np.exp(-s / tau)))
        rest = float(rng.uniform(0.0, 0.08))
        knots_t += [knots_t[-1] + 0.3, 0.0]
        knots_t[-1] = knots_t[-2] + float(rng.uniform(2.0, 4.0))
        knots_u += [rest, rest]
    return _knots(duration_s, dt_s, peak, knots_t, knots_u)


def cycloidal_cam(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks of 3-6 cam cycles: a cycloidal rise ``s - sin(2 pi s) / (2 pi)`` from 0.05-0.25 to
    0.7-1 ``peak`` in 0.5-3 s, a dwell of 0.5-3 s, the same return, a dwell; the rise time,
    the dwells and the lift redrawn per block."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start = 0.0
    while start < duration_s:
        low, high = float(rng.uniform(0.05, 0.25)), float(rng.uniform(0.7, 1.0))
        rise, dwell_top, dwell_low = (float(rng.uniform(a, b)) for a, b in ((0.5, 3.0), (0.5, 3.0), (0.5, 3.0)))
        cycle = 2.0 * rise + dwell_top + dwell_low
        n = int(rng.integers(3, 7))
        inside = (t >= start) & (t < start + n * cycle)
        phase = (t[inside] - start) % cycle
        up = np.clip(phase / rise, 0.0, 1.0)
        down = np.clip((phase - rise - dwell_top) / rise, 0.0, 1.0)
        lift = (up - np.sin(2.0 * np.pi * up) / (2.0 * np.pi)) - (down - np.sin(2.0 * np.pi * down) / (2.0 * np.pi))
        out[inside] = low + (high - low) * lift
        start += n * cycle
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


BLIND8_PROTOCOLS: dict[str, Protocol] = {
    "atc24_incremental": atc24_incremental,
    "sine_on_random": sine_on_random,
    "hand_pump_bleed": hand_pump_bleed,
    "leak_down_tests": leak_down_tests,
    "cycloidal_cam": cycloidal_cam,
}


def with_shakedown(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.5-1 s vented, four trapezoids to 0.97-1 ``peak`` (ramps of 0.4-0.6 s, 0.3 s at the
    top, 0.2 s vented), 0.3 s vented, a 0.5 s linear ramp to the protocol's first value, then
    ``protocol`` [0..peak] to ``duration_s``."""
    top = float(rng.uniform(0.97, 1.0))
    knots_t, knots_u = [0.0, float(rng.uniform(0.5, 1.0))], [0.0, 0.0]
    for _ in range(4):
        ramp = float(rng.uniform(0.4, 0.6))
        for dt_knot, level in ((ramp, top), (0.3, top), (ramp, 0.0), (0.2, 0.0)):
            knots_t.append(knots_t[-1] + dt_knot)
            knots_u.append(level)
    knots_t.append(knots_t[-1] + 0.3)
    knots_u.append(0.0)
    lead_s = knots_t[-1] + 0.5
    body = np.clip(BLIND8_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    knots_t.append(lead_s)
    knots_u.append(float(body[0]) / peak)
    lead = _knots(lead_s, dt_s, peak, knots_t, knots_u)
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
