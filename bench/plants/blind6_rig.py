"""The blind6 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side (:func:`spool_valve`, part of every core): a proportional spool valve whose
muscle pressure answers the set pressure as a second-order system (6-14 Hz, damping 0.55-0.8,
so a fast step overshoots a little). The recorded input is not the set pressure but the
muscle's pressure read through the transducer's *snubber* (a sintered restrictor on its port
against pressure spikes: a first-order lag of 4-15 ms, :func:`snubbed_reading`).

Stroke side (:func:`stroke_reading`): the shop compressor beside the rig shakes the frame while
it runs (bursts of 23-31 Hz vibration, 8-25 um, running 8-25 s, resting 15-40 s, sampled at the
record's rate so aliased at the low rates) and the DAQ's multiplexer leaks a little of the
pressure channel into the stroke channel (crosstalk of 10-40 um at full pressure). In the
recording (:func:`aperture_jitter`) the DAQ's sampling instants jitter (20-100 us RMS, its USB frames polled) while
the time stamps stay nominal, so every channel reads an error of its speed times the jitter.

All the confounds are drawn with the plant parameters: the same in a record with its effect on
and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass, resonance

Array = NDArray[np.float64]
G_MS2 = 9.81
KELVIN = 273.15


def spool_valve(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Muscle pressure [bar] for the set pressure ``u`` [bar]: a second-order response
    (``valve_hz``, ``valve_zeta``) from rest, never below 0."""
    return np.asarray(np.clip(resonance(u, dt_s, p["valve_hz"], p["valve_zeta"]), 0.0, None), dtype=np.float64)


def snubbed_reading(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The recorded input [bar]: the muscle's pressure (:func:`spool_valve` of the set pressure)
    through the transducer port's snubber lag ``snubber_tau_s``."""
    return lowpass(spool_valve(u, dt_s, p), dt_s, p["snubber_tau_s"])


def compressor_bursts(t: Array, p: dict[str, float]) -> Array:
    """Frame vibration [mm] while the compressor runs: its schedule drawn from ``vib_seed``,
    each run ramping in and out over 1 s."""
    rng = np.random.default_rng(int(p["vib_seed"]))
    envelope = np.zeros_like(t)
    now = float(rng.uniform(0.0, 30.0))
    while now < t[-1]:
        run = float(rng.uniform(8.0, 25.0))
        envelope = np.maximum(envelope, np.clip(np.minimum(t - now, now + run - t), 0.0, 1.0))
        now += run + float(rng.uniform(15.0, 40.0))
    phase = 2.0 * math.pi * p["vib_hz"] * t + p["vib_phase"]
    return np.asarray(p["vib_mm"] * envelope * np.sin(phase), dtype=np.float64)


def stroke_reading(x: Array, u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke transducer's reading [mm] of a contraction ``x`` [mm] under the set pressure
    ``u`` [bar]: the compressor's vibration bursts and the multiplexer's crosstalk added."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    crosstalk = p["crosstalk_mm"] * spool_valve(u, dt_s, p) / p["peak"]
    return np.asarray(x + compressor_bursts(t, p) + crosstalk, dtype=np.float64)


def aperture_jitter(x: Array, dt_s: float, jitter_s: Array) -> Array:
    """``x`` sampled ``jitter_s`` [s] off its nominal instants (to first order: its slope times
    the jitter)."""
    return np.asarray(x + np.gradient(x, dt_s) * jitter_s, dtype=np.float64)


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    return {
        "peak": peak,
        "valve_hz": rng.uniform(6.0, 14.0),
        "valve_zeta": rng.uniform(0.55, 0.8),
        "snubber_tau_s": rng.uniform(0.004, 0.015),
        "vib_seed": float(rng.integers(0, 2**31)),
        "vib_hz": rng.uniform(23.0, 31.0),
        "vib_mm": rng.uniform(0.008, 0.025),
        "vib_phase": rng.uniform(0.0, 2.0 * math.pi),
        "crosstalk_mm": rng.uniform(0.01, 0.04),
        "jitter_s": rng.uniform(0.00002, 0.0001),
    }
