"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a shakedown.

What labs working on soft-robot circuits, pumps and system identification would run: a
*frequency-hopping* sine (phase-continuous, hopping among 4-6 log-spaced frequencies of 0.05-2
Hz, a few cycles at each: the dwell-free cousin of a stepped sine); a *crank-driven bellows* (a
crank-slider pump's non-sinusoidal pressure: its rod ratio skews the cycle, the crank's speed,
the bias and the stroke redrawn per block); a *bias ladder* (a small sine riding on a mean that
steps up a ladder of levels and back, the sine's frequency redrawn per rung: minor loops all
over the range); a *chaotic* input (the x coordinate of the Lorenz system, time-scaled to
lobe switches of ~0.2-0.8 Hz: broadband, never periodic); and a *pneumatic relaxation
oscillator* (a soft-robot oscillator cell: the line fills through a restrictor until a
snap-acting valve trips at its upper threshold, vents until it resets at the lower one; the
thresholds and the restrictor wander slowly).

Every record starts vented (0.3-0.8 s) and is *shaken down* in its first ~6 s
(:func:`with_exhaust_shakedown`): three sawtooth fills (a linear rise to 0.97-1 ``peak`` in
0.9-1.3 s, a quick exhaust in 0.08-0.15 s, 0.2-0.3 s vented), then a 0.4 s linear ramp to the
protocol's first value.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import solve_ivp

from bench.plants.grids import time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def frequency_hopping(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """``mid - amp cos(phase)`` (mid 0.45-0.55, amp 0.3-0.43 ``peak``, from the low point), the
    phase advancing at a frequency hopping among 4-6 log-spaced values in 0.05-2 Hz, 2-5 cycles
    (and at least 2 s) at each, the next frequency another one of the set."""
    t = time_grid(duration_s, dt_s)
    if t.size == 0:
        return t
    freqs = np.geomspace(float(rng.uniform(0.05, 0.1)), float(rng.uniform(1.0, 2.0)), int(rng.integers(4, 7)))
    f = np.empty_like(t)
    now, k = 0.0, int(rng.integers(0, freqs.size))
    while now < duration_s:
        length = max(float(rng.integers(2, 6)) / float(freqs[k]), 2.0)
        f[(t >= now) & (t < now + length)] = freqs[k]
        now += length
        k = (k + int(rng.integers(1, freqs.size))) % freqs.size
    phase = 2.0 * np.pi * np.cumsum(f) * dt_s
    mid, amp = float(rng.uniform(0.45, 0.55)), float(rng.uniform(0.3, 0.43))
    return np.asarray(peak * np.clip(mid - amp * np.cos(phase - phase[0]), 0.0, 1.0), dtype=np.float64)


def crank_bellows(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks of 15-40 s of a crank-slider bellows: ``bias + lift s(theta)``, ``s`` the slider's
    travel ``(r (1 - cos th) + l - sqrt(l^2 - r^2 sin^2 th)) / 2r`` (rod ratio ``r / l`` 0.2-0.45),
    the crank at 0.15-1 Hz, bias 0.03-0.2 and lift 0.6-0.9 ``peak`` (at most to the top), all redrawn
    per block; the phase runs on across blocks."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start, theta0 = 0.0, 0.0
    while start < duration_s:
        length = float(rng.uniform(15.0, 40.0))
        ratio, f = float(rng.uniform(0.2, 0.45)), float(rng.uniform(0.15, 1.0))
        bias = float(rng.uniform(0.03, 0.2))
        lift = min(float(rng.uniform(0.6, 0.9)), 1.0 - bias)
        inside = (t >= start) & (t < start + length)
        th = theta0 + 2.0 * np.pi * f * (t[inside] - start)
        rod = 1.0 / ratio
        s = ((1.0 - np.cos(th)) + rod - np.sqrt(rod * rod - np.sin(th) ** 2)) / 2.0
        out[inside] = bias + lift * s
        theta0 += 2.0 * np.pi * f * length
        start += length
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def bias_ladder(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A sine of 0.08-0.16 ``peak`` riding on a mean that climbs 5-8 equal rungs from 0.15-0.25 to
    0.75-0.85 and back down, each held 4-10 s and reached over 0.5 s; the sine's frequency
    (0.3-1.2 Hz) redrawn per rung, its phase running on."""
    t = time_grid(duration_s, dt_s)
    knots_t, knots_m, freq = [0.0], [0.2], np.empty_like(t)
    now, amp = 0.0, float(rng.uniform(0.08, 0.16))
    while now < duration_s:
        n = int(rng.integers(5, 9))
        levels = np.linspace(float(rng.uniform(0.15, 0.25)), float(rng.uniform(0.75, 0.85)), n)
        for level in np.concatenate([levels, levels[-2::-1]]).tolist():
            hold = float(rng.uniform(4.0, 10.0))
            knots_t += [now + 0.5, now + hold]
            knots_m += [level, level]
            freq[(t >= now) & (t < now + hold)] = float(rng.uniform(0.3, 1.2))
            now += hold
    mean = np.interp(t, knots_t, knots_m)
    phase = 2.0 * np.pi * np.cumsum(freq) * dt_s
    return np.asarray(peak * np.clip(mean + amp * np.sin(phase), 0.0, 1.0), dtype=np.float64)


def lorenz_chaos(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """``0.5 + 0.45 x / 20`` (clipped to 0.02..1) of the Lorenz system (sigma 10, rho 28, beta
    8/3) run ``kappa`` (0.25-0.6) of its own time units per second, from a random point after a
    transient of 20 units."""
    t = time_grid(duration_s, dt_s)
    kappa = float(rng.uniform(0.25, 0.6))

    def lorenz(_: float, s: Array) -> Array:
        x, y, z = s
        return np.array([10.0 * (y - x), x * (28.0 - z) - y, x * y - 8.0 / 3.0 * z])

    start = rng.uniform(-10.0, 10.0, 3) + np.array([0.0, 0.0, 25.0])
    settled = solve_ivp(lorenz, (0.0, 20.0), start, method="DOP853", rtol=1e-5, atol=1e-7).y[:, -1]
    if t.size == 0:
        return t
    span = (0.0, kappa * t[-1] + 1e-9)
    path = solve_ivp(lorenz, span, settled, method="DOP853", t_eval=kappa * t, rtol=1e-5, atol=1e-7)
    return np.asarray(peak * np.clip(0.5 + 0.45 * path.y[0] / 20.0, 0.02, 1.0), dtype=np.float64)


def relaxation_oscillator(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Fill towards the supply (1.0) through a restrictor (``tau_f`` 0.4-1.5 s) until the snap valve
    trips at ``hi`` (0.75-0.95), vent (``tau_v`` 0.3-1.0 s) until it resets at ``lo`` (0.05-0.3);
    ``hi``, ``lo`` and ``tau_f`` wander by +-10-20 % on 20-60 s sines (exact per sample)."""
    t = time_grid(duration_s, dt_s)
    hi0, lo0 = float(rng.uniform(0.75, 0.95)), float(rng.uniform(0.05, 0.3))
    tau_f0, tau_v = float(rng.uniform(0.4, 1.5)), float(rng.uniform(0.3, 1.0))
    wander = float(rng.uniform(0.1, 0.2))

    def drift(period: float, phase: float) -> Array:
        return np.asarray(1.0 + wander * np.sin(2.0 * np.pi * t / period + phase), dtype=np.float64)

    hi = np.minimum(hi0 * drift(float(rng.uniform(20.0, 60.0)), float(rng.uniform(0.0, 6.3))), 0.98).tolist()
    lo = (lo0 * drift(float(rng.uniform(20.0, 60.0)), float(rng.uniform(0.0, 6.3)))).tolist()
    tau_f = (tau_f0 * drift(float(rng.uniform(20.0, 60.0)), float(rng.uniform(0.0, 6.3)))).tolist()
    keep_v = math.exp(-dt_s / tau_v)
    out = np.empty_like(t)
    p, filling = float(rng.uniform(0.1, 0.5)), True
    for i in range(t.size):
        if filling:
            p = 1.0 + (p - 1.0) * math.exp(-dt_s / tau_f[i])
            filling = p < hi[i]
        else:
            p *= keep_v
            filling = p <= lo[i]
        out[i] = p
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


BLIND10_PROTOCOLS: dict[str, Protocol] = {
    "frequency_hopping": frequency_hopping,
    "crank_bellows": crank_bellows,
    "bias_ladder": bias_ladder,
    "lorenz_chaos": lorenz_chaos,
    "relaxation_oscillator": relaxation_oscillator,
}


def with_exhaust_shakedown(
    protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator
) -> Array:
    """0.3-0.8 s vented, three sawtooth fills (a linear rise to 0.97-1 ``peak`` in 0.9-1.3 s, a
    linear quick exhaust in 0.08-0.15 s, 0.2-0.3 s vented), a 0.4 s linear ramp to the protocol's
    first value, then ``protocol`` [0..peak] to ``duration_s``."""
    top = float(rng.uniform(0.97, 1.0))
    knots_t, knots_u = [0.0, float(rng.uniform(0.3, 0.8))], [0.0, 0.0]
    for _ in range(3):
        rise, fall, rest = float(rng.uniform(0.9, 1.3)), float(rng.uniform(0.08, 0.15)), float(rng.uniform(0.2, 0.3))
        now = knots_t[-1]
        knots_t += [now + rise, now + rise + fall, now + rise + fall + rest]
        knots_u += [top, 0.0, 0.0]
    lead_s = knots_t[-1] + 0.4
    body = np.clip(BLIND10_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    knots_t.append(lead_s)
    knots_u.append(float(body[0]) / peak)
    t = time_grid(lead_s, dt_s)
    lead = peak * np.interp(t, knots_t, knots_u)
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
