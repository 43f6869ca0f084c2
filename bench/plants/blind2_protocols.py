"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a range check.

What a rehabilitation / exoskeleton lab would run: gait-cycle pressure profiles in walking bouts
with standing pauses, an amplitude-modulated sine, sawtooth trains of random amplitude and
direction, a controller tracking a slowly changing setpoint (with its overshoot), and the
chamber pressure of an on/off valve driven by slow-varying PWM (ripple on a wandering mean).

Every record starts vented (1 s) and then does a *range check* (a half-cosine up to the top,
a short hold, a half-cosine down to where the protocol starts) within its first ~4 s, so the
hysteresis memory is known early (:func:`with_range_check`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator
from scipy.signal import lfilter

from bench.plants.filters import resonance
from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]
VENTED_S = 1.0
RISE_S, HOLD_S, FALL_S = 1.2, 0.5, 1.2
LEAD_IN_S = VENTED_S + RISE_S + HOLD_S + FALL_S


def gait_cycle(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Walking bouts of 8-25 strides (stride 1.2-2.4 s, drawn per bout, +-5 % per stride): a
    loading-response bump (0.3-0.6 ``peak`` at 10-20 % of the stride) and a swing-assist peak
    (0.7-1 ``peak`` at 60-75 %), on a 0.05-0.15 ``peak`` floor; standing pauses of 3-10 s."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start, floor = 0.0, float(rng.uniform(0.05, 0.15))
    while start < duration_s:
        stride = float(rng.uniform(1.2, 2.4))
        bump, swing = float(rng.uniform(0.3, 0.6)), float(rng.uniform(0.7, 1.0))
        for _ in range(int(rng.integers(8, 26))):
            length = stride * float(rng.uniform(0.95, 1.05))
            mask = (t >= start) & (t < start + length)
            ph = (t[mask] - start) / length
            a, b = bump * float(rng.uniform(0.9, 1.1)), swing * float(rng.uniform(0.92, 1.0))
            shape = a * np.exp(-0.5 * ((ph - rng.uniform(0.1, 0.2)) / 0.07) ** 2)
            shape = np.maximum(shape, b * np.exp(-0.5 * ((ph - rng.uniform(0.6, 0.75)) / 0.09) ** 2))
            out[mask] = peak * (floor + (1.0 - floor) * shape)
            start += length
        pause = float(rng.uniform(3.0, 10.0))
        out[(t >= start) & (t < start + pause)] = peak * floor
        start += pause
    return out


def am_sine(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A 0.1-0.6 Hz carrier around 0.45-0.55 ``peak`` whose amplitude is modulated by a
    0.01-0.04 Hz sine (depth 0.4-0.9), so the loops breathe between small and large."""
    t = time_grid(duration_s, dt_s)
    centre = float(rng.uniform(0.45, 0.55))
    depth, fm = float(rng.uniform(0.4, 0.9)), float(rng.uniform(0.01, 0.04))
    envelope = 1.0 - depth * 0.5 * (1.0 + np.cos(2 * np.pi * fm * t + rng.uniform(0, 2 * np.pi)))
    carrier = np.sin(2 * np.pi * rng.uniform(0.1, 0.6) * t)
    return np.asarray(peak * (centre + 0.97 * min(centre, 1.0 - centre) * envelope * carrier), dtype=np.float64)


def sawtooth_train(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Teeth from a 0-0.2 ``peak`` base to 0.25-1 ``peak``: a slow side of 2-8 s and a fast side of
    0.15-0.5 s, rising slowly or falling slowly (drawn per tooth), 0-2 s at the base between."""
    knots_t, knots_u = [0.0], [float(rng.uniform(0.0, 0.2) * peak)]
    while knots_t[-1] < duration_s:
        top, base = float(rng.uniform(0.25, 1.0) * peak), float(rng.uniform(0.0, 0.2) * peak)
        slow, fast = float(rng.uniform(2.0, 8.0)), float(rng.uniform(0.15, 0.5))
        up, down = (slow, fast) if rng.uniform() < 0.5 else (fast, slow)
        rest = float(rng.uniform(0.0, 2.0))
        now = knots_t[-1]
        knots_t += [now + up, now + up + down, now + up + down + rest + 1e-3]
        knots_u += [top, base, base]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def setpoint_tracking(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A pressure loop tracking a smooth setpoint (monotone cubic through random levels every
    4-15 s): its response is an underdamped 2nd-order one (0.5-1.5 Hz, damping 0.4-0.7)."""
    t = time_grid(duration_s, dt_s)
    knots_t, knots_u = [0.0], [float(rng.uniform(0.2, 0.8))]
    while knots_t[-1] < duration_s:
        knots_t.append(knots_t[-1] + float(rng.uniform(4.0, 15.0)))
        knots_u.append(float(rng.uniform(0.08, 0.92)))
    setpoint = PchipInterpolator(knots_t, knots_u)(t) * peak
    f_hz, zeta = float(rng.uniform(0.5, 1.5)), float(rng.uniform(0.4, 0.7))
    return resonance(setpoint, dt_s, f_hz, zeta)


def pwm_duty(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """The chamber pressure of an on/off valve pair switched at 2-5 Hz with a duty cycle that
    wanders slowly (random knots every 3-10 s in 0.05-0.95): fill and vent through a 0.1-0.3 s
    time constant, so the pressure ripples around a mean that follows the duty."""
    t = time_grid(duration_s, dt_s)
    knots_t, knots_d = [0.0], [float(rng.uniform(0.2, 0.8))]
    while knots_t[-1] < duration_s:
        knots_t.append(knots_t[-1] + float(rng.uniform(3.0, 10.0)))
        knots_d.append(float(rng.uniform(0.05, 0.95)))
    duty = np.interp(t, knots_t, knots_d)
    phase = (t * rng.uniform(2.0, 5.0)) % 1.0
    on = (phase < duty).astype(np.float64) * peak
    a = 1.0 - np.exp(-dt_s / rng.uniform(0.1, 0.3))
    return np.asarray(lfilter([a], [1.0, a - 1.0], on, zi=[duty[0] * peak * (1 - a)])[0], dtype=np.float64)


BLIND2_PROTOCOLS: dict[str, Protocol] = {
    "gait_cycle": gait_cycle,
    "am_sine": am_sine,
    "sawtooth_train": sawtooth_train,
    "setpoint_tracking": setpoint_tracking,
    "pwm_duty": pwm_duty,
}


def with_range_check(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """1 s vented, a half-cosine up to 0.97-1 ``peak`` in 1.2 s, 0.5 s hold, a half-cosine down
    to the protocol's first value in 1.2 s, then ``protocol`` [0..peak] to ``duration_s``."""
    body = np.clip(BLIND2_PROTOCOLS[protocol](duration_s - LEAD_IN_S + 1.0, dt_s, peak, rng), 0.0, peak)
    top = float(rng.uniform(0.97, 1.0) * peak)

    def half_cosine(a: float, b: float, seconds: float) -> Array:
        s = np.arange(int(round(seconds / dt_s)), dtype=np.float64) / round(seconds / dt_s)
        return np.asarray(a + (b - a) * 0.5 * (1.0 - np.cos(np.pi * s)), dtype=np.float64)

    lead = [
        np.zeros(int(round(VENTED_S / dt_s))),
        half_cosine(0.0, top, RISE_S),
        np.full(int(round(HOLD_S / dt_s)), top),
        half_cosine(top, float(body[0]), FALL_S),
    ]
    return np.concatenate([*lead, body])[: int(round(duration_s / dt_s))]
