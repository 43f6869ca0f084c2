"""The blind10 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side (:func:`muscle_pressure`): a process-style valve chain, an *I/P converter* (a
flapper-nozzle current-to-pressure transducer: a first-order lag of 15-35 ms) piloting a *volume
booster* that fills through its supply seat and exhausts through its larger exhaust port: a
first-order fill of 25-60 ms and a faster exhaust (0.35-0.7 x the fill's time constant), so the
muscle's pressure answers rises more slowly than falls.

The recorded input (:func:`recorded_pressure`, :func:`pressure_reading`) is a loop-powered *4-20 mA
pressure transmitter* at the booster's outlet, where the muscle's line starts (it reads the
pressure the line delivers, over a range of 1.2-1.6 x the peak; an effect may put a dead time in
the line after it): it updates its output every 8-20 ms (held between updates), and a HART master
polls it every 0.6-2.5 s, each transaction (0.12-0.3 s) putting *FSK bursts* (1200/2200 Hz, +-0.5 mA,
phase-continuous) on the loop current; the DAQ's RC anti-alias filter (0.2-0.35 x the sample rate)
attenuates them and the sampling aliases what is left into tones at random frequencies. Then the
12-bit converter's noise (1.5-4 mbar) and step (a 12-bit count over 1.25 x the transmitter's range).

Stroke side (:func:`stroke_reading`): a *magnetostrictive* position sensor whose waveguide reads
with a periodic nonlinearity (4-12 um over a 20-60 mm wavelength) and a linearity bow (5-15 um over
the stroke), and whose cable flexes with the carriage: *triboelectric* noise proportional to the
stroke's speed (3-8 um RMS at 20 mm/s; seeded by the plant, the same with the effect on and off).

Columns (:func:`hx711_load`, :func:`ntc_temperature`): the load cell is read by a 24-bit bridge
converter at 10 or 80 conversions per second (each the mean over its conversion, held until the
next one: the load column moves in stairs), and the temperature by an NTC thermistor probe (a
bead lag of 1-4 s) in a divider read by a 10-bit converter, so the temperature's reading step
is not uniform (finer where the divider is steepest).

All the confounds are drawn with the plant parameters (seeded by them): the same in a record
with its effect on and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass

Array = NDArray[np.float64]
HART_MARK_HZ, HART_SPACE_HZ, HART_BAUD = 1200.0, 2200.0, 1200.0
HART_MA = 0.5  # FSK amplitude [mA] on a 16 mA span
NTC_R25_OHM, NTC_T25_K = 10_000.0, 298.15
ADC10 = 1023.0


def io_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The I/P converter's output [bar] for the set pressure ``u`` [bar]: a first-order lag."""
    return lowpass(np.clip(u, 0.0, None), dt_s, p["ip_tau_s"])


def booster(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The volume booster's output [bar] following its pilot ``x``: a first-order lag whose time
    constant is ``fill_tau_s`` while rising and ``exhaust_share`` x it while falling (exact for a
    pilot held over each sample), from rest on ``x[0]``."""
    a_fill = 1.0 - math.exp(-dt_s / p["fill_tau_s"])
    a_exh = 1.0 - math.exp(-dt_s / (p["exhaust_share"] * p["fill_tau_s"]))
    out = np.empty(x.size)
    y = float(x[0])
    for i, xi in enumerate(x.tolist()):
        y += (xi - y) * (a_fill if xi > y else a_exh)
        out[i] = y
    return out


def muscle_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] in the muscle for the set pressure ``u`` [bar]: I/P converter, then booster."""
    return booster(io_pressure(u, dt_s, p), dt_s, p)


def held(x: Array, dt_s: float, period_s: float, phase: float) -> Array:
    """``x`` sampled every ``period_s`` (first update at ``phase`` x the period) and held."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    k = np.floor(t / period_s - phase)
    update_t = np.clip((k + phase) * period_s, 0.0, None)
    idx = np.clip(np.floor(update_t / dt_s + 1e-9).astype(np.int64), 0, x.size - 1)
    return np.asarray(x[idx], dtype=np.float64)


def hart_bursts(n: int, dt_s: float, p: dict[str, float]) -> Array:
    """The HART FSK on the loop [bar of the transmitter's range] read at the ``n`` samples: bursts
    of phase-continuous 1200/2200 Hz at random bits, each tone scaled by the RC anti-alias
    filter's gain at its frequency (the sampling aliases it)."""
    rng = np.random.default_rng(int(p["hart_seed"]))
    t = np.arange(n, dtype=np.float64) * dt_s
    corner = p["aa_share"] / dt_s
    gain = {f: 1.0 / math.hypot(1.0, f / corner) for f in (HART_MARK_HZ, HART_SPACE_HZ)}
    bar_per_ma = p["transmitter_range_bar"] / 16.0
    out = np.zeros(n)
    start = float(rng.uniform(0.0, p["hart_poll_s"]))
    while n and start < t[-1]:
        length = float(rng.uniform(0.12, 0.3))
        inside = np.flatnonzero((t >= start) & (t < start + length))
        if inside.size:
            bit = np.floor((t[inside] - start) * HART_BAUD).astype(np.int64)
            bits = rng.integers(0, 2, int(bit.max()) + 1)
            freq = np.where(bits[bit] > 0, HART_MARK_HZ, HART_SPACE_HZ)
            amp = np.where(bits[bit] > 0, gain[HART_MARK_HZ], gain[HART_SPACE_HZ])
            # phase-continuous: the phase integrates the bit's frequency over each bit's time
            bit_phase = np.concatenate([[0.0], np.cumsum(np.where(bits > 0, HART_MARK_HZ, HART_SPACE_HZ) / HART_BAUD)])
            phase = bit_phase[bit] + freq * ((t[inside] - start) - bit / HART_BAUD)
            out[inside] = HART_MA * bar_per_ma * amp * np.sin(2.0 * np.pi * phase + float(rng.uniform(0.0, 6.3)))
        start += p["hart_poll_s"] * float(rng.uniform(0.8, 1.2))
    return out


def recorded_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The pressure channel [bar] for the set pressure ``u`` [bar], noise-free: the muscle's
    pressure as the transmitter outputs it (updated every ``tx_update_s``, held) plus the HART
    bursts left after the anti-alias filter, through that RC filter."""
    pressure = held(muscle_pressure(u, dt_s, p), dt_s, p["tx_update_s"], p["tx_phase"])
    smooth = lowpass(pressure, dt_s, 1.0 / (2.0 * math.pi * p["aa_share"] / dt_s))
    return np.asarray(smooth + hart_bursts(u.size, dt_s, p), dtype=np.float64)


def pressure_reading(pressure: Array, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The converter's reading [bar]: its noise ``input_noise_bar`` and step ``input_step_bar``."""
    noisy = pressure + rng.normal(0.0, p["input_noise_bar"], pressure.size)
    return np.asarray(np.round(noisy / p["input_step_bar"]) * p["input_step_bar"], dtype=np.float64)


def waveguide_error(x: Array, p: dict[str, float]) -> Array:
    """The magnetostrictive sensor's static error [mm] at the stroke ``x`` [mm]: a periodic
    nonlinearity and a bow (a parabola, 0 at both ends of ``0..bow_span_mm``)."""
    periodic = p["wave_amp_mm"] * np.sin(2.0 * np.pi * (x + p["wave_offset_mm"]) / p["wave_length_mm"])
    s = x / p["bow_span_mm"]
    return np.asarray(periodic + 4.0 * p["bow_mm"] * s * (1.0 - s), dtype=np.float64)


def triboelectric(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The cable's triboelectric noise [mm]: seeded white noise times the stroke's speed over
    20 mm/s (``tribo_mm`` RMS at that speed), the speed smoothed over 20 ms."""
    rng = np.random.default_rng(int(p["tribo_seed"]))
    speed = np.abs(lowpass(np.gradient(x, dt_s), dt_s, 0.02)) if x.size > 1 else np.zeros_like(x)
    return np.asarray(p["tribo_mm"] * speed / 20.0 * rng.standard_normal(x.size), dtype=np.float64)


def stroke_reading(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The stroke channel [mm] of a contraction ``x`` [mm], noise-free: the waveguide's error and
    the cable's triboelectric noise added."""
    return np.asarray(x + waveguide_error(x, p) + triboelectric(x, dt_s, p), dtype=np.float64)


def hx711_load(load: Array, dt_s: float, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The load column [kg]: each conversion (at ``hx711_sps``) the mean of the load over its
    period plus the converter's noise (``hx711_noise_kg``), read to ``hx711_step_kg`` and held
    until the next conversion completes; before the first one, the first."""
    period = 1.0 / p["hx711_sps"]
    t = np.arange(load.size, dtype=np.float64) * dt_s
    k = np.floor(t / period + p["hx711_phase"]).astype(np.int64)
    conv_index = k - k[0]
    n_conv = int(conv_index[-1]) + 1 if load.size else 0
    sums = np.bincount(conv_index, weights=load, minlength=n_conv)
    counts = np.maximum(np.bincount(conv_index, minlength=n_conv), 1)
    means = sums / counts + rng.normal(0.0, p["hx711_noise_kg"], n_conv)
    means = np.round(means / p["hx711_step_kg"]) * p["hx711_step_kg"]
    shown = np.clip(conv_index - 1, 0, None)  # a conversion is shown once it has finished
    return np.asarray(means[shown], dtype=np.float64)


def ntc_counts(temperature_c: Array, p: dict[str, float]) -> Array:
    """The 10-bit converter's (real-valued) counts for an NTC at ``temperature_c`` [degC] in a
    divider with ``divider_ohm`` to the reference (the NTC on the low side)."""
    kelvin = temperature_c + 273.15
    r = NTC_R25_OHM * np.exp(p["ntc_beta"] * (1.0 / kelvin - 1.0 / NTC_T25_K))
    return np.asarray(ADC10 * r / (r + p["divider_ohm"]), dtype=np.float64)


def ntc_celsius(counts: Array, p: dict[str, float]) -> Array:
    """The temperature [degC] the logger computes from the counts (Beta equation)."""
    c = np.clip(counts, 0.5, ADC10 - 0.5)
    r = p["divider_ohm"] * c / (ADC10 - c)
    return np.asarray(1.0 / (1.0 / NTC_T25_K + np.log(r / NTC_R25_OHM) / p["ntc_beta"]) - 273.15, dtype=np.float64)


def ntc_temperature(temperature: Array, dt_s: float, p: dict[str, float], rng: np.random.Generator) -> Array:
    """The temperature column [degC]: the probe's bead lag, the converter's noise (0.3 counts RMS)
    and its whole counts, converted back by the Beta equation (a non-uniform step)."""
    counts = ntc_counts(lowpass(temperature, dt_s, p["probe_tau_s"]), p) + rng.normal(0.0, 0.3, temperature.size)
    return ntc_celsius(np.round(counts), p)


def draw_rig(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The rig's constants for a supply range ``peak`` [bar]."""
    tx_range = peak * float(rng.uniform(1.2, 1.6))
    return {
        "peak": peak,
        "ip_tau_s": rng.uniform(0.015, 0.035),
        "fill_tau_s": rng.uniform(0.025, 0.06),
        "exhaust_share": rng.uniform(0.35, 0.7),
        "transmitter_range_bar": tx_range,
        "tx_update_s": rng.uniform(0.008, 0.02),
        "tx_phase": rng.uniform(0.0, 1.0),
        "hart_poll_s": rng.uniform(0.6, 2.5),
        "hart_seed": float(rng.integers(0, 2**31)),
        "aa_share": rng.uniform(0.2, 0.35),
        "input_noise_bar": rng.uniform(0.0015, 0.004),
        "input_step_bar": 1.25 * tx_range / 4096.0,
        "wave_amp_mm": rng.uniform(0.004, 0.012),
        "wave_length_mm": rng.uniform(20.0, 60.0),
        "wave_offset_mm": rng.uniform(0.0, 60.0),
        "bow_mm": float(rng.choice([-1.0, 1.0])) * rng.uniform(0.005, 0.015),
        "tribo_mm": rng.uniform(0.003, 0.008),
        "tribo_seed": float(rng.integers(0, 2**31)),
        "hx711_sps": float(rng.choice([10.0, 80.0])),
        "hx711_phase": rng.uniform(0.0, 1.0),
        "hx711_noise_kg": rng.uniform(0.001, 0.003),
        "hx711_step_kg": 0.0005,
        "ntc_beta": rng.uniform(3435.0, 3950.0),
        "divider_ohm": rng.uniform(6_800.0, 15_000.0),
        "probe_tau_s": rng.uniform(1.0, 4.0),
    }
