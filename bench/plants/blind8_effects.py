"""Every effect in two forms none of the other nine families uses, and the always-moving columns.

Rate dependence: an *air dashpot* on the payload carriage (a glass-piston dashpot whose air
leaks through an adjustable orifice: the air's compressibility is a spring in series with the
orifice, a Maxwell element, so the carriage lags by ``r tau v`` at slow speeds and at most by a
share ``r / (1 + r)`` of a quick move); a *flywheel inerter* (the payload's line runs over a
heavy drum: its rotational inertia ``J / r^2`` rides on the muscle's stiffness, a lightly damped
2-5 Hz resonance, so the stroke lags and overshoots by its acceleration). Creep: the rubber
*return cord's stress relaxation* by the *Chasset-Thirion* law (``E(t) ~ 1 + (1 + t /
tau0)^(-m)``, superposed over the stroke's history, Boltzmann: the cord's force fades slowly at
any held stretch and comes back when it is released); *crimp interchange* of the woven sleeve
(the hoop yarns straighten under the hoop tension towards ``c_eq ~ v^2`` at a rate that slows
exponentially as the crimp is used up, and re-crimp 2-5 x slower when the tension falls).
Transport delay: the stroke's LVDT conditioner *demodulates* through a fourth-order *Bessel*
filter (a near-constant group delay of 12-50 ms); the stroke sensor streams its readings as
*ASCII frames over a UART* (sampled at 60-150 Hz, formatted after a firmware latency, each frame
queued behind the one on the wire and taking ``10 chars / baud``, the logger holding the last
complete frame). Load dependence: the muscle's top anchor sits on a stack of *Belleville
disc springs* (Almen-Laszlo, degressive) that the line's tension (payload plus return spring)
compresses (sized so that the working pull sits near the discs' flat, constant-force region);
the muscle pulls its payload through a *Bowden cable whose sheath compresses* under the
payload's weight (its coil gaps close first, softly, then the solid sheath). Temperature drift:
the rubber return cord's *thermoelastic inversion* (entropic force ``~ T`` against thermal expansion: it weakens
when warm at small stretch and strengthens at large stretch), through the cord's thermal lag;
the draw-wire stroke sensor's plastic *drum expanding* (the reading of the whole extension, its
dead length included, scales by ``1 / (1 + alpha dT)``), through the drum's lag.

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: a hoist paying a chain out onto the payload's pan and taking it up again, or masses
set on and taken off a pan on a spring hanger (each change ringing on the load cell).
Temperature: the muscle's exhaust blowing over the sensor at every vent (a decoy following the
input's falls), or an oscillating desk fan switched on and off, sweeping over the warm rig.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import bessel, cont2discrete, lfilter, lfilter_zi

from bench.plants.blind8_rig import muscle_pressure, second_order, stroke_reading
from bench.plants.filters import lowpass

Array = NDArray[np.float64]
BLIND8_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("air_dashpot", "flywheel_inerter"),
    "creep": ("chasset_thirion_cord", "crimp_interchange"),
    "transport_delay": ("bessel_lvdt_demod", "uart_ascii_stream"),
    "load_dependence": ("belleville_anchor", "bowden_sheath_compression"),
    "temperature_drift": ("thermoelastic_inversion_cord", "drawwire_drum_expansion"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "air_dashpot": "air_stiffness_ratio",
    "flywheel_inerter": "inertance_s2",
    "chasset_thirion_cord": "cord_share",
    "crimp_interchange": "crimp_share",
    "bessel_lvdt_demod": "group_delay_s",
    "uart_ascii_stream": "firmware_latency_s",
    "belleville_anchor": "stack_mm",
    "bowden_sheath_compression": "gap_mm",
    "thermoelastic_inversion_cord": "cord_mm_share",
    "drawwire_drum_expansion": "drum_alpha_per_k",
}
G_MS2 = 9.81
T0_K = 273.15


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_hoist_chain(t: Array, rng: np.random.Generator) -> Array:
    """A 0.5-2 kg pan onto which a hoist pays out a chain at 0.15-0.3 kg/s for 4-10 s, pauses
    2-6 s and takes it up again (to 0-20 % left), pausing 2-6 s; the first payout within 3 s."""
    knots_t, knots_f = [0.0, float(rng.uniform(0.0, 3.0))], [0.0, 0.0]
    while knots_t[-1] < t[-1]:
        rate, length = float(rng.uniform(0.15, 0.3)), float(rng.uniform(4.0, 10.0))
        top = knots_f[-1] + rate * length
        left = float(rng.uniform(0.0, 0.2)) * top
        knots_t += [knots_t[-1] + length, 0.0, 0.0, 0.0]
        knots_t[-3] = knots_t[-4] + float(rng.uniform(2.0, 6.0))
        knots_t[-2] = knots_t[-3] + (top - left) / rate
        knots_t[-1] = knots_t[-2] + float(rng.uniform(2.0, 6.0))
        knots_f += [top, top, left, left]
    return np.asarray(float(rng.uniform(0.5, 2.0)) + np.interp(t, knots_t, knots_f), dtype=np.float64)


def load_spring_hanger_masses(t: Array, rng: np.random.Generator) -> Array:
    """A 1-3 kg pan on a spring hanger onto which masses of 0.3-1 kg are set or taken off every
    6-15 s (first within 4 s; never below the pan): each change rings on the load cell as a
    decaying oscillation of the change's size at 1.5-3 Hz (damping ratio 0.03-0.08)."""
    f, zeta = float(rng.uniform(1.5, 3.0)), float(rng.uniform(0.03, 0.08))
    w = 2.0 * math.pi * f
    pan = float(rng.uniform(1.0, 3.0))
    load = np.full_like(t, pan)
    on, now = 0.0, float(rng.uniform(0.0, 4.0))
    while now < t[-1]:
        change = float(rng.uniform(0.3, 1.0))
        change = -change if on >= change and rng.uniform() < 0.5 else change
        on += change
        s = t - now
        after = s >= 0.0
        load[after] += change * (1.0 - np.exp(-zeta * w * s[after]) * np.cos(w * s[after]))
        now += float(rng.uniform(6.0, 15.0))
    return load


def temp_exhaust_cooling(t: Array, rng: np.random.Generator, v: Array) -> Array:
    """A 19-25 degC room drifting by 0.3-1 K over 150-400 s; every fall of the muscle's pressure
    ``v`` [share of peak] blows its exhaust over the sensor: ``dT/dt = -(T - T_room) / tau -
    k max(-dv/dt, 0)`` (``k`` 2-6 K per full vent, ``tau`` 10-25 s)."""
    dt = float(t[1] - t[0])
    room = float(rng.uniform(19.0, 25.0)) + float(rng.uniform(0.3, 1.0)) * np.sin(
        2.0 * np.pi * t / float(rng.uniform(150.0, 400.0)) + float(rng.uniform(0.0, 6.3))
    )
    tau, k = float(rng.uniform(10.0, 25.0)), float(rng.uniform(2.0, 6.0))
    venting = np.clip(-np.diff(v, prepend=v[0]), 0.0, None)
    keep = math.exp(-dt / tau)
    cooling = lfilter([k], [1.0, -keep], venting)
    return np.asarray(room - cooling, dtype=np.float64)


def temp_fan_sweep(t: Array, rng: np.random.Generator) -> Array:
    """A rig 3-7 K above a 20-26 degC room and an oscillating desk fan switched on and off every
    15-40 s (first within 10 s): while on, the rig cools towards 1.5-4 K lower (lag 8-20 s) and
    every sweep over it (every 8-16 s) adds a cooling pulse ``depth max(0, cos)^4`` (depth
    0.5-1.5 K); read through the sensor's 1.5-4 s lag."""
    dt = float(t[1] - t[0])
    base = float(rng.uniform(20.0, 26.0)) + float(rng.uniform(3.0, 7.0))
    fan = np.zeros_like(t)
    on, now = bool(rng.uniform() < 0.5), float(rng.uniform(0.0, 10.0))
    fan[t < now] = float(on)
    while now < t[-1]:
        on = not on
        length = float(rng.uniform(15.0, 40.0))
        fan[(t >= now) & (t < now + length)] = float(on)
        now += length
    period, depth = float(rng.uniform(8.0, 16.0)), float(rng.uniform(0.5, 1.5))
    sweep = depth * np.clip(np.cos(2.0 * np.pi * t / period + float(rng.uniform(0.0, 6.3))), 0.0, None) ** 4
    cooled = lowpass(fan * float(rng.uniform(1.5, 4.0)), dt, float(rng.uniform(8.0, 20.0)))
    return lowpass(base - cooled - fan * sweep, dt, float(rng.uniform(1.5, 4.0)))


LOAD_PATTERNS = {"hoist_chain": load_hoist_chain, "spring_hanger_masses": load_spring_hanger_masses}
TEMPERATURE_PATTERNS = ("exhaust_cooling", "fan_sweep")


def columns(t: Array, v: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record whose muscle pressure is ``v`` [share of
    peak], and their pattern names (independent of the effect)."""
    load_name = tuple(LOAD_PATTERNS)[int(rng.integers(0, len(LOAD_PATTERNS)))]
    temp_name = TEMPERATURE_PATTERNS[int(rng.integers(0, len(TEMPERATURE_PATTERNS)))]
    load = LOAD_PATTERNS[load_name](t, rng)
    temperature = temp_exhaust_cooling(t, rng, v) if temp_name == "exhaust_cooling" else temp_fan_sweep(t, rng)
    return load, temperature, load_name, temp_name


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "air_dashpot":  # air spring over the muscle's stiffness; orifice time [s]
        return {"air_stiffness_ratio": rng.uniform(0.1, 0.35), "orifice_s": rng.uniform(0.05, 0.3)}
    if form == "flywheel_inerter":  # J / (r^2 K) [s^2] (2-5 Hz); damping ratio
        return {"inertance_s2": (2.0 * math.pi * rng.uniform(2.0, 5.0)) ** -2, "inerter_zeta": rng.uniform(0.1, 0.3)}
    if form == "chasset_thirion_cord":  # relaxing share of span; tau0 [s]; exponent
        return {
            "cord_share": rng.uniform(0.03, 0.1),
            "cord_tau_s": rng.uniform(0.05, 0.5),
            "cord_power": rng.uniform(0.1, 0.25),
        }
    if form == "crimp_interchange":  # share of span; time [s]; exhaustion; recovery slowness
        return {
            "crimp_share": rng.uniform(0.03, 0.1),
            "crimp_tau_s": rng.uniform(2.0, 8.0),
            "crimp_exhaustion": rng.uniform(1.0, 3.0),
            "recrimp_factor": rng.uniform(2.0, 5.0),
        }
    if form == "bessel_lvdt_demod":  # group delay [s]
        return {"group_delay_s": rng.uniform(0.012, 0.05)}
    if form == "uart_ascii_stream":  # latency [s]; sensor rate [Hz]; baud; phase
        return {
            "firmware_latency_s": rng.uniform(0.01, 0.04),
            "sensor_hz": rng.uniform(60.0, 150.0),
            "baud": float(rng.choice([19200.0, 38400.0, 57600.0])),
            "sensor_phase": rng.uniform(0.0, 1.0),
        }
    if form == "belleville_anchor":  # stack thickness [mm]; cone height / thickness; flat force / line force
        return {
            "stack_mm": rng.uniform(1.0, 4.0),
            "cone_ratio": rng.uniform(1.0, 1.35),
            "flat_over_line": rng.uniform(0.9, 1.3),
        }
    if form == "bowden_sheath_compression":  # coil gaps [mm]; gap force / payload's; solid [mm/N]; preload [N]
        return {
            "gap_mm": rng.uniform(0.3, 1.5),
            "gap_over_line": rng.uniform(0.3, 1.0),
            "solid_mm_per_n": rng.uniform(0.002, 0.006),
            "cable_preload_n": rng.uniform(5.0, 15.0),
        }
    if form == "thermoelastic_inversion_cord":  # cord force as stroke share; prestretch; stretch range; expansion; lag
        return {
            "cord_mm_share": rng.uniform(1.0, 2.5),
            "cord_prestretch": rng.uniform(0.01, 0.04),
            "cord_stretch": rng.uniform(0.15, 0.35),
            "cord_expansion_per_k": rng.uniform(1.8e-4, 2.4e-4),
            "cord_thermal_tau_s": rng.uniform(5.0, 20.0),
        }
    if form == "drawwire_drum_expansion":  # drum expansion [1/K] (POM to PE); cable out to the carriage [mm]; lag [s]
        return {
            "drum_alpha_per_k": rng.uniform(0.8e-4, 2.0e-4),
            "dead_length_mm": rng.uniform(500.0, 2000.0),
            "drum_tau_s": rng.uniform(8.0, 25.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND8_FORMS}")


def air_dashpot_lag(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The dashpot's lag [mm] of the carriage behind ``x`` [mm]: ``(1 + r) f' = r x' - f / tau``
    (exact for a speed held over each sample): ``r tau v`` when slow, ``r / (1 + r)`` of a jump."""
    r, tau = q["air_stiffness_ratio"], q["orifice_s"]
    keep = math.exp(-dt_s / ((1.0 + r) * tau))
    speed = np.diff(x, prepend=x[0]) / dt_s
    return np.asarray(lfilter([r * tau * (1.0 - keep)], [1.0, -keep], speed), dtype=np.float64)


def chasset_thirion_creep(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The cord's relaxed share [mm x share]: ``sum_k dx_k (1 - (1 + (t - t_k) / tau0)^(-m))``
    (Boltzmann superposition over the stroke ``x``, from rest; FFT convolution)."""
    dx = np.diff(x, prepend=x[0])
    kernel = 1.0 - (1.0 + np.arange(x.size, dtype=np.float64) * dt_s / q["cord_tau_s"]) ** -q["cord_power"]
    n = 1 << int(math.ceil(math.log2(2 * x.size)))
    return np.asarray(np.fft.irfft(np.fft.rfft(dx, n) * np.fft.rfft(kernel, n), n)[: x.size], dtype=np.float64)


def crimp_state(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Crimp taken out of the hoop yarns (0..1): towards ``v^2`` at the rate ``exp(-kappa c) /
    tau`` while below it, at ``1 / (factor tau)`` while above (re-crimping); from none."""
    tau, kappa, slow = q["crimp_tau_s"], q["crimp_exhaustion"], q["recrimp_factor"]
    out = np.empty(v.size)
    c = 0.0
    for i, vi in enumerate(v.tolist()):
        target = min(max(vi, 0.0), 1.2) ** 2
        rate = math.exp(-kappa * c) / tau if c < target else 1.0 / (slow * tau)
        c += (target - c) * (1.0 - math.exp(-dt_s * rate))
        out[i] = c
    return out


def bessel_demodulated(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` through a fourth-order Bessel low-pass of DC group delay ``group_delay_s`` (analog,
    discretised with a first-order hold), at rest on ``x[0]``."""
    b, a = bessel(4, 1.0 / q["group_delay_s"], analog=True, norm="delay")
    num, den, _ = cont2discrete((b, a), dt_s, method="foh")
    bd, ad = np.asarray(num, dtype=np.float64).ravel(), np.asarray(den, dtype=np.float64)
    bd = bd / (bd.sum() / ad.sum())  # unit DC gain exactly
    out, _ = lfilter(bd, ad, x, zi=lfilter_zi(bd, ad) * x[0])
    return np.asarray(out, dtype=np.float64)


def uart_stream(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The logger's view [mm] of ``x``: the sensor samples at ``sensor_hz`` (phase
    ``sensor_phase``), formats ``f"{x:.3f}\\r\\n"`` after ``firmware_latency_s``, the frame
    waits for the line and takes ``10 len / baud``; the last complete frame is held."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    period = 1.0 / q["sensor_hz"]
    stamps = np.arange(q["sensor_phase"] * period, t[-1] + period, period)
    values = np.interp(stamps, t, x)
    done = np.empty(stamps.size)
    line_free = 0.0
    for k, (s, value) in enumerate(zip(stamps.tolist(), values.tolist())):
        start = max(s + q["firmware_latency_s"], line_free)
        line_free = start + 10.0 * (len(f"{value:.3f}") + 2) / q["baud"]
        done[k] = line_free
    which = np.searchsorted(done, t, side="right") - 1
    read = np.round(values * 1000.0) / 1000.0
    return np.asarray(np.where(which >= 0, read[np.clip(which, 0, None)], x[0]), dtype=np.float64)


def line_tension_n(x: Array, load: Array, params: dict[str, float]) -> Array:
    """The line's tension [N]: the payload's weight plus the return stiffness times the stroke."""
    return np.asarray(G_MS2 * load + params["k_total_n_mm"] * x, dtype=np.float64)


def belleville_deflection(tension: Array, q: dict[str, float], reference_n: float) -> Array:
    """The disc stack's deflection [mm]: ``stack_mm s`` where ``F = F_f s ((e - s)(e - s / 2) +
    1) / e`` (Almen-Laszlo, ``s`` the deflection per disc thickness, ``e`` = ``cone_ratio`` <
    sqrt 2 so it stays monotone, ``F_f`` the force at flat, ``flat_over_line`` x the reference
    tension) solved for ``s``."""
    e = q["cone_ratio"]
    s = np.linspace(0.0, 2.0 * e, 801)
    force = s * ((e - s) * (e - s / 2.0) + 1.0) / e
    flat = q["flat_over_line"] * reference_n
    return np.asarray(q["stack_mm"] * np.interp(tension / flat, force, s), dtype=np.float64)


def sheath_compression(tension: Array, q: dict[str, float], reference_n: float) -> Array:
    """The Bowden sheath's shortening [mm] under the cable's tension ``T`` [N]: its coil gaps
    ``gap (1 - exp(-T / T_g))`` (``T_g`` = ``gap_over_line`` x the reference tension [N]) plus
    the solid sheath's ``T L / EA``."""
    closing = q["gap_mm"] * (1.0 - np.exp(-np.clip(tension, 0.0, None) / (q["gap_over_line"] * reference_n)))
    return np.asarray(closing + q["solid_mm_per_n"] * tension, dtype=np.float64)


def cord_force_share(x: Array, span: float, cord_temp: Array, q: dict[str, float]) -> Array:
    """The rubber cord's force as a share of its force at the top of the stroke, at its own
    temperature [degC]: ``(T / T0)(l_e - l_e^-2)``, ``l_e = l / (1 + beta (T - T0))``, ``l = 1 +
    pre + range x / span``, ``T0`` the cord's first temperature."""
    lam = 1.0 + q["cord_prestretch"] + q["cord_stretch"] * np.clip(x / max(span, 1e-9), 0.0, None)
    t0 = float(cord_temp[0]) + T0_K
    ratio = (cord_temp + T0_K) / t0
    lam_e = lam / (1.0 + q["cord_expansion_per_k"] * (cord_temp - cord_temp[0]))
    top = 1.0 + q["cord_prestretch"] + q["cord_stretch"]
    return np.asarray(ratio * (lam_e - lam_e**-2) / (top - top**-2), dtype=np.float64)


def render(
    params: dict[str, float],
    u: Array,
    dt_s: float,
    form: str,
    q: dict[str, float],
    load: Array,
    temperature: Array,
    base: Array,
) -> Array:
    """Noise-free stroke reading [mm] of a core's contraction ``base`` (for the set pressure
    ``u`` [bar]) with the effect ``form`` (``"none"``: switched off), through the rig
    (:func:`~bench.plants.blind8_rig.stroke_reading`).

    The load and temperature forms act through their column's change since the record's start
    (the plant as identified then): with the columns held at their first value they are the
    effect-free plant."""
    x = base
    span = float(np.ptp(x))
    if form == "air_dashpot":
        x = x - air_dashpot_lag(x, dt_s, q)
    elif form == "flywheel_inerter":
        x = second_order(x, dt_s, 1.0 / (2.0 * math.pi * math.sqrt(q["inertance_s2"])), q["inerter_zeta"])
    elif form == "chasset_thirion_cord":
        x = x + q["cord_share"] * chasset_thirion_creep(x, dt_s, q)
    elif form == "crimp_interchange":
        v = np.clip(muscle_pressure(u, dt_s, params) / params["peak"], 0.0, None)
        x = x + q["crimp_share"] * span * crimp_state(v, dt_s, q)
    elif form == "bessel_lvdt_demod":
        x = bessel_demodulated(x, dt_s, q)
    elif form == "uart_ascii_stream":
        x = uart_stream(x, dt_s, q)
    elif form == "belleville_anchor":  # the stack carries the muscle's whole pull
        reference = G_MS2 * float(load[0]) + params["k_total_n_mm"] * 0.5 * span
        held = belleville_deflection(line_tension_n(x, np.full_like(load, load[0]), params), q, reference)
        x = x - (belleville_deflection(line_tension_n(x, load, params), q, reference) - held)
    elif form == "bowden_sheath_compression":  # the cable carries the payload (and its preload) only
        tension = G_MS2 * load + q["cable_preload_n"]
        compressed = sheath_compression(tension, q, float(tension[0]))
        x = x - (compressed - sheath_compression(np.full_like(tension, tension[0]), q, float(tension[0])))
    elif form == "thermoelastic_inversion_cord":
        cord_temp = lowpass(temperature, dt_s, q["cord_thermal_tau_s"])
        share = cord_force_share(x, span, cord_temp, q) - cord_force_share(x, span, np.full_like(x, cord_temp[0]), q)
        x = x - q["cord_mm_share"] * span * share
    elif form == "drawwire_drum_expansion":
        drum = lowpass(temperature, dt_s, q["drum_tau_s"]) - float(temperature[0])
        extension = q["dead_length_mm"] + x
        x = extension / (1.0 + q["drum_alpha_per_k"] * drum) - q["dead_length_mm"]
    return stroke_reading(x, dt_s, params)
