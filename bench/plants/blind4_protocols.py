"""Five excitation protocols [bar, 0..peak] unlike the other families', each after an S-curve sweep.

What a soft-robotics lab building assistive and medical devices would run: a sum of two chirps
sweeping in opposite directions (one up, one down in frequency) around mid pressure; a
respiratory-assist profile (inspiration rising exponentially, a plateau, passive expiration,
breath to breath changes of tidal pressure and rate, a sigh now and then); degaussing cycles
(triangles around a centre whose amplitude decays geometrically from full range, the classic
way to bring a hysteretic system to a known state, repeated about new centres); set points whose
jumps are heavy-tailed (a Levy flight) reached through the regulator's first-order response;
and a slow sine played through a coarse 4-bit DAC (16 pressure levels, a staircase).

Every record starts vented (0.5-0.9 s) and does an *S-curve sweep* in its first ~5 s: a
smoothstep fill to 0.98-1 ``peak`` in 1.4-1.9 s, a 0.2-0.5 s hold, a smoothstep vent to 0 in
1.4-1.9 s, 0.3 s vented and a 0.4 s ramp to where the protocol starts (:func:`with_s_sweep`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass
from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def dual_chirp(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Two linear chirps in 0.02-1.2 Hz, one sweeping up and one down over a 30-50 s sweep
    (then repeating), each +-0.18-0.25 ``peak`` around 0.5 ``peak`` (their beats reach the ends)."""
    t = time_grid(duration_s, dt_s)
    sweep = float(rng.uniform(30.0, 50.0))
    f_lo, f_hi = float(rng.uniform(0.02, 0.05)), float(rng.uniform(0.6, 1.2))
    s = t % sweep
    k = (f_hi - f_lo) / sweep
    up = np.sin(2 * np.pi * (f_lo * s + 0.5 * k * s * s) + rng.uniform(0, 2 * np.pi))
    down = np.sin(2 * np.pi * (f_hi * s - 0.5 * k * s * s) + rng.uniform(0, 2 * np.pi))
    a, b = float(rng.uniform(0.18, 0.25)), float(rng.uniform(0.18, 0.25))
    return np.asarray(peak * (0.5 + a * up + b * down), dtype=np.float64)


def breathing_assist(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Breaths of 2.5-5 s (drawn per breath): inspiration for 30-40 % of the breath rising as
    ``1 - exp(-t / tau)`` (tau 0.2-0.5 s) to a tidal pressure 0.5-0.9 ``peak``, a 0.2-0.5 s
    plateau, passive expiration ``exp(-t / tau_e)`` (0.3-0.8 s) to a PEEP of 0.03-0.1 ``peak``;
    every 6-10 breaths a sigh to 0.95-1 ``peak``."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    now, n, sigh_every, peep = 0.0, 0, int(rng.integers(6, 11)), float(rng.uniform(0.03, 0.1))
    while now < duration_s:
        breath = float(rng.uniform(2.5, 5.0))
        n += 1
        tidal = float(rng.uniform(0.95, 1.0) if n % sigh_every == 0 else rng.uniform(0.5, 0.9))
        insp, plateau = breath * float(rng.uniform(0.3, 0.4)), float(rng.uniform(0.2, 0.5))
        tau_i, tau_e = float(rng.uniform(0.2, 0.5)), float(rng.uniform(0.3, 0.8))
        mask = (t >= now) & (t < now + breath)
        s = t[mask] - now
        rise = peep + (tidal - peep) * -np.expm1(-s / tau_i) / -np.expm1(-insp / tau_i)
        top = peep + (tidal - peep) * np.ones_like(s)
        fall = peep + (tidal - peep) * np.exp(-np.clip(s - insp - plateau, 0.0, None) / tau_e)
        out[mask] = peak * np.where(s < insp, rise, np.where(s < insp + plateau, top, fall))
        now += breath
    return out


def degauss_cycles(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks of 6-10 triangle cycles (period 2-6 s) about a centre 0.35-0.65 ``peak``, the
    first reaching both ends of the range and each next one 0.6-0.8 x as wide; a new block
    starts from full range about a new centre."""
    knots_t, knots_u = [0.0], [0.5 * peak]
    while knots_t[-1] < duration_s:
        centre, ratio = float(rng.uniform(0.35, 0.65)), float(rng.uniform(0.6, 0.8))
        amp, period = min(centre, 1.0 - centre), float(rng.uniform(2.0, 6.0))
        for _ in range(int(rng.integers(6, 11))):
            knots_t += [knots_t[-1] + period / 4, knots_t[-1] + 3 * period / 4, knots_t[-1] + period]
            knots_u += [peak * (centre + amp), peak * (centre - amp), peak * centre]
            amp *= ratio
    return knotted(duration_s, dt_s, knots_t, knots_u)


def levy_setpoints(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Set points that jump by Cauchy-distributed steps (scale 0.15 ``peak``, reflected into
    0.02-1 ``peak``: many small jumps, a few across the range) after exponential holds (mean
    2.5 s, 0.4-10 s), reached through a first-order regulator response (tau 0.15-0.5 s)."""
    knots_t, level = [0.0], [float(rng.uniform(0.1, 0.9))]
    while knots_t[-1] < duration_s:
        x = level[-1] + 0.15 * float(rng.standard_cauchy())
        y = (x - 0.02) % 1.96  # reflect into [0.02, 1]
        x = 0.02 + (1.96 - y if y > 0.98 else y)
        knots_t.append(knots_t[-1] + float(np.clip(rng.exponential(2.5), 0.4, 10.0)))
        level.append(x)
    t = time_grid(duration_s, dt_s)
    idx = np.searchsorted(np.asarray(knots_t), t, side="right") - 1
    return lowpass(peak * np.asarray(level)[idx], dt_s, float(rng.uniform(0.15, 0.5)))


def coarse_dac_sine(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A sine of 0.03-0.12 Hz (frequency drawn per cycle), 0.02-1 ``peak``, played through a
    4-bit DAC: 16 levels, so the pressure is a staircase with steps of 1/15 of the range."""
    t = time_grid(duration_s, dt_s)
    knots, phase, now = [0.0], [0.0], 0.0
    while now < duration_s:
        now += 1.0 / float(rng.uniform(0.03, 0.12))
        knots.append(now)
        phase.append(phase[-1] + 1.0)
    s = np.sin(2 * np.pi * np.interp(t, knots, phase) + rng.uniform(0, 2 * np.pi))
    level = np.round((0.5 + 0.5 * s) * 15.0) / 15.0
    return np.asarray(peak * (0.02 + 0.98 * level), dtype=np.float64)


BLIND4_PROTOCOLS: dict[str, Protocol] = {
    "dual_chirp": dual_chirp,
    "breathing_assist": breathing_assist,
    "degauss_cycles": degauss_cycles,
    "levy_setpoints": levy_setpoints,
    "coarse_dac_sine": coarse_dac_sine,
}


def _smoothstep(s: Array) -> Array:
    s = np.clip(s, 0.0, 1.0)
    return np.asarray(s * s * (3.0 - 2.0 * s), dtype=np.float64)


def with_s_sweep(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.5-0.9 s vented, a smoothstep fill to 0.98-1 ``peak`` in 1.4-1.9 s, a 0.2-0.5 s hold, a
    smoothstep vent to 0 in 1.4-1.9 s, 0.3 s vented, a 0.4 s ramp to the protocol's first value,
    then ``protocol`` [0..peak] to ``duration_s``."""
    vented, rise, hold, fall = (
        float(rng.uniform(lo, hi)) for lo, hi in ((0.5, 0.9), (1.4, 1.9), (0.2, 0.5), (1.4, 1.9))
    )
    top = float(rng.uniform(0.98, 1.0)) * peak
    down_at = vented + rise + hold
    lead_s = down_at + fall + 0.7
    body = np.clip(BLIND4_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    t = time_grid(lead_s, dt_s)
    lead = top * (_smoothstep((t - vented) / rise) - _smoothstep((t - down_at) / fall))
    ramp_in = np.clip((t - (lead_s - 0.4)) / 0.4, 0.0, 1.0)
    lead = lead + ramp_in * float(body[0])
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
