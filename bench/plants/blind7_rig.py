"""The blind7 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side: a PWM-driven proportional valve (:func:`valve_pressure`: a first-order lag of
8-25 ms and the ripple of its solenoid's PWM, 90-210 Hz and 0.3-1 % of the peak, sampled at the
record's rate so aliased) whose outlet is where the pressure transducer sits; the muscle gets
that pressure through its hose (:func:`muscle_pressure`: a further lag of 10-30 ms), so the
recorded input *leads* the muscle's pressure. The transducer's reading carries its own noise
(2-6 mbar) and the 12-bit converter's step (2-5 mbar, :func:`pressure_reading`).

Stroke side (:func:`stroke_reading`): the DAQ's multiplexer converts the stroke channel
0.1-0.6 ms after the pressure channel (a channel skew: the stroke sample is a little later than
its time stamp says), and the stroke amplifier has *popcorn* (random telegraph) noise: an offset
of 5-15 um switching on and off at random (0.05-0.3 switches per second).

All the confounds are drawn with the plant parameters (seeded by them): the same in a record
with its effect on and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass

Array = NDArray[np.float64]


def _ripple(u: Array, dt_s: float, p: dict[str, float], tau_s: float = 0.0) -> Array:
    """The PWM ripple [bar] (fading in over the first 5 % of the peak) after a first-order lag
    ``tau_s`` in continuous time (its gain and phase at ``pwm_hz``: sampling would alias it)."""
    t = np.arange(u.size, dtype=np.float64) * dt_s
    open_share = np.clip(lowpass(u, dt_s, p["valve_tau_s"]) / (0.05 * p["peak"]), 0.0, 1.0)
    w = 2.0 * math.pi * p["pwm_hz"]
    gain, phase = 1.0 / math.hypot(1.0, w * tau_s), math.atan(w * tau_s)
    return np.asarray(p["ripple_bar"] * gain * open_share * np.sin(w * t + p["pwm_phase"] - phase), dtype=np.float64)


def valve_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] at the valve's outlet for the set pressure ``u`` [bar]: a first-order lag
    ``valve_tau_s`` plus the PWM ripple, never below 0."""
    return np.asarray(np.clip(lowpass(u, dt_s, p["valve_tau_s"]) + _ripple(u, dt_s, p), 0.0, None), dtype=np.float64)


def muscle_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] in the muscle: the valve's outlet pressure through the hose's lag
    ``hose_tau_s`` (the ripple through the hose's continuous-time gain), never below 0."""
    smooth = lowpass(lowpass(u, dt_s, p["valve_tau_s"]), dt_s, p["hose_tau_s"])
    return np.asarray(np.clip(smooth + _ripple(u, dt_s, p, p["hose_tau_s"]), 0.0, None), dtype=np.float64)


def pressure_reading(pressure: Array, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The transducer's reading [bar] of ``pressure``: its noise ``input_noise_bar`` and the
    converter's step ``input_step_bar``."""
    noisy = pressure + rng.normal(0.0, p["input_noise_bar"], pressure.size)
    return np.asarray(np.round(noisy / p["input_step_bar"]) * p["input_step_bar"], dtype=np.float64)


def popcorn_noise(n: int, dt_s: float, p: dict[str, float]) -> Array:
    """Random telegraph offset [mm] of the stroke amplifier: 0 or ``rtn_mm``, switching at
    exponential intervals of mean ``1 / rtn_rate_hz`` (seeded by ``rtn_seed``)."""
    rng = np.random.default_rng(int(p["rtn_seed"]))
    duration = n * dt_s
    switches: list[float] = []
    now = float(rng.exponential(1.0 / p["rtn_rate_hz"]))
    while now < duration:
        switches.append(now)
        now += float(rng.exponential(1.0 / p["rtn_rate_hz"]))
    t = np.arange(n, dtype=np.float64) * dt_s
    state = np.searchsorted(np.asarray(switches, dtype=np.float64), t, side="right") % 2
    return np.asarray(p["rtn_mm"] * state, dtype=np.float64)


def stroke_reading(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke channel's reading [mm] of a contraction ``x`` [mm]: converted ``skew_s`` after
    its time stamp (the multiplexer's channel skew), popcorn noise added."""
    idx = np.arange(x.size, dtype=np.float64)
    skewed = np.interp(idx + p["skew_s"] / dt_s, idx, x)
    return np.asarray(skewed + popcorn_noise(x.size, dt_s, p), dtype=np.float64)


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    return {
        "peak": peak,
        "valve_tau_s": rng.uniform(0.008, 0.025),
        "pwm_hz": rng.uniform(90.0, 210.0),
        "pwm_phase": rng.uniform(0.0, 2.0 * math.pi),
        "ripple_bar": rng.uniform(0.003, 0.01) * peak,
        "hose_tau_s": rng.uniform(0.01, 0.03),
        "input_noise_bar": rng.uniform(0.002, 0.006),
        "input_step_bar": rng.uniform(0.002, 0.005),
        "skew_s": rng.uniform(0.0001, 0.0006),
        "rtn_mm": rng.uniform(0.005, 0.015),
        "rtn_rate_hz": rng.uniform(0.05, 0.3),
        "rtn_seed": float(rng.integers(0, 2**31)),
    }
