"""Test protocols after the seed papers, as pressure-command sequences [bar] at the plant rate.

Each scenario is ``f(duration_s, dt_s, rng) -> commands``; the random generator varies phases
and amplitudes a little so that different seeds give different (but comparable) recordings.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

Scenario = Callable[[float, float, np.random.Generator], np.ndarray]


def _time(duration_s: float, dt_s: float) -> np.ndarray:
    return np.arange(int(round(duration_s / dt_s))) * dt_s


def triangles(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Ai2019: triangles 0 -> 1, 2, 3, 4 bar at 0.05 Hz (20 s each), repeated to fill."""
    t = _time(duration_s, dt_s)
    period = 20.0
    cycle = (t // period).astype(int)
    peak = 1.0 + (cycle % 4)
    return peak * (1.0 - np.abs(2.0 * ((t % period) / period) - 1.0))


def sines(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Wu2025: sinusoids at several rates and amplitudes around 2 bar.

    Segments of whole cycles, each starting and ending at the offset, so the command never
    steps between segments (a step would test the valve, not the hysteresis).
    """
    settings = [(0.05, 1.6), (0.2, 1.2), (0.5, 1.0), (1.0, 0.8), (0.1, 1.8), (0.35, 1.4)]
    segment_s = duration_s / len(settings)
    pieces = []
    for index in rng.permutation(len(settings)):
        frequency, amplitude = settings[index]
        cycles = max(1, int(round(segment_s * frequency)))
        local = np.arange(int(round(cycles / frequency / dt_s))) * dt_s
        pieces.append(2.0 + amplitude * np.sin(2 * np.pi * frequency * local))
    sequence = np.concatenate(pieces)
    steps = int(round(duration_s / dt_s))
    return np.tile(sequence, int(np.ceil(steps / sequence.size)))[:steps]


def amplitude_ramp(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Zhou2022 eq 33: a sine whose amplitude ramps up, holds for a tenth, ramps down."""
    t = _time(duration_s, dt_s)
    frequency = 0.25
    x = t / duration_s
    envelope = np.where(x < 0.45, x / 0.45, np.where(x < 0.55, 1.0, (1.0 - x) / 0.45))
    return 2.0 + 1.8 * envelope * np.sin(2 * np.pi * frequency * t)


def holds(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Constant-pressure holds of 15-25 s at random levels, reached by 2 s ramps."""
    t = _time(duration_s, dt_s)
    out = np.empty_like(t)
    level, start = 0.0, 0.0
    while start < duration_s:
        target = float(rng.uniform(0.5, 3.8))
        hold = float(rng.uniform(15.0, 25.0))
        mask = (t >= start) & (t < start + 2.0 + hold)
        ramp = np.clip((t[mask] - start) / 2.0, 0.0, 1.0)
        out[mask] = level + (target - level) * ramp
        level, start = target, start + 2.0 + hold
    return out


def forc(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Schreiber: first-order reversal curves, 0 -> rising maxima -> 0, at 0.4 bar/s."""
    rate = 0.4
    peaks = np.linspace(0.4, 4.0, 10)
    pieces = [np.concatenate([np.arange(0.0, p, rate * dt_s), np.arange(p, 0.0, -rate * dt_s)]) for p in peaks]
    sweep = np.concatenate(pieces)
    reps = int(np.ceil(duration_s / dt_s / sweep.size))
    return np.tile(sweep, reps)[: int(round(duration_s / dt_s))]


def mixed(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """All of the above in equal parts, joined by 2 s ramps."""
    parts = [triangles, sines, amplitude_ramp, holds, forc]
    ramp_s = 2.0
    share = max(1.0, (duration_s - ramp_s * (len(parts) - 1)) / len(parts))
    pieces: list[np.ndarray] = []
    for part in parts:
        piece = part(share, dt_s, rng)
        if pieces:
            steps = int(round(ramp_s / dt_s))
            pieces.append(np.linspace(pieces[-1][-1], piece[0], steps, endpoint=False))
        pieces.append(piece)
    return np.concatenate(pieces)[: int(round(duration_s / dt_s))]


STEPPED_SINE_FREQUENCIES_HZ = (0.1, 0.2, 0.35, 0.6, 1.0, 1.7, 3.0)


def stepped_sine(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """PAMInertial's frequency response: sinusoids of 0.6 bar around 2 bar, one frequency after another.

    Frequencies :data:`STEPPED_SINE_FREQUENCIES_HZ` in ascending order, each for an equal share of
    the duration in whole cycles (at least 3: one to settle, two to analyse), each starting and
    ending at the offset so the command never steps. The amplitude varies by +-10 % with the seed.
    The fastest segment asks 11 bar/s of the valve, below its 40 bar/s rate limit.
    """
    offset, amplitude = 2.0, 0.6 * float(rng.uniform(0.9, 1.1))
    share = duration_s / len(STEPPED_SINE_FREQUENCIES_HZ)
    pieces = []
    for frequency in STEPPED_SINE_FREQUENCIES_HZ:
        cycles = max(3, int(share * frequency))
        local = np.arange(int(round(cycles / frequency / dt_s))) * dt_s
        pieces.append(offset + amplitude * np.sin(2 * np.pi * frequency * local))
    sequence = np.concatenate(pieces)
    steps = int(round(duration_s / dt_s))
    if sequence.size < steps:
        sequence = np.concatenate([sequence, np.full(steps - sequence.size, offset)])
    return sequence[:steps]


def isotonic(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Static force map: slow triangles 0.3 -> 5.5 -> 0.3 bar, ten over the duration (at least 40 s each).

    Quasi-static (0.26 bar/s at 400 s), so the load cell reads the muscle's static force minus its
    braid friction. With ``--effect load_dependence`` the load steps through Ai2019's five masses,
    two triangles per mass: isotonic curves at five forces, the data a static force law is fitted on.
    """
    t = _time(duration_s, dt_s)
    period = max(40.0, duration_s / 10.0)
    return 0.3 + 5.2 * (1.0 - np.abs(2.0 * ((t % period) / period) - 1.0))


ISOMETRIC_CONTRACTION_RATIOS = (0.0, 0.04, 0.08, 0.12, 0.16, 0.20)


def isometric_contraction_ratio(t: float, duration_s: float) -> float:
    """Where the isometric protocol clamps the muscle at ``t``: one ratio per sixth of the duration."""
    index = min(int(t / duration_s * len(ISOMETRIC_CONTRACTION_RATIOS)), len(ISOMETRIC_CONTRACTION_RATIOS) - 1)
    return ISOMETRIC_CONTRACTION_RATIOS[index]


def isometric(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """PAMInertial sec 2.1's isometric test: the muscle clamped at six contraction ratios
    (:data:`ISOMETRIC_CONTRACTION_RATIOS`, the recorder holds it there), a pressure triangle
    0.3 -> 5.5 -> 0.3 bar at each; the load cell then reads the static force itself."""
    t = _time(duration_s, dt_s)
    period = duration_s / len(ISOMETRIC_CONTRACTION_RATIOS)
    return 0.3 + 5.2 * (1.0 - np.abs(2.0 * ((t % period) / period) - 1.0))


def decaying_sines(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Schreiber Fig 7's wiping-out test: one sine cycle over the full 0-4 bar from the 2 bar middle,
    then ten whose amplitude falls linearly to zero, the whole sequence twice. The full cycle wipes
    out what came before, so both halves must give the same output."""
    t = _time(duration_s, dt_s)
    half = duration_s / 2.0
    local = t % half
    frequency = 11.0 / half
    cycles = local * frequency
    envelope = np.where(cycles < 1.0, 1.0, np.clip(1.0 - (cycles - 1.0) / 10.0, 0.0, 1.0))
    return 2.0 + 2.0 * envelope * np.sin(2 * np.pi * frequency * local)


MINOR_LOOP_LOW_BAR, MINOR_LOOP_HIGH_BAR = 2.0, 2.5
MINOR_LOOP_CORNERS_BAR = (
    (2.0, 4.0, 0.5)
    + (MINOR_LOOP_LOW_BAR, MINOR_LOOP_HIGH_BAR) * 3
    + (MINOR_LOOP_LOW_BAR,)
    + (0.0, 3.5)
    + (MINOR_LOOP_LOW_BAR, MINOR_LOOP_HIGH_BAR) * 3
    + (MINOR_LOOP_LOW_BAR,)
)


def minor_loop_corner_times(duration_s: float) -> np.ndarray:
    """When :func:`minor_loops` reaches each of :data:`MINOR_LOOP_CORNERS_BAR` [s]."""
    steps = np.abs(np.diff(MINOR_LOOP_CORNERS_BAR))
    return np.concatenate([[0.0], np.cumsum(steps)]) * duration_s / float(steps.sum())


def minor_loops(duration_s: float, dt_s: float, rng: np.random.Generator) -> np.ndarray:
    """Schreiber Fig 8's congruency test: the same small minor loop (2.0 <-> 2.5 bar, three times)
    after two different histories: arriving at 2 bar from below (4 -> 0.5 -> 2) and from above
    (0 -> 3.5 -> 2). One ramp rate throughout; corners in :data:`MINOR_LOOP_CORNERS_BAR`. The
    loop is small so that the larger friction elements keep each history (an offset between the
    loops); a Preisach-type system then gives loops of the same shape."""
    return np.interp(_time(duration_s, dt_s), minor_loop_corner_times(duration_s), MINOR_LOOP_CORNERS_BAR)


SCENARIOS: dict[str, Scenario] = {
    "triangles": triangles,
    "sines": sines,
    "ramp": amplitude_ramp,
    "holds": holds,
    "forc": forc,
    "mixed": mixed,
    "stepped-sine": stepped_sine,
    "isotonic": isotonic,
    "isometric": isometric,
    "decaying-sines": decaying_sines,
    "minor-loops": minor_loops,
}
