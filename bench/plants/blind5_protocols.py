"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a valve sweep.

What a lab characterising muscles for wearable assist and grippers would run: an equal-step
pressure *ladder* (3-6 equal rungs up to the top and back down, each held 2-10 s, the number of
rungs and the top redrawn per ladder); minor loops riding on a major one (a slow triangle plus a
faster sine of 6-14 % of the range); a pedal-assist profile (one half-sine push per crank
revolution, the cadence wandering between 30 and 75 rpm, the push's effort redrawn per stroke,
coasting pauses vented); pick-and-place gripper cycles (fill towards an object's grip
pressure, hold while carrying, sometimes a re-grip squeeze, vent, idle); and blocks of
trapezoidal cycles with dwells at the top and the bottom, each block with its own levels and
ramp times.

Every record starts vented (0.4-0.8 s) and does a *valve sweep* in its first ~5 s
(:func:`with_valve_sweep`): the valve opens fully and the muscle fills as a first-order charge
(normalised to reach 0.98-1 ``peak`` in 1.5-2.2 s), holds 0.2-0.6 s, vents as a first-order
discharge to 0 in 1.5-2.2 s, stays vented 0.3 s and ramps in 0.4 s to where the protocol starts.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass
from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def step_ladder(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Ladders of 3-6 equal rungs from 0-0.05 ``peak`` up to 0.6-1 ``peak`` and back down the
    same rungs; each rung is reached in 0.15-0.4 s and held 2-10 s (drawn per rung)."""
    knots_t, knots_u = [0.0], [0.0]
    while knots_t[-1] < duration_s:
        rungs = int(rng.integers(3, 7))
        bottom, top = float(rng.uniform(0.0, 0.05)), float(rng.uniform(0.6, 1.0))
        levels = np.linspace(bottom, top, rungs + 1)
        for level in np.concatenate([levels[1:], levels[-2::-1]]).tolist():
            knots_t += [knots_t[-1] + float(rng.uniform(0.15, 0.4)), 0.0]
            knots_t[-1] = knots_t[-2] + float(rng.uniform(2.0, 10.0))
            knots_u += [peak * level, peak * level]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def riding_minor_loops(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A triangle of period 20-45 s between 0.02-0.08 and 0.9-1 ``peak`` plus a sine of 0.3-1.2
    Hz and 6-14 % of ``peak`` (minor loops riding on the major one), clipped into 0..peak."""
    t = time_grid(duration_s, dt_s)
    period = float(rng.uniform(20.0, 45.0))
    lo, hi = float(rng.uniform(0.02, 0.08)), float(rng.uniform(0.9, 1.0))
    tri = 1.0 - np.abs(2.0 * ((t / period + 0.5) % 1.0) - 1.0)
    ripple = float(rng.uniform(0.06, 0.14)) * np.sin(2 * np.pi * float(rng.uniform(0.3, 1.2)) * t)
    return np.asarray(peak * np.clip(lo + (hi - lo) * tri + ripple, 0.0, 1.0), dtype=np.float64)


def pedal_assist(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """One push per crank revolution: ``effort sin(pi f / duty)^1.5`` over the first 35-50 % of
    the revolution, vented for the rest; the cadence wanders (Ornstein-Uhlenbeck, 10 s, 8 rpm, around
    40-60 rpm, held in 30-75 rpm: rehabilitation cycling), the effort 0.45-1 ``peak`` is redrawn per revolution, and
    every 15-40 s the rider coasts 2-6 s (vented)."""
    t = time_grid(duration_s, dt_s)
    mean = float(rng.uniform(40.0, 60.0))
    a = float(np.exp(-dt_s / 10.0))
    kicks = rng.normal(0.0, 8.0 * np.sqrt(1.0 - a * a), t.size)
    cadence = np.empty_like(t)
    c = mean
    for i, k in enumerate(kicks.tolist()):
        c = mean + a * (c - mean) + k
        cadence[i] = min(max(c, 30.0), 75.0)
    coasting = np.zeros(t.size, dtype=bool)
    now = float(rng.uniform(15.0, 40.0))
    while now < duration_s:
        stop = now + float(rng.uniform(2.0, 6.0))
        coasting |= (t >= now) & (t < stop)
        now = stop + float(rng.uniform(15.0, 40.0))
    phase = np.cumsum(np.where(coasting, 0.0, cadence / 60.0)) * dt_s
    turn = phase.astype(np.int64)
    effort = rng.uniform(0.45, 1.0, int(turn[-1]) + 2)
    duty = float(rng.uniform(0.35, 0.5))
    f = phase - turn
    push = np.where(f < duty, np.sin(np.pi * np.clip(f / duty, 0.0, 1.0)) ** 1.5, 0.0)
    return np.asarray(np.where(coasting, 0.0, peak * effort[turn] * push), dtype=np.float64)


def gripper_cycles(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Pick and place: idle vented 0.5-2 s, grip at 0.4-1 ``peak`` (per object) held 2-8 s
    while carrying, a re-grip squeeze of +8-15 % of ``peak`` half way in a third of the cycles,
    vent; the valve fills and vents as a first-order response (0.08-0.25 s)."""
    knots_t, level = [0.0], [0.0]
    while knots_t[-1] < duration_s:
        knots_t.append(knots_t[-1] + float(rng.uniform(0.5, 2.0)))
        grip, hold = float(rng.uniform(0.4, 1.0)), float(rng.uniform(2.0, 8.0))
        level.append(grip)
        if rng.random() < 1.0 / 3.0:
            knots_t.append(knots_t[-1] + 0.5 * hold)
            level.append(min(grip + float(rng.uniform(0.08, 0.15)), 1.0))
            hold *= 0.5
        knots_t.append(knots_t[-1] + hold)
        level.append(0.0)
    t = time_grid(duration_s, dt_s)
    idx = np.searchsorted(np.asarray(knots_t), t, side="right") - 1
    return lowpass(peak * np.asarray(level)[idx], dt_s, float(rng.uniform(0.08, 0.25)))


def block_trapezoids(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks of 3-6 trapezoidal cycles; per block a bottom 0-0.3 and a top 0.6-1 ``peak``, a
    ramp time 0.5-4 s and dwells of 0.5-3 s at the top and at the bottom."""
    knots_t, knots_u = [0.0], [0.0]
    while knots_t[-1] < duration_s:
        lo, hi = float(rng.uniform(0.0, 0.3)), float(rng.uniform(0.6, 1.0))
        ramp, top, bottom = (float(rng.uniform(a, b)) for a, b in ((0.5, 4.0), (0.5, 3.0), (0.5, 3.0)))
        for _ in range(int(rng.integers(3, 7))):
            now = knots_t[-1]
            knots_t += [now + ramp, now + ramp + top, now + 2 * ramp + top, now + 2 * ramp + top + bottom]
            knots_u += [peak * hi, peak * hi, peak * lo, peak * lo]
    return knotted(duration_s, dt_s, knots_t, knots_u)


BLIND5_PROTOCOLS: dict[str, Protocol] = {
    "step_ladder": step_ladder,
    "riding_minor_loops": riding_minor_loops,
    "pedal_assist": pedal_assist,
    "gripper_cycles": gripper_cycles,
    "block_trapezoids": block_trapezoids,
}


def _charge(s: Array, span_s: float) -> Array:
    """A first-order charge from 0 to 1 over ``span_s`` (time constant a fifth of it), normalised."""
    tau = span_s / 5.0
    return np.asarray(-np.expm1(-np.clip(s, 0.0, span_s) / tau) / -np.expm1(-5.0), dtype=np.float64)


def with_valve_sweep(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.4-0.8 s vented, a first-order fill to 0.98-1 ``peak`` in 1.5-2.2 s, a 0.2-0.6 s hold, a
    first-order vent to 0 in 1.5-2.2 s, 0.3 s vented, a 0.4 s ramp to the protocol's first
    value, then ``protocol`` [0..peak] to ``duration_s``."""
    vented, fill, hold, vent = (float(rng.uniform(a, b)) for a, b in ((0.4, 0.8), (1.5, 2.2), (0.2, 0.6), (1.5, 2.2)))
    top = float(rng.uniform(0.98, 1.0)) * peak
    vent_at = vented + fill + hold
    lead_s = vent_at + vent + 0.7
    body = np.clip(BLIND5_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    t = time_grid(lead_s, dt_s)
    filled = top * _charge(t - vented, fill)
    emptied = top * (1.0 - _charge(t - vent_at, vent))
    lead = np.where(t < vent_at, filled, emptied)
    lead = np.where(t < vented, 0.0, lead)
    ramp_in = np.clip((t - (lead_s - 0.4)) / 0.4, 0.0, 1.0)
    lead = lead + ramp_in * float(body[0])
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
