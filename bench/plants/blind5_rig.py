"""The blind5 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side (:func:`regulator`, part of every core): the supply regulator's own first-order
lag (25-70 ms) and the small hysteresis of its diaphragm's friction (a play of 0.4-1.2 % of the
peak pressure). The recorded input is the pressure transducer's reading of the command
(:func:`transducer_reading`): a gain error of +-0.6-2 % and an offset of +-5-15 mbar.

Stroke side (:func:`stroke_reading`): the mount settling slowly under the muscle after it is
clamped (an exponential sag of 0.015-0.04 mm over 15-40 s) and mains hum on the transducer's
cable (0.004-0.012 mm at 49.95-50.05 Hz, sampled at the record's rate, so aliased below
100 Hz). In the recording (:func:`dropped_frames`) the DAQ now and then drops 1-3 frames and
repeats the last one on every channel (0.1-0.4 % of the frames).

All the confounds are drawn with the plant parameters: the same in a record with its effect on
and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass

Array = NDArray[np.float64]
G_MS2 = 9.81


def diaphragm_play(x: Array, radius: float) -> Array:
    """A play of half-width ``radius`` (the regulator diaphragm's friction), starting on ``x[0]``."""
    out = np.empty_like(x)
    y = float(x[0])
    for i, xi in enumerate(x.tolist()):
        if y < xi - radius:
            y = xi - radius
        elif y > xi + radius:
            y = xi + radius
        out[i] = y
    return out


def regulator(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Muscle pressure [bar] for the set pressure ``u`` [bar]: the diaphragm's play (half-width
    ``reg_play_share`` of the peak) after the regulator's lag ``tau_reg_s``, never below 0."""
    lagged = lowpass(u, dt_s, p["tau_reg_s"])
    return np.asarray(np.clip(diaphragm_play(lagged, p["reg_play_share"] * p["peak"]), 0.0, None), dtype=np.float64)


def transducer_reading(u: Array, p: dict[str, float]) -> Array:
    """The pressure transducer's reading [bar] of the set pressure ``u``: gain error and offset,
    zero while vented (the DAQ's zero is taken vented, so the offset grows in with the pressure)."""
    v = np.clip(u / p["peak"], 0.0, 1.0)
    return np.asarray(u * (1.0 + p["p_gain_error"]) + p["p_offset_bar"] * v, dtype=np.float64)


def stroke_reading(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke transducer's reading [mm] of a contraction ``x`` [mm]: the mount's settling
    sag and aliased mains hum added."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    settle = -p["settle_mm"] * -np.expm1(-t / p["settle_tau_s"])
    hum = p["hum_mm"] * np.sin(2.0 * math.pi * p["mains_hz"] * t + p["hum_phase"])
    return np.asarray(x + settle + hum, dtype=np.float64)


def dropped_frames(n: int, rng: np.random.Generator, share: float) -> NDArray[np.intp]:
    """Indices of frames the DAQ dropped and replaced by the frame before (runs of 1-3, about
    ``share`` of the frames, never the first)."""
    starts = np.flatnonzero(rng.random(n) < share / 2.0)
    runs = rng.integers(1, 4, starts.size)
    idx = [np.arange(s, s + k) for s, k in zip(starts.tolist(), runs.tolist())]
    flat = np.concatenate(idx) if idx else np.zeros(0, dtype=np.intp)
    return np.asarray(np.unique(np.clip(flat, 1, n - 1)), dtype=np.intp)


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    return {
        "peak": peak,
        "tau_reg_s": rng.uniform(0.025, 0.07),
        "reg_play_share": rng.uniform(0.004, 0.012),
        "p_gain_error": float(rng.choice([-1.0, 1.0]) * rng.uniform(0.006, 0.02)),
        "p_offset_bar": float(rng.choice([-1.0, 1.0]) * rng.uniform(0.005, 0.015)),
        "settle_mm": rng.uniform(0.015, 0.04),
        "settle_tau_s": rng.uniform(15.0, 40.0),
        "hum_mm": rng.uniform(0.004, 0.012),
        "mains_hz": rng.uniform(49.95, 50.05),
        "hum_phase": rng.uniform(0.0, 2.0 * math.pi),
        "drop_share": rng.uniform(0.001, 0.004),
    }
