"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a conditioning.

What labs in rehabilitation, bio-inspired and marine soft robotics and system identification
would run: a *pseudo-random ternary sequence* of ramps (a maximal-length sequence over GF(3) from
a linear feedback shift register, its three levels joined by ramps: persistently exciting with
minor loops between any two levels); a *sum of decaying ring-downs* (an impedance-controlled joint
struck at random instants: each strike rings down as a damped sinusoid on a bias, overlapping);
a *Matsuoka central pattern generator* (two mutually inhibiting neurons with self-adaptation
driving a swimming fin: a non-sinusoidal rhythm whose frequency and amplitude follow a tonic drive
stepped every 10-25 s); *sit-to-stand* assistance of a knee exoskeleton (seated rest, a
minimum-jerk rise to full assistance, standing support with sway, a slower controlled sit-down,
every repetition redrawn); and a *JONSWAP sea state* for a wave-energy pump (a random-phase sum
over a peaked JONSWAP spectrum scaled to a lab tank, its significant height breathing over
40-90 s: wave groups, never periodic).

Every record starts vented (0.3-0.6 s) and is conditioned in its first ~6 s
(:func:`with_ringdown_conditioning`): two raised-cosine fills to 0.98-1 ``peak`` (0.9-1.3 s up,
0.5-0.8 s down to vented, 0.15-0.3 s vented after each), then a *decaying oscillation* about half
the range starting vented (3-5 Hz, decaying in 0.25-0.4 s, 1.2-1.6 s long: it wipes the memory
towards a demagnetised state), then a 0.3 s ramp to the protocol's first value.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.grids import time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]
GF3_PERIOD = 242  # 3^5 - 1: the register's characteristic polynomial x^5 + 2x + 1 is primitive over GF(3)


def ternary_sequence(n: int, seed_state: tuple[int, ...]) -> list[int]:
    """``n`` symbols (0, 1, 2) of the maximal-length sequence of the GF(3) register ``s[k] = 2 s[k-5] +
    s[k-4]`` mod 3 (characteristic polynomial ``x^5 - x - 2 = x^5 + 2x + 1``, primitive: period
    :data:`GF3_PERIOD`) from a non-zero state."""
    state = list(seed_state)
    out: list[int] = []
    while len(out) < n:
        nxt = (2 * state[-5] + state[-4]) % 3
        state.append(nxt)
        out.append(nxt)
        del state[0]
    return out


def ternary_ramps(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Three levels (0.08-0.2, 0.42-0.58, 0.82-0.95 ``peak``) chosen by the ternary sequence, a clock
    period of 0.7-2.5 s redrawn every 12 symbols, each change a linear ramp over 15-60 % of the
    period (repeats hold)."""
    t = time_grid(duration_s, dt_s)
    levels = [float(rng.uniform(0.08, 0.2)), float(rng.uniform(0.42, 0.58)), float(rng.uniform(0.82, 0.95))]
    state = tuple(int(s) for s in rng.integers(0, 3, 5))
    if not any(state):
        state = (1, 0, 0, 0, 0)
    start = int(rng.integers(0, GF3_PERIOD))
    knots_t, knots_u = [0.0], [levels[1]]
    now, period = 0.0, 1.0
    symbols = ternary_sequence(start + 4000, state)[start:]
    for i, sym in enumerate(symbols):
        if now > duration_s + 3.0:
            break
        if i % 12 == 0:
            period = float(rng.uniform(0.7, 2.5))
        target = levels[sym]
        if target != knots_u[-1]:
            ramp = float(rng.uniform(0.15, 0.6)) * period
            knots_t += [now, now + ramp]
            knots_u += [knots_u[-1], target]
        now += period
    knots_t.append(now)
    knots_u.append(knots_u[-1])
    return np.asarray(peak * np.interp(t, knots_t, knots_u), dtype=np.float64)


def ringdown_sum(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A bias of 0.35-0.55 plus ring-downs struck at a Poisson rate (one per 1.5-4 s on average, the
    first within 1 s): each ``A e^(-t / tau) sin(2 pi f t)`` (A 0.15-0.4, f 0.3-2 Hz, tau 1.5-6 s,
    either sign); the bias wanders by +-0.1 over 30-80 s; clipped to 0..1."""
    t = time_grid(duration_s, dt_s)
    bias = float(rng.uniform(0.35, 0.55)) + 0.1 * np.sin(
        2.0 * np.pi * t / float(rng.uniform(30.0, 80.0)) + float(rng.uniform(0.0, 6.3))
    )
    out = bias.copy()
    mean_gap = float(rng.uniform(1.5, 4.0))
    strike = float(rng.uniform(0.0, 1.0))
    while strike < duration_s:
        amp = float(rng.choice([-1.0, 1.0])) * float(rng.uniform(0.15, 0.4))
        f, tau = float(rng.uniform(0.3, 2.0)), float(rng.uniform(1.5, 6.0))
        after = t >= strike
        s = t[after] - strike
        out[after] += amp * np.exp(-s / tau) * np.sin(2.0 * np.pi * f * s)
        strike += float(rng.exponential(mean_gap))
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def matsuoka_cpg(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Matsuoka's oscillator ``tau_r x_i' = -x_i - beta v_i - w y_j + s``, ``tau_a v_i' = -v_i + y_i``,
    ``y_i = max(x_i, 0)`` (beta 2.5, w 2.5, tau_a / tau_r 5-8, tau_r 0.1-0.3 s: a 0.2-1.2 Hz rhythm),
    the tonic drive ``s`` stepped to 0.6-1.4 every 10-25 s; the output ``0.5 + g (y_1 - y_2) / s``
    (g 0.4-0.55) clipped to 0..1, integrated by semi-implicit Euler at <= 5 ms."""
    t = time_grid(duration_s, dt_s)
    tau_r = float(rng.uniform(0.1, 0.3))
    tau_a = tau_r * float(rng.uniform(5.0, 8.0))
    beta, w, gain = 2.5, 2.5, float(rng.uniform(0.4, 0.55))
    steps = max(1, int(math.ceil(dt_s / 0.005)))
    h = dt_s / steps
    x1, x2, v1, v2 = 0.1, 0.0, 0.0, 0.0
    change, drive = 0.0, 1.0
    out = np.empty(t.size)
    for i, ti in enumerate(t.tolist()):
        if ti >= change:
            drive = float(rng.uniform(0.6, 1.4))
            change = ti + float(rng.uniform(10.0, 25.0))
        for _ in range(steps):
            y1, y2 = max(x1, 0.0), max(x2, 0.0)
            x1 += h / tau_r * (-x1 - beta * v1 - w * y2 + drive)
            x2 += h / tau_r * (-x2 - beta * v2 - w * y1 + drive)
            v1 += h / tau_a * (-v1 + max(x1, 0.0))
            v2 += h / tau_a * (-v2 + max(x2, 0.0))
        out[i] = 0.5 + gain * (max(x1, 0.0) - max(x2, 0.0)) / drive
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def _min_jerk(s: Array) -> Array:
    return np.asarray(10.0 * s**3 - 15.0 * s**4 + 6.0 * s**5, dtype=np.float64)


def sit_to_stand(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Repetitions of: seated (0.03-0.15 for 1.5-4 s), a minimum-jerk rise to 0.85-1 in 0.8-1.5 s,
    a minimum-jerk settle to standing support (0.4-0.6) in 0.4-0.8 s held 2-6 s with sway (0.02-0.05
    at 0.2-0.5 Hz), then a controlled sit-down: up to 0.6-0.8 in 0.3 s and down to seated in
    1.2-2.5 s (minimum jerk)."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    now, seated = 0.0, float(rng.uniform(0.03, 0.15))
    while now < duration_s:
        rest = float(rng.uniform(1.5, 4.0))
        rise, top = float(rng.uniform(0.8, 1.5)), float(rng.uniform(0.85, 1.0))
        settle, stand = float(rng.uniform(0.4, 0.8)), float(rng.uniform(0.4, 0.6))
        hold, sway = float(rng.uniform(2.0, 6.0)), float(rng.uniform(0.02, 0.05))
        f_sway, brake = float(rng.uniform(0.2, 0.5)), float(rng.uniform(0.6, 0.8))
        lower = float(rng.uniform(1.2, 2.5))
        nxt = float(rng.uniform(0.03, 0.15))
        phases = [
            (rest, seated, seated),
            (rise, seated, top),
            (settle, top, stand),
            (hold, stand, stand),
            (0.3, stand, brake),
            (lower, brake, nxt),
        ]
        for length, a, b in phases:
            inside = (t >= now) & (t < now + length)
            s = _min_jerk((t[inside] - now) / length)
            out[inside] = a + (b - a) * s
            if length == hold and a == stand:
                out[inside] += sway * np.sin(2.0 * np.pi * f_sway * (t[inside] - now))
            now += length
        seated = nxt
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def jonswap_swell(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """``0.5 + H(t) eta(t)``: ``eta`` a sum of 80 random-phase components over 0.5-4 ``f_p`` weighted
    by the JONSWAP spectrum (peak ``f_p`` 0.25-0.6 Hz, peak enhancement 2-5, normalised to unit
    standard deviation), ``H`` 0.17-0.24 breathing by +-30 % over 40-90 s; clipped to 0.02..1."""
    t = time_grid(duration_s, dt_s)
    f_p, gamma = float(rng.uniform(0.25, 0.6)), float(rng.uniform(2.0, 5.0))
    f = np.linspace(0.5 * f_p, 4.0 * f_p, 80)
    sigma = np.where(f <= f_p, 0.07, 0.09)
    shape = np.exp(-1.25 * (f_p / f) ** 4) / f**5 * gamma ** np.exp(-((f - f_p) ** 2) / (2.0 * sigma**2 * f_p**2))
    amp = np.sqrt(shape / shape.sum() * 2.0)  # unit variance
    phase = rng.uniform(0.0, 2.0 * np.pi, f.size)
    eta = np.zeros_like(t)
    for a, fi, ph in zip(amp.tolist(), f.tolist(), phase.tolist()):
        eta += a * np.cos(2.0 * np.pi * fi * t + ph)
    breathe = 1.0 + 0.3 * np.sin(2.0 * np.pi * t / float(rng.uniform(40.0, 90.0)) + float(rng.uniform(0.0, 6.3)))
    height = float(rng.uniform(0.17, 0.24)) * breathe
    return np.asarray(peak * np.clip(0.5 + height * eta, 0.02, 1.0), dtype=np.float64)


BLIND11_PROTOCOLS: dict[str, Protocol] = {
    "ternary_ramps": ternary_ramps,
    "ringdown_sum": ringdown_sum,
    "matsuoka_cpg": matsuoka_cpg,
    "sit_to_stand": sit_to_stand,
    "jonswap_swell": jonswap_swell,
}


def with_ringdown_conditioning(
    protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator
) -> Array:
    """0.3-0.6 s vented; two raised-cosine fills to 0.98-1 ``peak`` (0.9-1.3 s up, 0.5-0.8 s down,
    0.15-0.3 s vented after each); a decaying oscillation ``0.5 (1 - e^(-s / tau) cos(2 pi f s))``
    (f 3-5 Hz, tau 0.25-0.4 s, 1.2-1.6 s long, from vented); a 0.3 s linear ramp to the protocol's
    first value; then ``protocol`` [0..peak] to ``duration_s``."""
    n_vent = int(round(float(rng.uniform(0.3, 0.6)) / dt_s))
    top = float(rng.uniform(0.98, 1.0))
    pieces: list[Array] = [np.zeros(n_vent)]
    for _ in range(2):
        up, down, rest = float(rng.uniform(0.9, 1.3)), float(rng.uniform(0.5, 0.8)), float(rng.uniform(0.15, 0.3))
        pieces.append(top * 0.5 * (1.0 - np.cos(np.pi * np.arange(int(round(up / dt_s))) * dt_s / up)))
        pieces.append(top * 0.5 * (1.0 + np.cos(np.pi * np.arange(int(round(down / dt_s))) * dt_s / down)))
        pieces.append(np.zeros(int(round(rest / dt_s))))
    f, tau, ring = float(rng.uniform(3.0, 5.0)), float(rng.uniform(0.25, 0.4)), float(rng.uniform(1.2, 1.6))
    s = np.arange(int(round(ring / dt_s))) * dt_s
    wipe = 0.5 * (1.0 - np.exp(-s / tau) * np.cos(2.0 * np.pi * f * s))
    pieces.append(wipe)
    lead = np.concatenate(pieces)
    body = np.clip(
        BLIND11_PROTOCOLS[protocol](max(duration_s - lead.size * dt_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak
    )
    first = float(body[0]) / peak if body.size else 0.0
    n_ramp = int(round(0.3 / dt_s))
    last = float(lead[-1]) if lead.size else 0.0
    ramp = last + (first - last) * np.arange(1, n_ramp + 1) / n_ramp
    out = np.concatenate([peak * lead, peak * ramp, body])
    return np.asarray(np.clip(out, 0.0, peak)[: int(round(duration_s / dt_s))], dtype=np.float64)
