"""Every effect in two forms none of the other six families uses, and the always-moving columns.

Rate dependence: a *tempered springpot* in the braid (a fractional viscoelastic element,
``K (x - y) = eta s (s + w_c)^(alpha - 1) y``: a lag that grows as ``w^alpha`` above the
tempering frequency and is viscous below it, applied exactly in the frequency domain); the
lubricant's *thixotropy* (a structure parameter broken down by the braid's motion, at a rate
growing with the square of the speed, and rebuilt at rest in 1-4 s, so the friction that makes
the loop drops at fast rates and returns after a rest). Creep: a Kelvin creep towards ``v^n``
with a *direction-dependent* time constant (quick under rising stress, 2-8 x slower recovery);
*Fickian* gas sorption swelling the bladder (Henry's law: the equilibrium is proportional to the
pressure; the kernel is the diffusion series, which goes as sqrt(t) at first), superposed over
the pressure history. Transport delay: an *exhaust pilot* that opens the vent only after a dead
time, so only deflation is delayed (the muscle sees the running maximum of the set pressure
over the dead time); the stroke transducer's firmware *median* despiking filter over its last
60-200 ms (a dead time of half the window on every monotone stretch). Load dependence: a slack
rope linkage whose *slack the payload takes up* (the share held against one flank grows with
the payload, so only the descending branch moves); a *Fung* (exponentially stiffening) tendon
strap carrying the payload and the return spring. Temperature drift: the bladder's *onset
softening* (a warmer bladder needs less pressure to start the braid, a shift of the input that
vanishes vented and at the top, after an 8-30 s thermal lag); the sleeve's thermal expansion
changing the stroke gain through a *two-node* thermal network (air to bladder to braid).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: parcels arriving on a tray that is emptied when full (the load cell rings after
each change), or a water tank draining through an orifice (Torricelli) and refilled by a pump.
Temperature: the rig's motor and electronics warming up after power-on (with the room's
ripple), or the room's thermostat cycling the heating in a dead band.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_cores import Core
from bench.plants.blind5_rig import G_MS2, stroke_reading
from bench.plants.filters import lowpass
from bench.plants.recording import drawn_columns

Array = NDArray[np.float64]
BLIND5_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("tempered_springpot", "thixotropic_grease"),
    "creep": ("slow_recovery_kelvin", "fickian_swelling"),
    "transport_delay": ("exhaust_pilot", "median_despike"),
    "load_dependence": ("slack_takeup", "fung_tendon"),
    "temperature_drift": ("onset_softening", "two_node_sleeve"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "tempered_springpot": "theta_s",
    "thixotropic_grease": "breakdown",
    "slow_recovery_kelvin": "creep_share",
    "fickian_swelling": "swell_share",
    "exhaust_pilot": "pilot_s",
    "median_despike": "window_s",
    "slack_takeup": "takeup_gain",
    "fung_tendon": "strap_length",
    "onset_softening": "onset_share_per_k",
    "two_node_sleeve": "gain_per_k",
}
THIXO_REF_SPEED = 0.2  # [peak/s] the speed at which the breakdown rate is ``b``
MAX_WINDOW_S = 0.6  # the longest dead time / filter window the firmware allows


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_parcel_tray(t: Array, rng: np.random.Generator) -> Array:
    """A tray (0.4-0.8 kg) on which parcels of 0.2-1.2 kg arrive every 3-12 s (the first within
    1-4 s); above 2.5-4 kg of parcels it is emptied. Every change takes 0.2 s and the load cell
    rings after it (2-4 Hz, decaying in 0.3-0.6 s, 30 % of the change)."""
    out = np.full_like(t, float(rng.uniform(0.4, 0.8)))
    f_ring, decay = float(rng.uniform(2.0, 4.0)), float(rng.uniform(0.3, 0.6))
    full, parcels, now = float(rng.uniform(2.5, 4.0)), 0.0, float(rng.uniform(1.0, 4.0))
    while now < t[-1]:
        change = float(rng.uniform(0.2, 1.2))
        if parcels + change > full:
            change = -parcels
        parcels += change
        s = t - now
        edge = np.clip(s / 0.2, 0.0, 1.0)
        after = np.clip(s - 0.2, 0.0, None)
        ring = np.where(s > 0.2, np.exp(-after / decay) * np.sin(2 * np.pi * f_ring * after), 0.0)
        out += change * (edge + 0.3 * ring)
        now += float(rng.uniform(3.0, 12.0))
    return out


def load_torricelli_tank(t: Array, rng: np.random.Generator) -> Array:
    """A 0.3-0.6 kg tank whose water (2-4 kg when full) drains through an orifice,
    ``dm/dt = -c sqrt(m)`` (from full to the 0.3-1 kg refill mark in 8-25 s), and a pump refills it
    at 0.3-0.6 kg/s; it starts part full."""
    dt = float(t[1] - t[0])
    high, low = float(rng.uniform(2.0, 4.0)), float(rng.uniform(0.3, 1.0))
    c = 2.0 * (math.sqrt(high) - math.sqrt(low)) / float(rng.uniform(8.0, 25.0))
    pump = float(rng.uniform(0.3, 0.6))
    m, filling = float(rng.uniform(low + 0.3, high)), False
    out = np.empty_like(t)
    for i in range(t.size):
        m += dt * ((pump if filling else 0.0) - c * math.sqrt(max(m, 0.0)))
        filling = (filling and m < high) or (not filling and m <= low)
        out[i] = m
    return np.asarray(float(rng.uniform(0.3, 0.6)) + out, dtype=np.float64)


def temp_motor_warmup(t: Array, rng: np.random.Generator) -> Array:
    """After power-on the rig warms from 18-24 degC by 5-10 K (time constant 30-80 s), with the
    room's ripple of 0.2-0.5 K over 40-90 s on top."""
    base, rise, tau = float(rng.uniform(18.0, 24.0)), float(rng.uniform(5.0, 10.0)), float(rng.uniform(30.0, 80.0))
    ripple = float(rng.uniform(0.2, 0.5)) * np.sin(2 * np.pi * t / float(rng.uniform(40.0, 90.0)) + rng.uniform(0, 6.3))
    return np.asarray(base + rise * -np.expm1(-t / tau) + ripple, dtype=np.float64)


def temp_hvac_deadband(t: Array, rng: np.random.Generator) -> Array:
    """A thermostat holding 19-24 degC in a 1.5-3 K dead band: the heater warms the air at
    0.04-0.1 K/s, the room loses 0.03-0.07 K/s with it off; the rig's sensor sees the air through
    a 3-8 s lag."""
    dt = float(t[1] - t[0])
    setpoint, band = float(rng.uniform(19.0, 24.0)), float(rng.uniform(1.5, 3.0))
    heat, loss = float(rng.uniform(0.04, 0.1)), float(rng.uniform(0.03, 0.07))
    x, on = setpoint + float(rng.uniform(-0.5, 0.5)) * band, bool(rng.random() < 0.5)
    out = np.empty_like(t)
    for i in range(t.size):
        x += dt * (heat if on else -loss)
        on = (on and x < setpoint + 0.5 * band) or (not on and x <= setpoint - 0.5 * band)
        out[i] = x
    return lowpass(out, dt, float(rng.uniform(3.0, 8.0)))


LOAD_PATTERNS = {"parcel_tray": load_parcel_tray, "torricelli_tank": load_torricelli_tank}
TEMPERATURE_PATTERNS = {"motor_warmup": temp_motor_warmup, "hvac_deadband": temp_hvac_deadband}


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record and their pattern names (independent of the effect)."""
    return drawn_columns(LOAD_PATTERNS, TEMPERATURE_PATTERNS, t, rng)


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "tempered_springpot":  # eta / K [s^alpha]; order; tempering frequency [Hz]
        return {"theta_s": rng.uniform(0.08, 0.3), "alpha": rng.uniform(0.3, 0.6), "temper_hz": rng.uniform(0.3, 1.0)}
    if form == "thixotropic_grease":  # breakdown rate [1/s] at 0.2 peak/s; rebuild time [s]; friction share lost
        return {"breakdown": rng.uniform(1.0, 3.0), "rebuild_s": rng.uniform(1.0, 4.0), "loss": rng.uniform(0.6, 0.9)}
    if form == "slow_recovery_kelvin":  # share of span at full pressure; stress exponent; times [s]
        up = rng.uniform(6.0, 20.0)
        return {
            "creep_share": rng.uniform(0.03, 0.09),
            "stress_exp": rng.uniform(1.2, 2.0),
            "tau_up_s": up,
            "tau_down_s": up * rng.uniform(2.0, 8.0),
        }
    if form == "fickian_swelling":  # share of span at full pressure; diffusion time [s]
        return {"swell_share": rng.uniform(0.04, 0.12), "diffusion_s": rng.uniform(20.0, 80.0)}
    if form == "exhaust_pilot":  # pilot dead time [s]
        return {"pilot_s": rng.uniform(0.05, 0.2)}
    if form == "median_despike":  # median window [s]
        return {"window_s": rng.uniform(0.06, 0.2)}
    if form == "slack_takeup":  # slack half-width [mm]; held share at the start; gain; half-share load [kg]
        return {
            "slack_mm": rng.uniform(0.6, 2.0),
            "held_share": rng.uniform(0.2, 0.5),
            "takeup_gain": 1.0,
            "half_kg": rng.uniform(1.0, 3.0),
        }
    if form == "fung_tendon":  # initial stiffness [N/mm] and stiffening [1/N] of a unit strap; its length (x unit)
        return {"k0_n_mm": rng.uniform(8.0, 25.0), "stiffening_per_n": rng.uniform(0.01, 0.04), "strap_length": 1.0}
    if form == "onset_softening":  # onset shift [share of peak per K]; bladder lag [s]
        return {"onset_share_per_k": rng.uniform(0.006, 0.02), "bladder_tau_s": rng.uniform(8.0, 30.0)}
    if form == "two_node_sleeve":  # stroke gain [1/K] (negative: warmer, less stroke); lags [s]
        return {
            "gain_per_k": -rng.uniform(0.006, 0.018),
            "air_tau_s": rng.uniform(2.0, 6.0),
            "braid_tau_s": rng.uniform(8.0, 25.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND5_FORMS}")


def tempered_springpot(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` [mm] through ``H(iw) = 1 / (1 + theta iw (iw + w_c)^(alpha - 1))`` (FFT on a record
    padded by holding its last value, at rest on ``x[0]``; the tempered kernel is short, so the
    circular wrap is negligible)."""
    n = x.size
    size = 1 << int(math.ceil(math.log2(2 * n)))
    z = np.concatenate([x - x[0], np.full(size - n, x[-1] - x[0])])
    s = 2j * np.pi * np.fft.rfftfreq(size, dt_s)
    h = 1.0 / (1.0 + q["theta_s"] * s * (s + 2.0 * np.pi * q["temper_hz"]) ** (q["alpha"] - 1.0))
    return np.asarray(np.fft.irfft(np.fft.rfft(z) * h, size)[:n] + x[0], dtype=np.float64)


def thixotropy_width(u: Array, dt_s: float, q: dict[str, float], peak: float) -> Array:
    """Friction factor ``1 - loss (1 - lambda)``: ``dlambda/dt = (1 - lambda) / T_b - b (r /
    r_0)^2 lambda`` with ``r`` the speed of the set pressure [peak/s], ``r_0`` = 0.2 peak/s (the
    breakdown grows with the square of the shear rate; exact per sample); 1 at rest."""
    speed = (np.abs(np.gradient(u, dt_s)) / peak / THIXO_REF_SPEED) ** 2
    out = np.empty_like(u)
    lam, rebuild, b = 1.0, 1.0 / q["rebuild_s"], q["breakdown"]
    for i, r in enumerate(speed.tolist()):
        rate = rebuild + b * r
        eq = rebuild / rate
        lam = eq + (lam - eq) * math.exp(-rate * dt_s)
        out[i] = lam
    return np.asarray(1.0 - min(q["loss"], 0.9) * (1.0 - out), dtype=np.float64)


def slow_recovery_kelvin(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Creep [share] towards ``v^n``: time constant ``tau_up`` while below it, ``tau_down`` while above."""
    target = np.clip(v, 0.0, None) ** q["stress_exp"]
    up, down = math.exp(-dt_s / q["tau_up_s"]), math.exp(-dt_s / q["tau_down_s"])
    out = np.empty_like(v)
    c = 0.0
    for i, g in enumerate(target.tolist()):
        c = g + (c - g) * (up if g > c else down)
        out[i] = c
    return out


def fickian_swelling(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Swelling [share]: ``sum_n w_n lowpass(v, T / (2n+1)^2)``, ``w_n`` proportional to
    ``8 / ((2n+1)^2 pi^2)`` (six terms, normalised): Boltzmann superposition of the slab's
    sorption kernel."""
    terms = [(8.0 / ((2 * k + 1) ** 2 * math.pi**2), q["diffusion_s"] / (2 * k + 1) ** 2) for k in range(6)]
    total = sum(w for w, _ in terms)
    out = np.zeros_like(v)
    for w, tau in terms:
        out += (w / total) * lowpass(v, dt_s, tau)
    return out


def _window(x: Array, seconds: float, dt_s: float) -> NDArray[np.float64]:
    """The last ``seconds`` of ``x`` at every sample (padded with ``x[0]`` before the start)."""
    w = max(int(round(min(seconds, MAX_WINDOW_S) / dt_s)), 0) + 1
    padded = np.concatenate([np.full(w - 1, x[0]), x])
    return np.asarray(np.lib.stride_tricks.sliding_window_view(padded, w), dtype=np.float64)


def slack_takeup(x: Array, share: Array, slack_mm: float) -> Array:
    """A slack linkage of half-width ``r``: the share ``s`` of it the payload holds against the
    lower flank closes; ``play(x, r (1 - s)) - r s`` (the ascending branch stays ``x - r``)."""
    r_free = slack_mm * (1.0 - share)
    out = np.empty_like(x)
    y = float(x[0] - r_free[0])
    for i, (xi, ri) in enumerate(zip(x.tolist(), r_free.tolist())):
        y = min(max(y, xi - ri), xi + ri)
        out[i] = y
    return np.asarray(out - slack_mm * share, dtype=np.float64)


def drive_of(u: Array, dt_s: float, form: str, q: dict[str, float], temperature: Array, peak: float) -> Array:
    """The set pressure [bar] reaching the core: ``u`` unless ``form`` acts on the input side."""
    if form == "exhaust_pilot":
        return np.asarray(_window(u, q["pilot_s"], dt_s).max(axis=1), dtype=np.float64)
    if form == "onset_softening":
        warm = lowpass(temperature, dt_s, q["bladder_tau_s"]) - temperature[0]
        v = np.clip(u / peak, 0.0, 1.0)
        return np.asarray(np.clip(u + q["onset_share_per_k"] * peak * warm * 4.0 * v * (1.0 - v), 0.0, None))
    return u


def render(
    core: Core,
    params: dict[str, float],
    u: Array,
    dt_s: float,
    form: str,
    q: dict[str, float],
    load: Array,
    temperature: Array,
    base: Array | None = None,
) -> Array:
    """Noise-free stroke reading [mm] of ``core`` with the effect ``form`` (``"none"``: switched
    off), through the rig (:func:`~bench.plants.blind5_rig.stroke_reading`).

    ``base`` is the effect-free core output (computed when not given). The load and temperature
    forms act through their column's change since the record's start (the plant as identified
    then): with the columns held at their first value they are the effect-free plant with the
    form's element in it."""
    peak = params["peak"]
    if form in ("exhaust_pilot", "onset_softening"):
        x = core(drive_of(u, dt_s, form, q, temperature, peak), dt_s, params)
    elif form == "thixotropic_grease":
        x = core(u, dt_s, params, thixotropy_width(u, dt_s, q, peak))
    else:
        x = core(u, dt_s, params) if base is None else base
    span = float(np.ptp(x))
    v = np.clip(u / peak, 0.0, None)
    if form == "tempered_springpot":
        x = tempered_springpot(x, dt_s, q)
    elif form == "slow_recovery_kelvin":
        x = x - q["creep_share"] * span * slow_recovery_kelvin(v, dt_s, q)
    elif form == "fickian_swelling":
        x = x + q["swell_share"] * span * fickian_swelling(v, dt_s, q)
    elif form == "slack_takeup":
        held = load / (load + q["half_kg"]) - load[0] / (load[0] + q["half_kg"])
        share = np.clip(q["held_share"] + q["takeup_gain"] * held, 0.0, 1.0)
        x = slack_takeup(x, share, q["slack_mm"])
    elif form == "fung_tendon":
        k0, b = q["k0_n_mm"], q["stiffening_per_n"]
        tension = G_MS2 * np.clip(load, 0.0, None) + params["k_load_n_mm"] * x
        rest = G_MS2 * max(float(load[0]), 0.0) + params["k_load_n_mm"] * x
        # the stretch of a strap ``length`` units long: ``length ln(1 + b T / k0) / b``
        x = x - q["strap_length"] * (np.log1p(b * tension / k0) - np.log1p(b * rest / k0)) / b
    elif form == "two_node_sleeve":
        braid = lowpass(lowpass(temperature, dt_s, q["air_tau_s"]), dt_s, q["braid_tau_s"])
        x = x * (1.0 + q["gain_per_k"] * (braid - temperature[0]))
    reading = stroke_reading(x, dt_s, params)
    if form == "median_despike":
        return np.asarray(np.median(_window(reading, q["window_s"], dt_s), axis=1), dtype=np.float64)
    return reading
