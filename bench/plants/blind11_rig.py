"""The blind11 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side (:func:`regulator_pressure`, :func:`muscle_line`): a *proportional pressure
regulator* whose spool has an *overlap* (a dead band of 0.4-1.2 % of the peak: inside it no
port is open, so the outlet stops short of the set pressure and stays there until the set
pressure moves out of the band again), which otherwise approaches the set pressure as a first-order
system (12-30 ms) whose flow saturates (a slew limit of 8-20 x the peak per second); the muscle gets
the outlet's pressure through a 2-6 m line (a further lag of 6-18 ms).

The recorded input (:func:`sensor_pressure`, :func:`pressure_reading`) is a piezoresistive
transducer *at the regulator's outlet*, where the line starts, so it leads the muscle's pressure
a little and it sees the line's *quarter-wave ringing* after fast changes (``c / 4 l``: 15-45 Hz,
damping ratio 0.06-0.15, 25-50 % of the outlet's own change: what the muscle's volume damps away);
its bridge's *zero drifts while it warms up* after power-on (2-6 mbar, a time constant of 20-70 s,
its own die's heating, not the temperature column's); then the 12-bit converter's noise
(1-3 mbar) and step (a count over 1.3-2 x the peak).

Stroke side (:func:`stroke_reading`): a *laser triangulation* sensor looking at the payload: the
Scheimpflug geometry leaves a cubic (S-shaped) linearity error over its 60-100 mm range (8-25 um
at its extremes), the laser's *speckle* on the payload's surface a smooth random error of the
position (3-8 um RMS, correlated over 0.3-1.5 mm, seeded by the plant), and the sensor *averages*
its internal samples over a window of 1-5 ms before it outputs (a boxcar: half of it late).

Columns (:func:`load_reading`, :func:`thermocouple_reading`): the load cell's bridge through an
instrumentation amplifier with a two-pole Butterworth low-pass (6-15 Hz), picking up 2-6 g of
*mains* hum (50 or 60 Hz, sampled at the record's rate, so aliased), read by a 12-bit converter
over a 10-30 kg range (a count of 2.4-7.3 g); the temperature by an exposed type-K
*thermocouple* junction (0.3-1.5 s lag) through a cold-junction-compensated converter that
completes a conversion every 100 ms (held between them), reads to 0.25 K and is off by its
cold-junction sensor's error (-0.5..0.5 K).

All the confounds are drawn with the plant parameters (seeded by them): the same in a record
with its effect on and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from bench.plants.filters import lowpass

Array = NDArray[np.float64]
SPECKLE_TERMS = 24
SPECKLE_TABLE_MM = 0.02  # the speckle error is tabulated at this pitch and read linearly
_CACHE_SIZE = 16
_REGULATOR_CACHE: dict[tuple[object, ...], Array] = {}
_SPECKLE_CACHE: dict[tuple[float, ...], tuple[Array, Array]] = {}
TC_CONVERSION_S = 0.1  # the thermocouple converter's conversion period [s]
TC_STEP_K = 0.25  # its reading step [K]
LOAD_COUNTS = 4096.0  # the load channel's 12-bit converter


def second_order(x: Array, dt_s: float, f_hz: float, zeta: float) -> Array:
    """``y'' + 2 zeta wn y' + wn^2 y = wn^2 x`` (``wn = 2 pi f_hz``, ``0 < zeta < 1``) for ``x`` held over
    each sample (the step-invariant discretisation in closed form: the same as
    :func:`bench.plants.filters.resonance` without its matrix exponential), at rest on ``x[0]``."""
    wn = 2.0 * math.pi * f_hz
    wd = wn * math.sqrt(1.0 - zeta * zeta)
    decay = math.exp(-zeta * wn * dt_s)
    c, s = math.cos(wd * dt_s), math.sin(wd * dt_s)
    ratio = zeta * wn / wd
    a = [1.0, -2.0 * decay * c, decay * decay]
    b = [0.0, 1.0 - decay * (c + ratio * s), decay * decay + decay * (ratio * s - c)]
    return np.asarray(lfilter(b, a, x - x[0]) + x[0], dtype=np.float64)


def regulator_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The regulator's outlet pressure [bar] for the set pressure ``u`` [bar]: outside the spool's
    dead band ``+-deadband_bar`` it approaches ``u`` less the band (first order, ``reg_tau_s``, exact
    for ``u`` held over a sample) at most ``slew_bar_s`` per second; inside the band it holds. From
    rest on ``u[0]``. (A record's effect renders ask for it again: the last few are kept.)"""
    key = (u.tobytes(), dt_s, p["deadband_bar"], p["slew_bar_s"], p["reg_tau_s"])
    if key not in _REGULATOR_CACHE:
        if len(_REGULATOR_CACHE) >= _CACHE_SIZE:
            _REGULATOR_CACHE.clear()
        _REGULATOR_CACHE[key] = _regulate(u, dt_s, p)
    return _REGULATOR_CACHE[key].copy()


def _regulate(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    band, slew_step = p["deadband_bar"], p["slew_bar_s"] * dt_s
    keep = math.exp(-dt_s / p["reg_tau_s"])
    out = np.empty(u.size)
    q = float(u[0]) if u.size else 0.0
    for i, ui in enumerate(np.clip(u, 0.0, None).tolist()):
        err = ui - q
        if err > band:
            q += min((err - band) * (1.0 - keep), slew_step)
        elif err < -band:
            q += max((err + band) * (1.0 - keep), -slew_step)
        out[i] = q
    return out


def muscle_line(outlet: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The muscle's pressure [bar]: the outlet's through the line's lag ``line_tau_s``."""
    return lowpass(outlet, dt_s, p["line_tau_s"])


def muscle_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] in the muscle for the set pressure ``u`` [bar]: regulator, then line."""
    return muscle_line(regulator_pressure(u, dt_s, p), dt_s, p)


def sensor_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The transducer's noise-free reading [bar] for the set pressure ``u``: the outlet's pressure
    plus ``ring_share`` of the line's quarter-wave ringing on it, plus the bridge's warm-up zero
    drift ``warm_bar (1 - exp(-t / warm_tau_s))``."""
    outlet = regulator_pressure(u, dt_s, p)
    ringing = second_order(outlet, dt_s, p["line_ring_hz"], p["line_ring_zeta"]) - outlet
    t = np.arange(u.size, dtype=np.float64) * dt_s
    drift = p["warm_bar"] * (1.0 - np.exp(-t / p["warm_tau_s"]))
    return np.asarray(outlet + p["ring_share"] * ringing + drift, dtype=np.float64)


def pressure_reading(pressure: Array, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The converter's reading [bar]: its noise ``input_noise_bar`` and step ``input_step_bar``."""
    noisy = pressure + rng.normal(0.0, p["input_noise_bar"], pressure.size)
    return np.asarray(np.round(noisy / p["input_step_bar"]) * p["input_step_bar"], dtype=np.float64)


def triangulation_error(x: Array, p: dict[str, float]) -> Array:
    """The laser sensor's static error [mm] at the stroke ``x`` [mm]: a cubic linearity error over
    its range (``lin_mm`` at its extremes, zero at its ends and middle) plus the speckle, a sum of
    :data:`SPECKLE_TERMS` cosines of random wavelengths about ``speckle_corr_mm`` (RMS ``speckle_mm``;
    seeded by ``speckle_seed``; tabulated over the range)."""
    x = np.asarray(x, dtype=np.float64)
    s = (x + p["standoff_mm"]) / p["range_mm"]
    linear = p["lin_mm"] * 6.0 * math.sqrt(3.0) * s * (1.0 - s) * (2.0 * s - 1.0)
    grid, table = _speckle_table(p)
    return np.asarray(linear + np.interp(x, grid, table), dtype=np.float64)


def _speckle_table(p: dict[str, float]) -> tuple[Array, Array]:
    """The speckle error [mm] tabulated every :data:`SPECKLE_TABLE_MM` over the sensor's range."""
    key = (p["speckle_seed"], p["speckle_corr_mm"], p["speckle_mm"], p["standoff_mm"], p["range_mm"])
    if key not in _SPECKLE_CACHE:
        if len(_SPECKLE_CACHE) >= _CACHE_SIZE:
            _SPECKLE_CACHE.clear()
        rng = np.random.default_rng(int(p["speckle_seed"]))
        k = 2.0 * np.pi / (p["speckle_corr_mm"] * rng.uniform(0.5, 2.0, SPECKLE_TERMS))
        phase = rng.uniform(0.0, 2.0 * np.pi, SPECKLE_TERMS)
        grid = np.arange(-p["standoff_mm"], p["range_mm"] - p["standoff_mm"] + SPECKLE_TABLE_MM, SPECKLE_TABLE_MM)
        speckle = np.cos(np.multiply.outer(grid, k) + phase).sum(axis=-1)
        _SPECKLE_CACHE[key] = grid, p["speckle_mm"] * math.sqrt(2.0 / SPECKLE_TERMS) * speckle
    return _SPECKLE_CACHE[key]


def boxcar(x: Array, dt_s: float, window_s: float) -> Array:
    """The mean of ``x`` (linear between samples, held at ``x[0]`` before the start) over the
    ``window_s`` [s] before each sample (the integral exact for the piecewise-linear signal)."""
    if x.size < 2:
        return np.asarray(x, dtype=np.float64)
    area = np.concatenate([[0.0], np.cumsum(0.5 * (x[1:] + x[:-1]) * dt_s)])  # the integral up to each sample
    start = np.arange(x.size, dtype=np.float64) - window_s / dt_s  # the window's start [samples]
    k = np.clip(np.floor(start), 0, x.size - 2).astype(np.int64)
    frac = np.clip(start - k, 0.0, 1.0)
    slope = x[k + 1] - x[k]
    at_start = area[k] + dt_s * frac * (x[k] + 0.5 * slope * frac)  # the integral up to the window's start
    before = np.clip(-start, 0.0, None) * dt_s * x[0]  # the part of the window before the record
    return np.asarray((area - np.where(start > 0.0, at_start, 0.0) + before) / window_s, dtype=np.float64)


def stroke_reading(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke channel [mm] of a payload stroke ``x`` [mm], noise-free: the triangulation and
    speckle errors, then the sensor's internal averaging over ``avg_window_s``."""
    return boxcar(np.asarray(x + triangulation_error(x, p), dtype=np.float64), dt_s, p["avg_window_s"])


def load_reading(load: Array, dt_s: float, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The load column [kg]: the amplifier's two-pole Butterworth low-pass, the mains hum it picks
    up (sampled at the record's rate), the converter's noise and its 12-bit count."""
    t = np.arange(load.size, dtype=np.float64) * dt_s
    filtered = second_order(load, dt_s, p["amp_corner_hz"], math.sqrt(0.5))
    hum = p["hum_kg"] * np.sin(2.0 * np.pi * p["mains_hz"] * t + p["hum_phase"])
    noisy = filtered + hum + rng.normal(0.0, p["load_noise_kg"], load.size)
    return np.asarray(np.round(noisy / p["load_step_kg"]) * p["load_step_kg"], dtype=np.float64)


def thermocouple_reading(temperature: Array, dt_s: float, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The temperature column [degC]: the junction's lag, the cold-junction error and the
    converter's noise (0.06 K RMS), converted every :data:`TC_CONVERSION_S` (the value at the
    conversion's end, shown until the next one ends), read to :data:`TC_STEP_K`."""
    junction = lowpass(temperature, dt_s, p["junction_tau_s"]) + p["cj_error_k"]
    t = np.arange(temperature.size, dtype=np.float64) * dt_s
    k = np.floor(t / TC_CONVERSION_S + p["tc_phase"]).astype(np.int64)
    done = np.clip(((k - p["tc_phase"]) * TC_CONVERSION_S / dt_s).astype(np.int64), 0, temperature.size - 1)
    value = junction[done] + rng.normal(0.0, 0.06, temperature.size)[done]
    return np.asarray(np.round(value / TC_STEP_K) * TC_STEP_K, dtype=np.float64)


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    sensor_range = peak * float(rng.uniform(1.3, 2.0))
    load_range = float(rng.uniform(10.0, 30.0))
    return {
        "peak": peak,
        "deadband_bar": peak * rng.uniform(0.004, 0.012),
        "reg_tau_s": rng.uniform(0.012, 0.03),
        "slew_bar_s": peak * rng.uniform(8.0, 20.0),
        "line_tau_s": rng.uniform(0.006, 0.018),
        "line_ring_hz": rng.uniform(15.0, 45.0),
        "line_ring_zeta": rng.uniform(0.06, 0.15),
        "ring_share": rng.uniform(0.25, 0.5),
        "warm_bar": float(rng.choice([-1.0, 1.0])) * rng.uniform(0.002, 0.006),
        "warm_tau_s": rng.uniform(20.0, 70.0),
        "sensor_range_bar": sensor_range,
        "input_noise_bar": rng.uniform(0.001, 0.003),
        "input_step_bar": sensor_range / 4096.0,
        "range_mm": rng.uniform(60.0, 100.0),
        "standoff_mm": rng.uniform(5.0, 15.0),
        "lin_mm": float(rng.choice([-1.0, 1.0])) * rng.uniform(0.008, 0.025),
        "speckle_mm": rng.uniform(0.003, 0.008),
        "speckle_corr_mm": rng.uniform(0.3, 1.5),
        "speckle_seed": float(rng.integers(0, 2**31)),
        "avg_window_s": rng.uniform(0.001, 0.005),
        "amp_corner_hz": rng.uniform(6.0, 15.0),
        "mains_hz": float(rng.choice([50.0, 60.0])),
        "hum_kg": rng.uniform(0.002, 0.006),
        "hum_phase": rng.uniform(0.0, 2.0 * np.pi),
        "load_noise_kg": rng.uniform(0.001, 0.003),
        "load_step_kg": load_range / LOAD_COUNTS,
        "junction_tau_s": rng.uniform(0.3, 1.5),
        "cj_error_k": rng.uniform(-0.5, 0.5),
        "tc_phase": rng.uniform(0.0, 1.0),
    }
