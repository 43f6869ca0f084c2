"""Five excitation protocols [bar, 0..peak] unlike the other families', each after a preconditioning.

What a lab qualifying muscles for industrial and medical use would run: a *relay autotuning*
test (Astrom-Hagglund: the valve switched between two levels by a relay with a small hysteresis
on the (modelled) stroke, so it settles into a limit cycle of its own period; the operating
point moved every 20-40 s); *fatigue cycling with reference cycles* (a fast sine between two
levels for 15-30 s, then one slow full-range reference triangle, as durability rigs do to track
the muscle's drift); a *DMA amplitude sweep* (a sine of fixed frequency about mid pressure whose
amplitude steps up logarithmically, 3-5 cycles per level, and back down: the Payne-effect test
of elastomers); an *oscillometric cuff* profile (a quick inflation to the top, then deflation in
small bleed steps held 1-2.5 s each, then vented and rested, as a blood-pressure cuff or a
compression garment does); and an *ISO 230-2 bidirectional* positioning test (5-9 targets
approached one by one upwards with dwells, an overrun past the last, then downwards, every
target reached from both sides).

Every record starts vented (0.5-1 s) and is *preconditioned* in its first ~6 s
(:func:`with_preconditioning`): three haversine cycles 0 -> 0.97-1 ``peak`` -> 0 of 1.0-1.6 s
each (the Mullins preconditioning elastomer tests begin with), 0.3 s vented and a 0.5 s
raised-cosine blend into the protocol's first value.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass
from bench.plants.grids import knotted, time_grid

Array = NDArray[np.float64]
Protocol = Callable[[float, float, float, np.random.Generator], Array]


def relay_autotune(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A relay between ``c - d`` and ``c + d`` (``c`` 0.35-0.65, ``d`` 0.2-0.33 ``peak``)
    switching when a model of the stroke (a first-order lag of 0.3-1.2 s after a dead time of
    0.1-0.4 s, the loop's valve, hose and sensor) crosses ``c`` +- a hysteresis of 0.02-0.05
    ``peak``; ``c`` and ``d`` redrawn every 20-40 s; the valve's steps smoothed over 30 ms."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    tau, eps = float(rng.uniform(0.3, 1.2)), float(rng.uniform(0.02, 0.05))
    keep = float(np.exp(-dt_s / tau))
    dead = deque([0.0] * max(int(round(float(rng.uniform(0.1, 0.4)) / dt_s)), 1))  # the levels on their way
    model, high, next_change = 0.0, True, 0.0
    centre = amp = 0.0
    for i, now in enumerate(t.tolist()):
        if now >= next_change:
            centre, amp = float(rng.uniform(0.35, 0.65)), float(rng.uniform(0.2, 0.33))
            next_change = now + float(rng.uniform(20.0, 40.0))
        level = centre + amp if high else centre - amp
        dead.append(level)
        arrived = dead.popleft()
        model = arrived + (model - arrived) * keep
        if high and model > centre + eps:
            high = False
        elif not high and model < centre - eps:
            high = True
        out[i] = level
    return np.asarray(peak * np.clip(lowpass(out, dt_s, 0.03), 0.0, 1.0), dtype=np.float64)


def fatigue_reference_cycles(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Blocks: a sine at 0.5-2 Hz between 0.2-0.4 and 0.6-0.85 ``peak`` for 15-30 s (starting at
    its low level), then a reference triangle 0.02 -> 1 -> 0.02 ``peak`` of 6-10 s."""
    knots_t, pieces = 0.0, []
    t = time_grid(duration_s, dt_s)
    out = np.zeros_like(t)
    while knots_t < duration_s:
        lo, hi, f = float(rng.uniform(0.2, 0.4)), float(rng.uniform(0.6, 0.85)), float(rng.uniform(0.5, 2.0))
        cycling = np.round(float(rng.uniform(15.0, 30.0)) * f) / f
        ref = float(rng.uniform(6.0, 10.0))
        pieces.append((knots_t, lo, hi, f, cycling, ref))
        knots_t += cycling + ref
    for start, lo, hi, f, cycling, ref in pieces:
        s = t - start
        sine = (s >= 0.0) & (s < cycling)
        out[sine] = lo + (hi - lo) * 0.5 * (1.0 - np.cos(2.0 * np.pi * f * s[sine]))
        tri = (s >= cycling) & (s < cycling + ref)
        phase = (s[tri] - cycling) / ref
        out[tri] = 0.02 + 0.98 * (1.0 - np.abs(2.0 * phase - 1.0))
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def dma_amplitude_sweep(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """A sine at 0.2-1 Hz about 0.45-0.55 ``peak`` whose amplitude steps up over 6-10 levels
    from 0.02-0.04 to 0.4-0.45 ``peak`` (log-spaced), 3-5 whole cycles per level, and back down;
    repeated with a new frequency."""
    t = time_grid(duration_s, dt_s)
    out = np.empty_like(t)
    start = 0.0
    while start < duration_s:
        f, mean = float(rng.uniform(0.2, 1.0)), float(rng.uniform(0.45, 0.55))
        levels = np.geomspace(float(rng.uniform(0.02, 0.04)), float(rng.uniform(0.4, 0.45)), int(rng.integers(6, 11)))
        for amp in np.concatenate([levels, levels[-2::-1]]).tolist():
            length = int(rng.integers(3, 6)) / f
            s = t - start
            inside = (s >= 0.0) & (s < length)
            out[inside] = mean + amp * np.sin(2.0 * np.pi * f * s[inside])
            start += length
    return np.asarray(peak * np.clip(out, 0.0, 1.0), dtype=np.float64)


def cuff_step_deflation(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Cycles: inflation in 1-2 s to 0.85-1 ``peak``, bleed steps of 0.03-0.06 ``peak`` (each
    in 0.15 s) held 1-2.5 s down to 0.05-0.15 ``peak``, a vent in 0.5 s, 2-5 s vented."""
    knots_t, knots_u = [0.0], [0.0]
    while knots_t[-1] < duration_s:
        top, bottom = float(rng.uniform(0.85, 1.0)), float(rng.uniform(0.05, 0.15))
        knots_t.append(knots_t[-1] + float(rng.uniform(1.0, 2.0)))
        knots_u.append(top)
        level = top
        while level > bottom:
            knots_t += [knots_t[-1] + float(rng.uniform(1.0, 2.5)), 0.0]
            knots_t[-1] = knots_t[-2] + 0.15
            level = max(level - float(rng.uniform(0.03, 0.06)), bottom)
            knots_u += [knots_u[-1], level]
        knots_t += [knots_t[-1] + 0.5, 0.0]
        knots_t[-1] = knots_t[-2] + float(rng.uniform(2.0, 5.0))
        knots_u += [0.0, 0.0]
    return peak * knotted(duration_s, dt_s, knots_t, knots_u)


def iso230_bidirectional(duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """Runs of an ISO 230-2 test: 5-9 targets (0.1-0.9 ``peak``, a little uneven) approached
    upwards at 0.2-0.5 ``peak``/s with dwells of 1-3 s, an overrun of 0.04-0.08 ``peak`` past
    the last, then approached downwards, an overrun below the first; new targets per run."""
    knots_t, knots_u = [0.0], [0.05]
    while knots_t[-1] < duration_s:
        n = int(rng.integers(5, 10))
        targets = np.linspace(0.1, 0.9, n) + rng.uniform(-0.3, 0.3, n) * 0.8 / (n - 1) / 2.0
        speed, over = float(rng.uniform(0.2, 0.5)), float(rng.uniform(0.04, 0.08))
        for level in [*targets.tolist(), float(targets[-1]) + over, *targets[::-1].tolist(), float(targets[0]) - over]:
            knots_t.append(knots_t[-1] + abs(level - knots_u[-1]) / speed + 1e-3)
            knots_u.append(level)
            knots_t.append(knots_t[-1] + float(rng.uniform(1.0, 3.0)))
            knots_u.append(level)
    return np.asarray(peak * np.clip(knotted(duration_s, dt_s, knots_t, knots_u), 0.0, 1.0), dtype=np.float64)


BLIND7_PROTOCOLS: dict[str, Protocol] = {
    "relay_autotune": relay_autotune,
    "fatigue_reference_cycles": fatigue_reference_cycles,
    "dma_amplitude_sweep": dma_amplitude_sweep,
    "cuff_step_deflation": cuff_step_deflation,
    "iso230_bidirectional": iso230_bidirectional,
}


def with_preconditioning(protocol: str, duration_s: float, dt_s: float, peak: float, rng: np.random.Generator) -> Array:
    """0.5-1 s vented, three haversine cycles to 0.97-1 ``peak`` of 1.0-1.6 s each, 0.3 s
    vented, a 0.5 s raised-cosine blend to the protocol's first value, then ``protocol``
    [0..peak] to ``duration_s``."""
    vented = float(rng.uniform(0.5, 1.0))
    cycles = [float(rng.uniform(1.0, 1.6)) for _ in range(3)]
    top = float(rng.uniform(0.97, 1.0)) * peak
    lead_s = vented + sum(cycles) + 0.8
    body = np.clip(BLIND7_PROTOCOLS[protocol](max(duration_s - lead_s, 0.0) + 1.0, dt_s, peak, rng), 0.0, peak)
    t = time_grid(lead_s, dt_s)
    lead = np.zeros_like(t)
    start = vented
    for length in cycles:
        inside = (t >= start) & (t < start + length)
        lead[inside] = top * 0.5 * (1.0 - np.cos(2.0 * np.pi * (t[inside] - start) / length))
        start += length
    blend = 0.5 * (1.0 - np.cos(np.pi * np.clip((t - (lead_s - 0.5)) / 0.5, 0.0, 1.0)))
    lead = lead + blend * float(body[0])
    return np.asarray(np.concatenate([lead, body])[: int(round(duration_s / dt_s))], dtype=np.float64)
