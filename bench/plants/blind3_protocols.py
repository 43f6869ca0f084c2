"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a full sweep.

What a soft-actuator characterisation lab would run: a Schroeder-phased multisine (low crest
factor, harmonics of one fundamental) riding on a very slow offset; a *speed ladder* of
full-range constant-rate ramps at four speeds (the classic rate-dependence test); a stepped
sine (a frequency-response test that dwells a few cycles at each of 6-9 log-spaced frequencies);
slow triangles with a 2-5 Hz dither on top (friction-compensation dither); and point-to-point
reaching moves with minimum-jerk profiles whose durations follow Fitts' law.

Every record starts vented (0.6-1 s) and then does a *full sweep* within its first ~5 s: a
linear fill to 0.98-1 ``peak`` in 1.3-1.7 s, a short hold, a linear vent to 0 and a ramp to
where the protocol starts, so the hysteresis memory is known early (:func:`with_full_sweep`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def schroeder_offset(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """8-14 harmonics of a 0.04-0.08 Hz fundamental (amplitudes flat or falling as 1/sqrt(k)) with
    Schroeder phases ``phi_k = -pi k (k - 1) / K`` (crest factor ~1.5), scaled to +-0.25-0.35
    ``peak``, on an offset swinging 0.35-0.65 ``peak`` at 0.006-0.015 Hz."""
    t = time_grid(duration_s, dt_s)
    n_tones, f0 = int(rng.integers(8, 15)), float(rng.uniform(0.04, 0.08))
    k = np.arange(1, n_tones + 1, dtype=np.float64)
    amps = k ** -float(rng.choice([0.0, 0.5]))
    phases = -np.pi * k * (k - 1.0) / n_tones
    x = (amps[:, None] * np.cos(2 * np.pi * f0 * k[:, None] * t[None, :] + phases[:, None])).sum(axis=0)
    x = x / max(float(np.max(np.abs(x))), 1e-12)
    swing = float(rng.uniform(0.1, 0.15))
    offset = 0.5 + swing * np.sin(2 * np.pi * rng.uniform(0.006, 0.015) * t + rng.uniform(0, 2 * np.pi))
    return np.asarray(peak * (offset + rng.uniform(0.25, 0.35) * x), dtype=np.float64)


def speed_ladder(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Full-range constant-rate ramps between 0.02-0.08 and 0.92-1 ``peak`` at four speeds (log
    spaced, 0.08-0.15 up to 1-2 ``peak``/s), 2-3 up-down cycles per speed, speeds in a random
    order per block, 0.2-1 s dwell at each end."""
    lo, hi = float(rng.uniform(0.02, 0.08)) * peak, float(rng.uniform(0.92, 1.0)) * peak
    speeds = np.geomspace(rng.uniform(0.08, 0.15), rng.uniform(1.0, 2.0), 4) * peak
    knots_t, knots_u = [0.0], [lo]
    while knots_t[-1] < duration_s:
        for speed in rng.permutation(speeds):
            for _ in range(int(rng.integers(2, 4))):
                ramp = (hi - lo) / float(speed)
                for level in (hi, lo):
                    dwell = float(rng.uniform(0.2, 1.0))
                    knots_t += [knots_t[-1] + ramp, knots_t[-1] + ramp + dwell]
                    knots_u += [level, level]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def stepped_sine(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A stepped-sine frequency response: 6-9 log-spaced frequencies in 0.03-1.5 Hz, 2-4 whole
    cycles each around 0.5 ``peak`` with amplitude 0.3-0.45 ``peak`` (sweeping up, then down, ...),
    starting and ending each dwell at the centre so the steps join smoothly."""
    freqs = np.geomspace(rng.uniform(0.03, 0.06), rng.uniform(0.8, 1.5), int(rng.integers(6, 10)))
    centre, amp = 0.5 * peak, float(rng.uniform(0.3, 0.45)) * peak
    pieces: list[Array] = []
    total, order = 0, freqs
    while total * dt_s < duration_s:
        for f in order:
            cycles = int(rng.integers(2, 5))
            s = np.arange(int(round(cycles / f / dt_s)), dtype=np.float64) * dt_s
            pieces.append(centre + amp * np.sin(2 * np.pi * f * s))
            total += s.size
        order = order[::-1]
    return np.asarray(np.concatenate(pieces)[: int(round(duration_s / dt_s))], dtype=np.float64)


def dithered_triangles(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Triangles between a low (0.03-0.3 ``peak``) and a high (0.6-0.97 ``peak``) level drawn per
    cycle, each side 4-15 s, with a 2-5 Hz sine dither of 2-4 % ``peak`` added (as a
    friction-compensating valve driver does)."""
    knots_t, knots_u = [0.0], [float(rng.uniform(0.03, 0.3)) * peak]
    while knots_t[-1] < duration_s:
        for lo, hi in ((0.6, 0.97), (0.03, 0.3)):
            knots_t.append(knots_t[-1] + float(rng.uniform(4.0, 15.0)))
            knots_u.append(float(rng.uniform(lo, hi)) * peak)
    t = time_grid(duration_s, dt_s)
    dither = rng.uniform(0.02, 0.04) * peak * np.sin(2 * np.pi * rng.uniform(2.0, 5.0) * t)
    return np.asarray(np.interp(t, knots_t, knots_u) + dither, dtype=np.float64)


def min_jerk_reaching(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Point-to-point moves to random targets in 0.03-1 ``peak`` along minimum-jerk profiles
    ``10 s^3 - 15 s^4 + 6 s^5``; each move lasts ``a + b log2(1 + D / W)`` (Fitts' law, ``a``
    0.2-0.4 s, ``b`` 0.3-0.6 s, ``W`` 0.05 ``peak``), then a log-normal dwell (median 1.5 s)."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    a, b = float(rng.uniform(0.2, 0.4)), float(rng.uniform(0.3, 0.6))
    now, level = 0.0, float(rng.uniform(0.03, 1.0))
    while now < duration_s:
        target = float(rng.uniform(0.03, 1.0))
        move = a + b * np.log2(1.0 + abs(target - level) / 0.05)
        dwell = float(np.clip(rng.lognormal(np.log(1.5), 0.7), 0.2, 8.0))
        mask = (t >= now) & (t < now + move + dwell)
        s = np.clip((t[mask] - now) / move, 0.0, 1.0)
        out[mask] = peak * (level + (target - level) * (10 * s**3 - 15 * s**4 + 6 * s**5))
        now, level = now + move + dwell, target
    return out


BLIND3_PROTOCOLS: dict[str, Protocol] = {
    "schroeder_offset": schroeder_offset,
    "speed_ladder": speed_ladder,
    "stepped_sine": stepped_sine,
    "dithered_triangles": dithered_triangles,
    "min_jerk_reaching": min_jerk_reaching,
}


def with_full_sweep(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.6-1 s vented, a linear fill to 0.98-1 ``peak`` in 1.3-1.7 s, a 0.3-0.6 s hold, a linear
    vent to 0 in 1.3-1.7 s, a 0.5 s ramp to the protocol's first value, then ``protocol``
    [0..peak] to ``duration_s``."""
    vented, rise, hold, fall = (
        float(rng.uniform(lo, hi)) for lo, hi in ((0.6, 1.0), (1.3, 1.7), (0.3, 0.6), (1.3, 1.7))
    )
    top = float(rng.uniform(0.98, 1.0)) * peak
    lead_s = vented + rise + hold + fall + 0.5
    body = np.clip(BLIND3_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    knots_t = np.array([0.0, vented, vented + rise, vented + rise + hold, vented + rise + hold + fall, lead_s])
    knots_u = np.array([0.0, 0.0, top, top, 0.0, float(body[0])])
    lead = knotted(lead_s, dt_s, knots_t, knots_u)
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
