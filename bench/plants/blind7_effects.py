"""Every effect in two forms none of the other eight families uses, and the always-moving columns.

Rate dependence: an *eddy-current brake* on the carriage (an aluminium fin in a magnet gap: its
drag grows with the speed and then, past the critical speed where the skin effect sets in,
falls, ``F = 2 F_max (v / v_c) / (1 + (v / v_c)^2)``; quasi-static behind the muscle's
stiffness, so the stroke lags by a share growing with the speed up to the brake's hold, then the
carriage slides along at that hold); a *shear-thickening* fill between the bladder and the
sleeve (the damping ``c (1 + (|v| / v*)^m)`` is negligible below a critical speed and grows
steeply above it: slow moves are not lagged at all, fast ones are). Creep: *Andrade* transient
creep of the sleeve (a compliance ``~ t^(1/3)``, superposed linearly over the pressure history:
Boltzmann's hereditary integral, evaluated by FFT); the bladder *pulling out* of its crimped end
fitting (an irreversible slip whose speed grows as a power of the tension above a threshold and
slows as the fitting's barbs bite: the stroke sinks while the pressure is high and never comes
back). Transport delay: an *ultrasonic ranging* stroke sensor (pings at 25-60 Hz, each reading
the echo's time of flight, ``2 (d0 + x) / c``, and ready after a processing latency; the logger
holds the last reading); the stroke DAQ's clock slaved by *PTP* to the pressure DAQ's, its
offset (the delay) wandering about its mean as an Ornstein-Uhlenbeck process as the servo hunts.
Load dependence: the frame stands on *foam pads* (open-cell foam: linear, then a plateau where
the cells buckle, by Gibson-Ashby; viscous, so it sinks over 0.5-3 s after each change of the
weight it carries), which moves the muscle against the stand-mounted stroke sensor; the
cantilevered frame's bolted joint *slips* (a play in the moment, i.e. in the payload) and the
frame's tilt reads on the stroke sensor as an Abbe error growing with the carriage's distance.
Temperature drift: the carriage's polyurethane *end-stop bumper* softens as it warms (an
exponential shift in its own lagged temperature), so only strokes that press into it (the top of
the range) change; the stroke sensor's two *half-bridge coils* sit at different distances from
the air (two thermal lags), and the bridge reads their temperature *difference*: a shift that
appears while the temperature changes and fades when it settles (band-pass in temperature).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: items on a conveyor rolling over the payload's plate one after another, or a
ratchet tensioner adding load in clicks and released at once. Temperature: an operator passing
a heat gun over the muscle, or the valve's solenoid coil warming with the duty it works at (the
sensor on the manifold: a decoy that follows the input's slow mean).
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from bench.plants.blind7_rig import stroke_reading
from bench.plants.filters import lowpass, variable_delay

Array = NDArray[np.float64]
BLIND7_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("eddy_current_brake", "shear_thickening_fill"),
    "creep": ("andrade_hereditary", "fitting_pullout"),
    "transport_delay": ("ultrasonic_ranging", "ptp_sync_wander"),
    "load_dependence": ("foam_pad_sink", "joint_slip_tilt"),
    "temperature_drift": ("bumper_softening", "coil_gradient_bridge"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "eddy_current_brake": "brake_hold_mm",
    "shear_thickening_fill": "fill_tau_s",
    "andrade_hereditary": "andrade_share",
    "fitting_pullout": "pullout_share",
    "ultrasonic_ranging": "processing_s",
    "ptp_sync_wander": "mean_delay_s",
    "foam_pad_sink": "pad_scale",
    "joint_slip_tilt": "tilt_mm_per_kg",
    "bumper_softening": "softening_per_k",
    "coil_gradient_bridge": "bridge_mm_per_k",
}
SPEED_SOUND_MM_S = 343e3
G_MS2 = 9.81


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_conveyor_items(t: Array, rng: np.random.Generator) -> Array:
    """A 1-3 kg plate that items of 0.3-1.2 kg roll over, one every 2-10 s (exponential), each
    on it for 1-3 s with 0.2 s ramps on and off."""
    load = np.full_like(t, float(rng.uniform(1.0, 3.0)))
    now = float(rng.uniform(0.0, 3.0))
    while now < t[-1]:
        mass, stay = float(rng.uniform(0.3, 1.2)), float(rng.uniform(1.0, 3.0))
        load += mass * np.clip(np.minimum(t - now, now + stay - t) / 0.2, 0.0, 1.0)
        now += stay + float(rng.exponential(4.0)) + 1.0
    return load


def load_ratchet_tensioner(t: Array, rng: np.random.Generator) -> Array:
    """A ratchet tensioner on the payload's line: clicks of 0.08-0.2 kg every 1-4 s from 0.5-1
    kg up to 2.5-5 kg, then released at once (in 0.3 s) and cranked up again."""
    base = float(rng.uniform(0.5, 1.0))
    knots_t, knots_f = [0.0], [base]
    top = float(rng.uniform(2.5, 5.0))
    while knots_t[-1] < t[-1]:
        level = knots_f[-1] + float(rng.uniform(0.08, 0.2))
        if level > top:
            level, top = base, float(rng.uniform(2.5, 5.0))
            knots_t += [knots_t[-1] + float(rng.uniform(1.0, 4.0)), 0.0]
            knots_t[-1] = knots_t[-2] + 0.3
        else:
            knots_t += [knots_t[-1] + float(rng.uniform(1.0, 4.0)), 0.0]
            knots_t[-1] = knots_t[-2] + 0.05
        knots_f += [knots_f[-1], level]
    return np.asarray(np.interp(t, knots_t, knots_f), dtype=np.float64)


def temp_heat_gun_passes(t: Array, rng: np.random.Generator) -> Array:
    """A 20-25 degC room with an operator passing a heat gun over the muscle every 8-30 s for
    2-6 s (heating at 0.8-2 K/s), the muscle's surface cooling back with a 10-25 s lag."""
    dt = float(t[1] - t[0])
    heat = np.zeros_like(t)
    now = float(rng.uniform(0.0, 10.0))
    while now < t[-1]:
        length = float(rng.uniform(2.0, 6.0))
        heat[(t >= now) & (t < now + length)] = float(rng.uniform(0.8, 2.0))
        now += length + float(rng.uniform(8.0, 30.0))
    tau = float(rng.uniform(10.0, 25.0))
    rise = lowpass(np.concatenate([[0.0], heat * tau]), dt, tau)[1:]
    return np.asarray(float(rng.uniform(20.0, 25.0)) + rise, dtype=np.float64)


def temp_coil_self_heating(t: Array, rng: np.random.Generator, duty: Array) -> Array:
    """The valve manifold's temperature: a 19-24 degC room drifting by 0.3-1 K over 100-300 s,
    plus 4-9 K x the valve's duty (the set pressure's share of the peak) through a 15-45 s lag."""
    dt = float(t[1] - t[0])
    room = float(rng.uniform(19.0, 24.0)) + float(rng.uniform(0.3, 1.0)) * np.sin(
        2.0 * np.pi * t / float(rng.uniform(100.0, 300.0)) + float(rng.uniform(0.0, 6.3))
    )
    heating = float(rng.uniform(4.0, 9.0)) * lowpass(np.concatenate([[0.0], duty]), dt, float(rng.uniform(15.0, 45.0)))
    return np.asarray(room + heating[1:], dtype=np.float64)


LOAD_PATTERNS = {"conveyor_items": load_conveyor_items, "ratchet_tensioner": load_ratchet_tensioner}
TEMPERATURE_PATTERNS = ("heat_gun_passes", "coil_self_heating")


def columns(t: Array, u: Array, peak: float, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record driven by the set pressure ``u`` [bar] and
    their pattern names (independent of the effect)."""
    load_name = tuple(LOAD_PATTERNS)[int(rng.integers(0, len(LOAD_PATTERNS)))]
    temp_name = TEMPERATURE_PATTERNS[int(rng.integers(0, len(TEMPERATURE_PATTERNS)))]
    load = LOAD_PATTERNS[load_name](t, rng)
    if temp_name == "heat_gun_passes":
        temperature = temp_heat_gun_passes(t, rng)
    else:
        temperature = temp_coil_self_heating(t, rng, np.clip(u / peak, 0.0, 1.0))
    return load, temperature, load_name, temp_name


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "eddy_current_brake":  # the brake's hold [mm of stroke lag]; critical speed [mm/s]
        return {"brake_hold_mm": rng.uniform(0.3, 1.5), "critical_mm_s": rng.uniform(15.0, 60.0)}
    if form == "shear_thickening_fill":  # lag below the critical speed [s]; critical speed [mm/s]; exponent
        return {
            "fill_tau_s": rng.uniform(0.0008, 0.003),
            "thickening_mm_s": rng.uniform(5.0, 15.0),
            "thickening_power": rng.uniform(1.2, 2.2),
        }
    if form == "andrade_hereditary":  # share of span per unit stress after 20 s; stress exponent
        return {"andrade_share": rng.uniform(0.03, 0.1), "stress_power": rng.uniform(1.0, 2.0)}
    if form == "fitting_pullout":  # share of span after 20 s at peak; threshold [peak]; power; barb bite
        return {
            "pullout_share": rng.uniform(0.03, 0.1),
            "pullout_threshold": rng.uniform(0.3, 0.55),
            "pullout_power": rng.uniform(1.0, 2.5),
            "barb_bite": rng.uniform(0.5, 2.0),
        }
    if form == "ultrasonic_ranging":  # processing latency [s]; ping rate [Hz]; distance to the carriage [mm]
        return {
            "processing_s": rng.uniform(0.01, 0.04),
            "ping_hz": rng.uniform(25.0, 60.0),
            "range_mm": rng.uniform(200.0, 600.0),
            "ping_phase": rng.uniform(0.0, 1.0),
        }
    if form == "ptp_sync_wander":  # mean delay [s]; wander [share of it]; servo time [s]; seed
        return {
            "mean_delay_s": rng.uniform(0.015, 0.06),
            "wander_share": rng.uniform(0.2, 0.4),
            "servo_s": rng.uniform(5.0, 20.0),
            "ptp_seed": float(rng.integers(0, 2**31)),
        }
    if form == "foam_pad_sink":  # scale; elastic compliance [mm/kg]; plateau compliance [mm/kg]; knee; lag [s]
        return {
            "pad_scale": 1.0,
            "elastic_mm_per_kg": rng.uniform(0.02, 0.06),
            "plateau_mm_per_kg": rng.uniform(0.4, 1.2),
            "knee_offset_kg": rng.uniform(-0.2, 0.5),
            "knee_width_kg": rng.uniform(0.15, 0.4),
            "foam_tau_s": rng.uniform(0.5, 3.0),
        }
    if form == "joint_slip_tilt":  # tilt reading [mm/kg at the arm's root]; slip band [kg]; arm [mm]
        return {
            "tilt_mm_per_kg": rng.uniform(0.2, 0.6),
            "slip_kg": rng.uniform(0.03, 0.12),
            "arm_mm": rng.uniform(40.0, 120.0),
        }
    if form == "bumper_softening":  # softening [1/K]; contact [share of stroke]; stiffness ratio; lag [s]
        return {
            "softening_per_k": rng.uniform(0.04, 0.1),
            "contact_share": rng.uniform(0.4, 0.7),
            "bumper_ratio": rng.uniform(0.5, 2.0),
            "bumper_tau_s": rng.uniform(15.0, 40.0),
        }
    if form == "coil_gradient_bridge":  # reading per K of difference [mm/K]; lags [s]; gain slope
        return {
            "bridge_mm_per_k": rng.uniform(0.1, 0.3),
            "near_tau_s": rng.uniform(3.0, 10.0),
            "far_tau_s": rng.uniform(25.0, 80.0),
            "gain_slope": rng.uniform(0.5, 1.5),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND7_FORMS}")


def _lag_through(x: Array, dt_s: float, speed_for: tuple[list[float], list[float]]) -> Array:
    """``x`` [mm] followed by a carriage that moves at the speed ``v(|x - y|)`` (tabulated as
    ``(lags, speeds)``, increasing), stepped exactly as a lag of time constant ``|x - y| / v``;
    a lag past the table's last is held at it (the carriage dragged along)."""
    lags, speeds = speed_for
    top = lags[-1]
    out = np.empty_like(x)
    y = float(x[0])
    for i, xi in enumerate(x.tolist()):
        gap = xi - y
        size = abs(gap)
        if size >= top:  # past the largest tabulated lag: carried along at it
            y = xi - math.copysign(top, gap)
        elif size > 0.0:
            j = min(bisect.bisect_left(lags, size), len(lags) - 1)
            lo = max(j - 1, 0)
            span = lags[j] - lags[lo]
            v = speeds[lo] + (speeds[j] - speeds[lo]) * ((size - lags[lo]) / span if span > 0.0 else 0.0)
            y = xi - math.copysign(size, gap) * math.exp(-dt_s * v / size)
        out[i] = y
    return out


def eddy_current_brake(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` [mm] behind the eddy brake: the lag ``2 h (v / v_c) / (1 + (v / v_c)^2)`` (``h`` =
    ``brake_hold_mm``) held at speed ``v`` on its rising side (``v <= v_c``); a larger lag is
    capped at ``h`` (the carriage slides along at the brake's hold)."""
    ratio = np.linspace(0.0, 1.0, 400)
    lags = 2.0 * q["brake_hold_mm"] * ratio / (1.0 + ratio * ratio)
    return _lag_through(x, dt_s, (lags.tolist(), (ratio * q["critical_mm_s"]).tolist()))


def shear_thickening_fill(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` [mm] behind the fill: the lag ``tau v (1 + (v / v*)^m)`` held at speed ``v``."""
    speeds = np.concatenate([[0.0], np.geomspace(1e-3, 1e4, 600)])
    lags = q["fill_tau_s"] * speeds * (1.0 + (speeds / q["thickening_mm_s"]) ** q["thickening_power"])
    return _lag_through(x, dt_s, (lags.tolist(), speeds.tolist()))


def andrade_creep(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Creep [share of the 20 s creep per unit stress]: ``sum_k ds_k ((t - t_k) / 20 s)^(1/3)``
    over the stress ``s = v^m`` (Boltzmann superposition, from rest; FFT convolution)."""
    stress = np.clip(v, 0.0, None) ** q["stress_power"]
    ds = np.diff(stress, prepend=0.0)
    kernel = (np.arange(v.size, dtype=np.float64) * dt_s / 20.0) ** (1.0 / 3.0)
    n = 1 << int(math.ceil(math.log2(2 * v.size)))
    out = np.fft.irfft(np.fft.rfft(ds, n) * np.fft.rfft(kernel, n), n)[: v.size]
    return np.asarray(out, dtype=np.float64)


def fitting_pullout(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Pull-out [share of 20 s at the peak without the barbs]: ``s' = ((v - theta)+ / (1 -
    theta))^n / (20 s (1 + bite s))``, never decreasing."""
    theta, n, bite = q["pullout_threshold"], q["pullout_power"], q["barb_bite"]
    drive = ((np.clip(v - theta, 0.0, None) / (1.0 - theta)) ** n * dt_s / 20.0).tolist()
    out = np.empty(v.size)
    s = 0.0
    for i, d in enumerate(drive):
        s += d / (1.0 + bite * s)
        out[i] = s
    return out


def ultrasonic_lag(x: Array, dt_s: float, q: dict[str, float], span: float) -> Array:
    """The ranging sensor's reading [mm] of ``x``: pings every ``1 / ping_hz`` (phase
    ``ping_phase``), each the stroke at the echo's return (``2 (d0 + x) / c`` later), ready
    ``processing_s`` after it, the last ready one held (``x[0]`` until the first)."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    period = 1.0 / q["ping_hz"]
    pings = np.arange(q["ping_phase"] * period, t[-1] + period, period)
    flight = 2.0 * (q["range_mm"] + span - np.interp(pings, t, x)) / SPEED_SOUND_MM_S
    echo = pings + flight
    value = np.interp(echo, t, x)
    ready = echo + q["processing_s"]
    which = np.searchsorted(ready, t, side="right") - 1
    return np.asarray(np.where(which >= 0, value[np.clip(which, 0, None)], x[0]), dtype=np.float64)


def ptp_delay_s(n: int, dt_s: float, q: dict[str, float]) -> Array:
    """The PTP-slaved clock's delay [s]: ``d (1 + w z)``, ``z`` a unit Ornstein-Uhlenbeck
    process of time constant ``servo_s`` (seeded by ``ptp_seed``), kept within 0.3-2 x ``d``."""
    rng = np.random.default_rng(int(q["ptp_seed"]))
    keep = math.exp(-dt_s / q["servo_s"])
    kicks = rng.normal(0.0, math.sqrt(1.0 - keep * keep), n)
    kicks[0] = rng.normal()
    z = lfilter([1.0], [1.0, -keep], kicks)
    d = q["mean_delay_s"]
    return np.asarray(np.clip(d * (1.0 + q["wander_share"] * z), 0.3 * d, 2.0 * d), dtype=np.float64)


def foam_sink_mm(load: Array, dt_s: float, q: dict[str, float]) -> Array:
    """How far the pads sink [mm] under the load ``load`` [kg]: ``e W + p w softplus((W -
    W_k) / w)`` (``W_k`` = the starting load plus ``knee_offset_kg``), through the foam's
    viscous lag ``foam_tau_s``, times ``pad_scale``."""
    knee, width = float(load[0]) + q["knee_offset_kg"], q["knee_width_kg"]
    static = q["elastic_mm_per_kg"] * load + q["plateau_mm_per_kg"] * width * np.logaddexp(0.0, (load - knee) / width)
    return np.asarray(q["pad_scale"] * lowpass(static, dt_s, q["foam_tau_s"]), dtype=np.float64)


def joint_slip(load: Array, q: dict[str, float]) -> Array:
    """The joint's slipped moment [kg of payload]: a play of radius ``slip_kg`` on the load's
    change since the start."""
    change = (load - load[0]).tolist()
    r = q["slip_kg"]
    out = np.empty(load.size)
    state = 0.0
    for i, c in enumerate(change):
        state = min(max(state, c - r), c + r)
        out[i] = state
    return out


def bumper_gain(temperature: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Share of the stroke past the contact that the bumper lets through: ``1 / (1 + R
    e^(-beta (T_b - T_b0)))``, ``T_b`` the temperature through the bumper's lag."""
    bumper = lowpass(temperature, dt_s, q["bumper_tau_s"])
    ratio = q["bumper_ratio"] * np.exp(-q["softening_per_k"] * (bumper - bumper[0]))
    return np.asarray(1.0 / (1.0 + ratio), dtype=np.float64)


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
    (:func:`~bench.plants.blind7_rig.stroke_reading`).

    The load and temperature forms act through their column's change since the record's start
    (the plant as identified then): with the columns held at their first value they are the
    effect-free plant."""
    x = base
    span = float(np.ptp(x))
    v = np.clip(u / params["peak"], 0.0, None)
    if form == "eddy_current_brake":
        x = eddy_current_brake(x, dt_s, q)
    elif form == "shear_thickening_fill":
        x = shear_thickening_fill(x, dt_s, q)
    elif form == "andrade_hereditary":
        x = x + q["andrade_share"] * span * andrade_creep(v, dt_s, q)
    elif form == "fitting_pullout":
        x = x - q["pullout_share"] * span * fitting_pullout(v, dt_s, q)
    elif form == "ultrasonic_ranging":
        x = ultrasonic_lag(x, dt_s, q, span)
    elif form == "ptp_sync_wander":
        x = variable_delay(x, ptp_delay_s(x.size, dt_s, q) / dt_s)
    elif form == "foam_pad_sink":
        x = x - (foam_sink_mm(load, dt_s, q) - foam_sink_mm(np.full_like(load, load[0]), dt_s, q))
    elif form == "joint_slip_tilt":
        x = x - q["tilt_mm_per_kg"] * joint_slip(load, q) * (1.0 + x / q["arm_mm"])
    elif form == "bumper_softening":
        contact = q["contact_share"] * float(np.max(x))
        past = 0.05 * span * np.logaddexp(0.0, (x - contact) / (0.05 * span))
        gain = bumper_gain(temperature, dt_s, q)
        x = x + past * (gain - gain[0]) / gain[0]
    elif form == "coil_gradient_bridge":
        difference = lowpass(temperature, dt_s, q["near_tau_s"]) - lowpass(temperature, dt_s, q["far_tau_s"])
        x = x + q["bridge_mm_per_k"] * difference * (1.0 + q["gain_slope"] * (x / max(span, 1e-9) - 0.5))
    return stroke_reading(x, dt_s, params)
