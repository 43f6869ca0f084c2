"""The blind9 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side (:func:`muscle_pressure`): the muscle is filled and vented by a pair of fast
*on/off* solenoid valves driven by PWM at a carrier of 23-47 Hz; the controller turns the set
pressure into a duty through its calibration with the timer's resolution (9-10 bits: the mean
pressure moves in steps of ``peak / 2^bits``), and the muscle's volume averages the pulses (a
first-order fill of 40-90 ms) leaving a triangular *carrier ripple* of 0.1-0.4 % of the peak at
50 % duty (``4 d (1 - d)`` of it at duty ``d``) at the valve manifold, sampled at the record's
rate (aliased); the muscle's own volume smooths the carrier away.

The recorded input is a transducer on the valve manifold (the muscle's pressure plus the
carrier's ripple; an effect may put a line between them) read through an instrumentation amplifier whose
output *slews* at most 8-16 x the peak per second (:func:`slew_limited`), a first-order RC
anti-alias filter at 0.15-0.3 x the sample rate, then the converter's noise (2-5 mbar) and step
(1.5-4 mbar) (:func:`pressure_reading`).

Stroke side (:func:`stroke_reading`): a *wire-wound string potentiometer*: its wiper steps from
turn to turn of the winding (a pitch of 8-20 um), each turn off its nominal place by up to 0.3
pitches (winding irregularity); its reading is ratiometric to a 5 V rail that *dips* while the
solenoids draw current (0.04-0.15 % per unit duty, through the rail's 20-60 ms filter: a gain
error that follows the input, a decoy); then the stroke channel's RC anti-alias filter (its
corner 3-8 % off the pressure channel's).

In the recording the load cell's strain-gauge bridge has a thermal zero shift (5-20 g/K of the
temperature's change since the start: the load column reads a little of the temperature column;
:func:`load_cell_zero_shift`).

All the confounds are drawn with the plant parameters (seeded by them): the same in a record
with its effect on and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass

Array = NDArray[np.float64]


def duty(u: Array, p: dict[str, float]) -> Array:
    """The PWM duty (0..1) for the set pressure ``u`` [bar], on the timer's ``pwm_bits`` grid."""
    levels = 2.0 ** p["pwm_bits"]
    return np.asarray(np.round(np.clip(u / p["peak"], 0.0, 1.0) * levels) / levels, dtype=np.float64)


def carrier_ripple(d: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The ripple [bar] the averaged pulses leave: a unit triangle at ``carrier_hz`` (phase
    ``carrier_phase``) times ``ripple_share`` x the peak x ``4 d (1 - d)``, read at the samples."""
    t = np.arange(d.size, dtype=np.float64) * dt_s
    phase = (t * p["carrier_hz"] + p["carrier_phase"]) % 1.0
    tri = 4.0 * np.abs(phase - 0.5) - 1.0
    return np.asarray(p["ripple_share"] * p["peak"] * 4.0 * d * (1.0 - d) * tri, dtype=np.float64)


def muscle_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] in the muscle for the set pressure ``u`` [bar]: the quantised duty times the
    peak through the volume's fill lag ``fill_tau_s`` (the muscle's volume smooths the carrier
    away; the manifold keeps it, :func:`manifold_pressure`)."""
    return lowpass(duty(u, p) * p["peak"], dt_s, p["fill_tau_s"])


def manifold_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] at the valve manifold: the muscle's plus the carrier ripple; never below 0."""
    ripple = carrier_ripple(duty(u, p), dt_s, p)
    return np.asarray(np.clip(muscle_pressure(u, dt_s, p) + ripple, 0.0, None), dtype=np.float64)


def rc_filter(x: Array, dt_s: float, corner_hz: float) -> Array:
    """``x`` through a first-order RC low-pass at ``corner_hz`` (exact for a signal held over
    each sample), at rest on ``x[0]``."""
    return lowpass(x, dt_s, 1.0 / (2.0 * math.pi * corner_hz))


def slew_limited(x: Array, dt_s: float, rate: float) -> Array:
    """``x`` followed at most ``rate`` [units/s] (an amplifier's slew limit), from ``x[0]``."""
    step = rate * dt_s
    out = np.empty(x.size)
    now = float(x[0])
    for i, target in enumerate(x.tolist()):
        now += min(max(target - now, -step), step)
        out[i] = now
    return out


def recorded_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The pressure channel [bar] for the set pressure ``u`` [bar], noise-free: the manifold's
    pressure through the amplifier's slew limit and the channel's RC anti-alias filter."""
    slewed = slew_limited(manifold_pressure(u, dt_s, p), dt_s, p["amp_slew_per_s"] * p["peak"])
    return rc_filter(slewed, dt_s, p["aa_share"] / dt_s)


def pressure_reading(pressure: Array, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The converter's reading [bar]: its noise ``input_noise_bar`` and step ``input_step_bar``."""
    noisy = pressure + rng.normal(0.0, p["input_noise_bar"], pressure.size)
    return np.asarray(np.round(noisy / p["input_step_bar"]) * p["input_step_bar"], dtype=np.float64)


def winding_error_table(p: dict[str, float], turns: int) -> Array:
    """Each turn's displacement from its nominal place [pitches], ``U(-1, 1) x pot_irregularity``."""
    rng = np.random.default_rng(int(p["pot_seed"]))
    return np.asarray(rng.uniform(-1.0, 1.0, turns) * p["pot_irregularity"], dtype=np.float64)


def wire_wound(x: Array, p: dict[str, float]) -> Array:
    """The wiper's reading [mm] of the stroke ``x`` [mm]: the centre of the turn it touches (pitch
    ``pot_pitch_mm``, the winding starting ``pot_origin`` pitches below zero), moved by that
    turn's winding error."""
    pitch = p["pot_pitch_mm"]
    k = np.floor(x / pitch + p["pot_origin"]).astype(np.int64)
    table = winding_error_table(p, int(k.max()) + 2 if k.size else 2)
    k = np.clip(k, 0, table.size - 1)
    return np.asarray((k + 0.5 - p["pot_origin"] + table[k]) * pitch, dtype=np.float64)


def rail_dip(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The 5 V rail's relative dip (0..~0.0015) while the solenoids draw current: ``rail_dip``
    x the duty, through the rail's ``rail_tau_s`` filter."""
    return np.asarray(p["rail_dip"] * lowpass(duty(u, p), dt_s, p["rail_tau_s"]), dtype=np.float64)


def stroke_reading(x: Array, u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke channel [mm] of a contraction ``x`` [mm] for the set pressure ``u`` [bar],
    noise-free: the wire-wound pot's reading, scaled by the rail's dip (ratiometric), through the
    stroke channel's RC anti-alias filter."""
    read = wire_wound(x, p) * (1.0 - rail_dip(u, dt_s, p))
    return rc_filter(read, dt_s, p["aa_share"] * (1.0 + p["aa_mismatch"]) / dt_s)


def load_cell_zero_shift(temperature: Array, p: dict[str, float]) -> Array:
    """The strain-gauge bridge's thermal zero shift [kg]: ``gauge_kg_per_k`` x the temperature's
    change [K] since the start."""
    return np.asarray(p["gauge_kg_per_k"] * (temperature - temperature[0]), dtype=np.float64)


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    return {
        "peak": peak,
        "pwm_bits": float(rng.integers(9, 11)),
        "carrier_hz": rng.uniform(23.0, 47.0),
        "carrier_phase": rng.uniform(0.0, 1.0),
        "ripple_share": rng.uniform(0.001, 0.004),
        "fill_tau_s": rng.uniform(0.04, 0.09),
        "amp_slew_per_s": rng.uniform(8.0, 16.0),
        "aa_share": rng.uniform(0.15, 0.3),
        "aa_mismatch": float(rng.choice([-1.0, 1.0])) * rng.uniform(0.03, 0.08),
        "input_noise_bar": rng.uniform(0.002, 0.005),
        "input_step_bar": rng.uniform(0.0015, 0.004),
        "pot_pitch_mm": rng.uniform(0.008, 0.02),
        "pot_origin": float(rng.integers(20, 200)),
        "pot_irregularity": rng.uniform(0.1, 0.3),
        "pot_seed": float(rng.integers(0, 2**31)),
        "rail_dip": rng.uniform(0.0004, 0.0015),
        "rail_tau_s": rng.uniform(0.02, 0.06),
        "gauge_kg_per_k": float(rng.choice([-1.0, 1.0])) * rng.uniform(0.005, 0.02),
    }
