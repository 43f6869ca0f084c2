"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a shakedown.

What labs characterising muscles for durability, identification, control and rehabilitation
run: an *endurance block* test in the manner of ISO fatigue standards (blocks of 8-20 sinusoidal
cycles at one frequency and amplitude, each followed by a vented rest, the frequency and
amplitude redrawn per block); a *pseudo-random binary sequence* (a maximal-length LFSR of 7-9
bits clocked every 0.25-0.8 s switching between two levels, the levels redrawn for every period
of the sequence: the identification input of system-ID labs); a *staircase with overshoot* (a
tuned pressure loop's underdamped step response at each new level, 10-30 % overshoot at 0.8-2
Hz, up and down a staircase of random levels); *human tracking* (a subject following a sum of
three slow sines with a joystick: the operator's reaction delay of 0.15-0.3 s and neuromuscular
lag, 8-12 Hz physiological tremor and occasional corrective sub-movements); and a *descending
sine sweep* (a logarithmic sweep from 1.5-3 Hz down to 0.02-0.05 Hz about mid range, repeated).

Every record starts vented (0.4-0.9 s) and is *shaken down* in its first ~6 s
(:func:`with_shakedown`): four raised-cosine pulses 0 -> 0.97-1 ``peak`` -> 0 of 1.0-1.4 s each,
0.4 s vented and a 0.5 s linear ramp to the protocol's first value.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass, resonance, variable_delay
from bench.plants.grids import time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]
LFSR_TAPS = {7: (7, 6), 8: (8, 6, 5, 4), 9: (9, 5)}


def endurance_blocks(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks of 8-20 cycles ``mid - amp cos(2 pi f t)`` (f 0.2-0.8 Hz, mid 0.4-0.6, amp 0.3-0.45
    ``peak``, from the block's low point), each followed by 2-6 s vented."""
    t = time_grid(duration_s, dt_s)
    out = np.zeros_like(t)
    start = 0.0
    while start < duration_s:
        f, n = float(rng.uniform(0.2, 0.8)), int(rng.integers(8, 21))
        mid = float(rng.uniform(0.4, 0.6))
        amp = min(float(rng.uniform(0.3, 0.45)), mid - 0.02)
        inside = (t >= start) & (t < start + n / f)
        out[inside] = mid - amp * np.cos(2.0 * np.pi * f * (t[inside] - start))
        ramp = (t >= start + n / f) & (t < start + n / f + 0.3)  # vent from the low point
        out[ramp] = (mid - amp) * (1.0 - (t[ramp] - start - n / f) / 0.3)
        start += n / f + float(rng.uniform(2.0, 6.0))
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def lfsr_bits(order: int, length: int, seed: int) -> Array:
    """``length`` bits (0/1) of the Fibonacci LFSR of ``order`` (taps :data:`LFSR_TAPS`)."""
    state = seed % (2**order - 1) + 1
    taps = LFSR_TAPS[order]
    out = np.empty(length)
    for i in range(length):
        bit = 0
        for tap in taps:
            bit ^= (state >> (order - tap)) & 1
        out[i] = state & 1
        state = (state >> 1) | (bit << (order - 1))
    return out


def prbs(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A maximal-length sequence (order 7-9, clocked every 0.25-0.8 s) between a low level of
    0.05-0.35 and a high level of 0.65-1 ``peak``, both redrawn for each period of the sequence;
    the valve's command is switched, not ramped."""
    t = time_grid(duration_s, dt_s)
    order, clock = int(rng.integers(7, 10)), float(rng.uniform(0.25, 0.8))
    n_bits = int(t[-1] / clock) + 2 if t.size else 2
    bits = lfsr_bits(order, n_bits, int(rng.integers(0, 2**31)))
    period = 2**order - 1
    lows = rng.uniform(0.05, 0.35, n_bits // period + 1)
    highs = rng.uniform(0.65, 1.0, n_bits // period + 1)
    k = (t / clock).astype(np.int64)
    which = k // period
    return np.asarray(peak * np.where(bits[k] > 0.5, highs[which], lows[which]), dtype=np.float64)


def overshoot_staircase(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Levels stepping up 4-7 times by 0.12-0.3 ``peak`` (to 0.95 at most) then down likewise
    (to a floor of 0.02-0.15), every 1.5-4 s, through a tuned loop's underdamped response (0.8-2
    Hz, damping 0.35-0.6: 10-30 % overshoot); clipped to 0..1."""
    t = time_grid(duration_s, dt_s)
    target = np.zeros_like(t)
    now, level = 0.0, 0.05
    while now < duration_s:
        for going_up in (True, False):
            for _ in range(int(rng.integers(4, 8))):
                step = float(rng.uniform(0.12, 0.3))
                level = min(level + step, 0.95) if going_up else max(level - step, float(rng.uniform(0.02, 0.15)))
                hold = float(rng.uniform(1.5, 4.0))
                target[t >= now] = level
                now += hold
    out = resonance(target, dt_s, float(rng.uniform(0.8, 2.0)), float(rng.uniform(0.35, 0.6)))
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def human_tracking(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A target ``0.5 + sum a_i sin(2 pi f_i t + phi_i)`` (three sines of 0.03-0.35 Hz, amplitudes
    summing to 0.3-0.45 ``peak``) followed with a reaction delay of 0.15-0.3 s and a neuromuscular
    lag of 0.1-0.25 s, with 8-12 Hz tremor of 0.5-1.5 % ``peak`` and a corrective sub-movement
    (a 0.2-0.4 s bump of +-0.03-0.08) every 2-6 s; clipped to 0.02..1."""
    t = time_grid(duration_s, dt_s)
    freqs = np.sort(rng.uniform(0.03, 0.35, 3))
    amps = rng.dirichlet(np.ones(3)) * float(rng.uniform(0.3, 0.45))
    target = 0.5 + sum(a * np.sin(2.0 * np.pi * f * t + float(rng.uniform(0.0, 6.3))) for a, f in zip(amps, freqs))
    delay = float(rng.uniform(0.15, 0.3))
    followed = lowpass(
        variable_delay(np.asarray(target), np.full_like(t, delay / dt_s)), dt_s, float(rng.uniform(0.1, 0.25))
    )
    tremor = float(rng.uniform(0.005, 0.015)) * np.sin(2.0 * np.pi * float(rng.uniform(8.0, 12.0)) * t)
    bumps = np.zeros_like(t)
    now = float(rng.uniform(1.0, 4.0))
    while now < duration_s:
        width, size = float(rng.uniform(0.2, 0.4)), float(rng.choice([-1.0, 1.0])) * float(rng.uniform(0.03, 0.08))
        inside = (t >= now) & (t < now + width)
        bumps[inside] += size * np.sin(np.pi * (t[inside] - now) / width) ** 2
        now += float(rng.uniform(2.0, 6.0))
    return np.asarray(peak * np.clip(followed + tremor + bumps, 0.02, 1.0), dtype=np.float64)


def descending_sweep(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Logarithmic sweeps ``0.5 - a cos(phase)`` (a 0.38-0.47 ``peak``) from 1.5-3 Hz down to
    0.02-0.05 Hz over 40-90 s, repeated with a new amplitude (each starts at its low point)."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start = 0.0
    while start < duration_s:
        f0, f1, length = float(rng.uniform(1.5, 3.0)), float(rng.uniform(0.02, 0.05)), float(rng.uniform(40.0, 90.0))
        amp = float(rng.uniform(0.38, 0.47))
        rate = np.log(f1 / f0) / length
        inside = (t >= start) & (t < start + length)
        s = t[inside] - start
        phase = 2.0 * np.pi * f0 * (np.exp(rate * s) - 1.0) / rate
        out[inside] = 0.5 - amp * np.cos(phase)
        start += length
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


BLIND9_PROTOCOLS: dict[str, Protocol] = {
    "endurance_blocks": endurance_blocks,
    "prbs": prbs,
    "overshoot_staircase": overshoot_staircase,
    "human_tracking": human_tracking,
    "descending_sweep": descending_sweep,
}


def with_shakedown(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.4-0.9 s vented, four raised-cosine pulses to 0.97-1 ``peak`` of 1.0-1.4 s each, 0.4 s
    vented, a 0.5 s linear ramp to the protocol's first value, then ``protocol`` [0..peak] to
    ``duration_s``."""
    top = float(rng.uniform(0.97, 1.0))
    lead_in = float(rng.uniform(0.4, 0.9))
    widths = rng.uniform(1.0, 1.4, 4)
    pulses_end = lead_in + float(np.sum(widths))
    lead_s = pulses_end + 0.4 + 0.5
    t = time_grid(lead_s, dt_s)
    lead = np.zeros_like(t)
    start = lead_in
    for w in widths.tolist():
        inside = (t >= start) & (t < start + w)
        lead[inside] = top * 0.5 * (1.0 - np.cos(2.0 * np.pi * (t[inside] - start) / w))
        start += w
    body = np.clip(BLIND9_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    ramp = t >= pulses_end + 0.4
    lead[ramp] = float(body[0]) / peak * (t[ramp] - pulses_end - 0.4) / 0.5
    lead = peak * np.clip(lead, 0.0, 1.0)
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
