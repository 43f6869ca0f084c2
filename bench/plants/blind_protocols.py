"""Seven excitation protocols [bar, 0..peak] unlike the tuning and fresh families', each started vented.

What a third lab would run: a staircase with holds of random (exponential) length, slow ramps
reversing at random levels, band-limited noise around a wandering mean, sine bursts whose
amplitude grows and then decays, trapezoids back to a low base, FORC-like sweeps (down to a
reversal level that falls sweep by sweep, back to the top), and triangles of random amplitude.
There is no full-range conditioning cycle: every record sits vented for 2 s and then ramps in.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray
from scipy.signal import butter, sosfiltfilt

from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]
VENTED_S = 2.0
JOIN_S = 1.5


def staircase_random_holds(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Steps of +-0.05-0.4 ``peak`` (a random walk reflected into 0.05-1) in 0.15 s, held for an
    exponentially distributed 0.3-20 s (mean 5 s)."""
    knots_t, knots_u = [0.0], [float(rng.uniform(0.2, 0.6) * peak)]
    while knots_t[-1] < duration_s:
        hold = float(np.clip(rng.exponential(5.0), 0.3, 20.0))
        level = knots_u[-1] / peak + float(rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.4))
        level = abs(level - 0.05) + 0.05 if level < 0.05 else 2.0 - level if level > 1.0 else level
        knots_t += [knots_t[-1] + hold, knots_t[-1] + hold + 0.15]
        knots_u += [knots_u[-1], float(np.clip(level, 0.05, 1.0)) * peak]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def reversing_ramps(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Ramps at 0.03-0.4 ``peak``/s, each reversing at a random level (no holds)."""
    knots_t, knots_u = [0.0], [float(rng.uniform(0.1, 0.3) * peak)]
    up = True
    while knots_t[-1] < duration_s:
        here = knots_u[-1] / peak
        target = float(
            rng.uniform(here + 0.05, 1.0) if up and here < 0.95 else rng.uniform(0.0, max(here - 0.05, 0.01))
        )
        speed = float(rng.uniform(0.03, 0.4))
        knots_t.append(knots_t[-1] + abs(target - here) / speed + 1e-3)
        knots_u.append(target * peak)
        up = not up
    return knotted(duration_s, dt_s, knots_t, knots_u)


def band_noise(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Gaussian noise low-passed at 0.2-1.5 Hz (4th-order Butterworth) on a mean wandering
    below 0.05 Hz, squeezed into 0.05-1 ``peak`` by a soft clip."""
    t = time_grid(duration_s, dt_s)
    fast = sosfiltfilt(butter(4, rng.uniform(0.2, 1.5), fs=1.0 / dt_s, output="sos"), rng.normal(size=t.size))
    slow = sosfiltfilt(butter(2, 0.05, fs=1.0 / dt_s, output="sos"), rng.normal(size=t.size))
    s = fast / (np.std(fast) or 1.0) * 0.15 + slow / (np.std(slow) or 1.0) * 0.12
    return np.asarray(peak * (0.525 + 0.475 * np.tanh((s - np.median(s)) / 0.45)), dtype=np.float64)


def spindle_bursts(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Sine bursts (0.05-1 Hz) around a random centre whose amplitude grows to its maximum and
    decays again (a sin^2 envelope over 8-25 s), separated by 1-4 s at the centre."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start, previous = 0.0, 0.5 * peak
    while start < duration_s:
        length, rest = float(rng.uniform(8.0, 25.0)), float(rng.uniform(1.0, 4.0))
        centre = float(rng.uniform(0.35, 0.65) * peak)
        amp = min(centre, peak - centre) * float(rng.uniform(0.7, 0.98))
        freq = float(rng.uniform(0.05, 1.0))
        mask = (t >= start) & (t < start + length + rest)
        tt = t[mask] - start
        envelope = np.sin(np.pi * np.clip(tt / length, 0.0, 1.0)) ** 2
        entry = np.clip(tt / 0.5, 0.0, 1.0)
        out[mask] = previous + (centre + amp * envelope * np.sin(2 * np.pi * freq * tt) - previous) * entry
        previous, start = centre, start + length + rest
    return out


def trapezoids(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """From a low base (0-0.2 ``peak``) up to 0.4-1 ``peak`` in 0.5-6 s, a 1-10 s plateau, down in
    0.5-6 s, 1-6 s at the base."""
    knots_t, knots_u = [0.0], [float(rng.uniform(0.0, 0.2) * peak)]
    while knots_t[-1] < duration_s:
        top = float(rng.uniform(0.4, 1.0) * peak)
        rise, plateau, fall = (float(x) for x in rng.uniform([0.5, 1.0, 0.5], [6.0, 10.0, 6.0]))
        rest = float(rng.uniform(1.0, 6.0))
        new_base = float(rng.uniform(0.0, 0.2) * peak)
        now = knots_t[-1]
        knots_t += [now + rise, now + rise + plateau, now + rise + plateau + fall, now + rise + plateau + fall + rest]
        knots_u += [top, top, new_base, new_base]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def forc_sweeps(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """First-order reversal curves: from 0.95 ``peak`` down to a reversal level falling from 0.85
    to 0.05 over 6-10 sweeps, back up, at 0.1-0.4 ``peak``/s; repeated until the record ends."""
    speed = float(rng.uniform(0.1, 0.4))
    n_sweeps = int(rng.integers(6, 11))
    knots_t, knots_u = [0.0], [0.95 * peak]
    while knots_t[-1] < duration_s:
        for level in np.linspace(0.85, 0.05, n_sweeps).tolist():
            down = (0.95 - level) / speed
            knots_t += [knots_t[-1] + down, knots_t[-1] + 2 * down]
            knots_u += [level * peak, 0.95 * peak]
    return knotted(duration_s, dt_s, knots_t, knots_u)


def random_triangles(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Triangles of random amplitude (0.05-0.45 ``peak``) around a centre that moves every 3-6
    cycles, at a period of 1-12 s drawn per group."""
    knots_t, knots_u = [0.0], [0.5 * peak]
    while knots_t[-1] < duration_s:
        centre, period = float(rng.uniform(0.3, 0.7)), float(rng.uniform(1.0, 12.0))
        for _ in range(int(rng.integers(3, 7))):
            amp = float(rng.uniform(0.05, 0.45)) * min(centre, 1.0 - centre) / 0.45
            knots_t += [knots_t[-1] + period / 2, knots_t[-1] + period]
            knots_u += [(centre + amp) * peak, (centre - amp) * peak]
    return knotted(duration_s, dt_s, knots_t, knots_u)


BLIND_PROTOCOLS: dict[str, Protocol] = {
    "staircase_random_holds": staircase_random_holds,
    "reversing_ramps": reversing_ramps,
    "band_noise": band_noise,
    "spindle_bursts": spindle_bursts,
    "trapezoids": trapezoids,
    "forc_sweeps": forc_sweeps,
    "random_triangles": random_triangles,
}


def vented_start(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """2 s vented, a 1.5 s ramp to the protocol's first value, then ``protocol`` [0..peak]."""
    body = np.clip(BLIND_PROTOCOLS[protocol](duration_s - VENTED_S - JOIN_S + 1.0, dt_s, peak, rng), 0.0, peak)
    vented = np.zeros(int(round(VENTED_S / dt_s)))
    join = np.linspace(0.0, body[0], int(round(JOIN_S / dt_s)), endpoint=False)
    return np.concatenate([vented, join, body])[: int(round(duration_s / dt_s))]
