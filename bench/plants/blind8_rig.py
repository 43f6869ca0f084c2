"""The blind8 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side: a proportional pressure valve whose internal controller limits the slew of its
set point (6-15 x the peak per second) and answers with a first-order lag of 10-30 ms
(:func:`muscle_pressure`: the pressure in the muscle). The transducer sits in the muscle's
inlet fitting, so it reads that pressure plus the *flow noise* of the turbulent jet past its
port (band-limited, growing with the flow, i.e. with the rate of change of the pressure, up to
0.3-1 % of the peak at full slew; :func:`port_flow_noise`). Its noise (2-6 mbar) and converter
step (2-5 mbar) are added by :func:`pressure_reading`.

Stroke side (:func:`stroke_reading`): the stroke ADC is a successive-approximation converter
whose bit weights are mismatched (capacitor mismatch: at every carry into bits 4-11 the reading
jumps by a few um, :func:`sar_bit_error`), its amplifier re-zeroes itself every 20-40 s leaving
a residual offset step of 3-8 um (:func:`autozero_steps`).

Both channels pass the DAQ's anti-aliasing filter (a second-order Butterworth at 0.3-0.4 x the
sample rate, :func:`anti_alias`), the stroke channel's corner 2-5 % off the pressure channel's
(component tolerance).

All the confounds are drawn with the plant parameters (seeded by them): the same in a record
with its effect on and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import cont2discrete, lfilter, lfilter_zi

from bench.plants.filters import lowpass

Array = NDArray[np.float64]
BUTTERWORTH_ZETA = 1.0 / math.sqrt(2.0)
SAR_BITS = range(4, 12)


def muscle_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] in the muscle for the set pressure ``u`` [bar]: the set point slew-limited
    to ``slew_per_s`` x the peak per second, then a first-order lag ``valve_tau_s``."""
    step = p["slew_per_s"] * p["peak"] * dt_s
    out = np.empty(u.size)
    now = float(u[0])
    for i, target in enumerate(u.tolist()):
        now += min(max(target - now, -step), step)
        out[i] = now
    return np.asarray(np.clip(lowpass(out, dt_s, p["valve_tau_s"]), 0.0, None), dtype=np.float64)


def port_flow_noise(pressure: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Turbulence [bar] the inlet transducer reads while air flows: unit white noise (seeded by
    ``flow_seed``) through a 25 ms lag, normalised, times ``flow_noise_bar`` x the flow's share of
    the valve's full slew."""
    rng = np.random.default_rng(int(p["flow_seed"]))
    white = rng.normal(0.0, 1.0, pressure.size)
    tau = 0.025
    a = 1.0 - math.exp(-dt_s / tau)
    band = lowpass(white, dt_s, tau) * math.sqrt((2.0 - a) / a)  # unit variance
    flow = np.abs(np.diff(pressure, prepend=pressure[0])) / dt_s / (p["slew_per_s"] * p["peak"])
    return np.asarray(p["flow_noise_bar"] * np.clip(flow, 0.0, 1.0) * band, dtype=np.float64)


def second_order(x: Array, dt_s: float, f_hz: float, zeta: float) -> Array:
    """``y'' + 2 zeta wn y' + wn^2 y = wn^2 x`` (``wn = 2 pi f_hz``) for a continuous ``x``
    sampled every ``dt_s``: discretised with a first-order hold (the signal joined linearly
    between samples, so no half-sample lag of a staircase), at rest on ``x[0]``."""
    wn = 2.0 * math.pi * f_hz
    num, den, _ = cont2discrete(([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn]), dt_s, method="foh")
    b, a = np.asarray(num, dtype=np.float64).ravel(), np.asarray(den, dtype=np.float64)
    b = b / (b.sum() / a.sum())  # unit DC gain exactly
    out, _ = lfilter(b, a, x, zi=lfilter_zi(b, a) * x[0])
    return np.asarray(out, dtype=np.float64)


def anti_alias(x: Array, dt_s: float, corner_share: float) -> Array:
    """``x`` through a second-order Butterworth low-pass at ``corner_share`` x the sample rate."""
    return second_order(x, dt_s, corner_share / dt_s, BUTTERWORTH_ZETA)


def recorded_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The pressure channel [bar], noise-free: the muscle's pressure plus the port's flow noise,
    through the pressure channel's anti-alias filter (the transducer's own noise and step come
    in :func:`pressure_reading`)."""
    pressure = muscle_pressure(u, dt_s, p)
    return anti_alias(pressure + port_flow_noise(pressure, dt_s, p), dt_s, p["aa_share"])


def pressure_reading(pressure: Array, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The transducer's reading [bar]: its noise ``input_noise_bar`` and step ``input_step_bar``."""
    noisy = pressure + rng.normal(0.0, p["input_noise_bar"], pressure.size)
    return np.asarray(np.round(noisy / p["input_step_bar"]) * p["input_step_bar"], dtype=np.float64)


def sar_bit_error(x: Array, p: dict[str, float]) -> Array:
    """The SAR converter's error [mm] at stroke ``x`` [mm]: code ``floor(x / lsb) + code0``, and
    for every set bit ``b`` of it (4..11) that bit's weight error ``sar_w<b>`` [LSB]."""
    lsb = p["sar_lsb_mm"]
    code = np.floor(x / lsb).astype(np.int64) + int(p["sar_code0"])
    err = np.zeros(x.size)
    for b in SAR_BITS:
        err += p[f"sar_w{b}"] * ((code >> b) & 1)
    return np.asarray(lsb * err, dtype=np.float64)


def autozero_steps(n: int, dt_s: float, p: dict[str, float]) -> Array:
    """The amplifier's residual offset [mm]: a new value ``N(0, autozero_mm)`` after every
    re-zeroing, every ``autozero_period_s`` (first at ``autozero_phase`` of a period)."""
    rng = np.random.default_rng(int(p["autozero_seed"]))
    t = np.arange(n, dtype=np.float64) * dt_s
    period = p["autozero_period_s"]
    which = np.floor(t / period + p["autozero_phase"]).astype(np.int64)
    levels = rng.normal(0.0, p["autozero_mm"], int(which.max()) + 1)
    return np.asarray(levels[which], dtype=np.float64)


def stroke_reading(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke channel [mm] of a contraction ``x`` [mm], noise-free: the SAR bit error and
    the amplifier's auto-zero offset added, through the stroke channel's anti-alias filter."""
    raw = x + sar_bit_error(x, p) + autozero_steps(x.size, dt_s, p)
    return anti_alias(raw, dt_s, p["aa_share"] * (1.0 + p["aa_mismatch"]))


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    g = {
        "peak": peak,
        "slew_per_s": rng.uniform(6.0, 15.0),
        "valve_tau_s": rng.uniform(0.01, 0.03),
        "flow_noise_bar": rng.uniform(0.003, 0.01) * peak,
        "flow_seed": float(rng.integers(0, 2**31)),
        "aa_share": rng.uniform(0.3, 0.4),
        "aa_mismatch": float(rng.choice([-1.0, 1.0])) * rng.uniform(0.02, 0.05),
        "input_noise_bar": rng.uniform(0.002, 0.006),
        "input_step_bar": rng.uniform(0.002, 0.005),
        "sar_lsb_mm": rng.uniform(0.004, 0.012),
        "sar_code0": float(rng.integers(64, 4096)),
        "autozero_mm": rng.uniform(0.003, 0.008),
        "autozero_period_s": rng.uniform(20.0, 40.0),
        "autozero_phase": rng.uniform(0.0, 1.0),
        "autozero_seed": float(rng.integers(0, 2**31)),
    }
    for b in SAR_BITS:  # a mismatch growing with the bit's capacitor, ~0.25 LSB at bit 4
        g[f"sar_w{b}"] = float(rng.normal(0.0, 0.25 * 2.0 ** ((b - 4) / 2.0)))
    return g
