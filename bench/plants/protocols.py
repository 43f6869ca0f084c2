"""Excitation protocols [input units, 0..peak], each preceded by one full-range conditioning cycle.

Every record starts vented (u = 0), makes one slow 0 -> peak -> low cycle (so the memory is
known early, as a careful experimenter does) and then runs the protocol, which may stay in the
upper part of the range: the case that put the only low-input data in one held-out block.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.grids import time_grid

Protocol = Callable[[float, float, float, np.random.Generator], NDArray[np.float64]]


def multisine(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """Random-phase multisine, 12 log-spaced tones 0.02-1.0 Hz, scaled into 0.1..1 of ``peak``."""
    t = time_grid(duration_s, dt_s)
    freqs = np.geomspace(0.02, 1.0, 12)
    amps = 1.0 / np.sqrt(freqs / freqs[0])
    s = sum(a * np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi)) for a, f in zip(amps, freqs))
    s = (s - s.min()) / np.ptp(s)
    return peak * (0.1 + 0.9 * s)


def steps(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """Steps to random levels (0.2-1 ramps of 0.3-1 s) with holds of 5-20 s."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    level, start = float(0.5 * peak), 0.0
    while start < duration_s:
        target = float(rng.uniform(0.15, 1.0) * peak)
        ramp = float(rng.uniform(0.3, 1.0))
        hold = float(rng.uniform(5.0, 20.0))
        mask = (t >= start) & (t < start + ramp + hold)
        out[mask] = level + (target - level) * np.clip((t[mask] - start) / ramp, 0.0, 1.0)
        level, start = target, start + ramp + hold
    return out


def growing_triangles(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """Triangles around mid-range whose amplitude grows then falls, at 0.05-0.5 Hz (period drawn per cycle)."""
    pieces, total = [], 0.0
    k = 0
    while total < duration_s:
        period = float(rng.uniform(2.0, 20.0))
        phase = k / 12.0
        amp = 0.45 * (0.2 + 0.8 * abs(np.sin(np.pi * phase)))
        tt = np.arange(int(round(period / dt_s))) * dt_s
        tri = 1.0 - np.abs(2.0 * (tt / period) - 1.0)  # 0 -> 1 -> 0
        pieces.append(peak * (0.55 + amp * (2 * tri - 1.0)))
        total += period
        k += 1
    return np.concatenate(pieces)[: int(round(duration_s / dt_s))]


def chirp(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """Logarithmic chirp 0.02 -> 1.5 Hz and back, amplitude 0.3-0.45 of ``peak`` around 0.55 ``peak``."""
    t = time_grid(duration_s, dt_s)
    half = duration_s / 2
    f0, f1 = 0.02, float(rng.uniform(0.8, 1.5))
    k = np.log(f1 / f0) / half
    tau = np.where(t < half, t, duration_s - t)
    phase = 2 * np.pi * f0 * (np.exp(k * tau) - 1) / k
    phase = np.where(t < half, phase, 2 * (2 * np.pi * f0 * (np.exp(k * half) - 1) / k) - phase)
    amp = float(rng.uniform(0.3, 0.45))
    return peak * (0.55 + amp * np.sin(phase))


PROTOCOLS: dict[str, Protocol] = {
    "multisine": multisine,
    "steps": steps,
    "triangles": growing_triangles,
    "chirp": chirp,
}


def with_conditioning(
    protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator
) -> NDArray[np.float64]:
    """0 -> peak -> 0.1 peak in 8 s, then ``protocol`` for the rest (joined by a 1 s ramp)."""
    cond_t = time_grid(8.0, dt_s)
    cond = peak * np.where(cond_t < 4.0, cond_t / 4.0, 1.0 - 0.9 * (cond_t - 4.0) / 4.0)
    body = PROTOCOLS[protocol](duration_s - 9.0, dt_s, peak, rng)
    join = np.linspace(cond[-1], body[0], int(round(1.0 / dt_s)), endpoint=False)
    return np.concatenate([cond, join, body])[: int(round(duration_s / dt_s))]
