"""Every effect in two forms none of the other seven families uses, and the always-moving columns.

Rate dependence: a *squeeze film* of lubricant between the bladder and the braid (the braid
follows the bladder through a film whose damping grows as ``1 / h^3`` while the pressure presses
the gap ``h`` thin: a lag whose time constant grows as ``(1 + c v)^3``); a *one-way* hydraulic
damper on the payload carriage (its check valve lets the contraction through and damps only the
return, so only the falling branch lags, by more the faster it falls). Creep: *Bailey-Orowan*
recovery-hardening creep of the sleeve (a power-law creep rate in the stress above a back
stress that hardens with the creep and recovers statically, so it keeps a slow secondary creep
while pressurised and creeps back vented); *hold slip* of the braid's fibre crossings (while the
pressure stays within a small band, the stuck crossings creep on in the direction of the last
move, logarithmically in the hold time, in proportion to the normal force; travel wipes the slip
out again). Transport delay: a *pilot-operated* valve whose pilot chamber must fill before the
spool moves (a dead time that is longest for slow, small changes of the set pressure and
shrinks as the pilot's pressure difference grows); a *radio* link from the stroke sensor (a
latency plus, per packet of a 7.5-30 ms connection interval, a jitter, and a retransmission of
3 % of the packets one interval later; samples are replayed in order). Load dependence: an
*elastic catenary*: a long cable from the muscle to the payload's carriage sags by ``w^2 l^3 /
24 T^2`` and stretches by ``T l / EA`` (the payload's weight changes its tension ``T`` and so the
stroke the payload sees); a preloaded *overload spring* (a mechanical fuse in the load path that
gives only when the tension exceeds its preload, with a soft knee). Temperature drift: the PTFE
liner of the braid's sleeve passes its *crystal transitions* near 19 and 30 degC (its friction,
the core's loop-making element, changes in two broad steps, after the liner's thermal lag); a
*sealed air spring* returning the payload whose gas pressure follows its (lagged) temperature by
the gas law, so the return force and the stroke change.

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: a payload hanging half in a water bath whose level a pump raises and lowers
(buoyancy), or a second air cylinder pressing on the payload at stepped preloads with a slow
wobble. Temperature: a hot-air blower under a PID controller stepping its set point (with the
loop's overshoot), or a water jacket swapped between cold and warm water.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind6_cores import Core
from bench.plants.blind6_rig import G_MS2, KELVIN, stroke_reading
from bench.plants.filters import lowpass, resonance, variable_delay
from bench.plants.recording import drawn_columns

Array = NDArray[np.float64]
BLIND6_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("squeeze_film", "one_way_damper"),
    "creep": ("bailey_orowan", "hold_slip_log"),
    "transport_delay": ("pilot_fill_time", "packet_radio"),
    "load_dependence": ("elastic_catenary", "overload_spring"),
    "temperature_drift": ("ptfe_transition", "sealed_air_spring"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "squeeze_film": "film_tau_s",
    "one_way_damper": "damper_tau_s",
    "bailey_orowan": "creep_share",
    "hold_slip_log": "slip_share",
    "pilot_fill_time": "pilot_dead_s",
    "packet_radio": "latency_s",
    "elastic_catenary": "cable_scale",
    "overload_spring": "compliance_mm_per_n",
    "ptfe_transition": "transition_gain",
    "sealed_air_spring": "spring_area_mm2",
}
PILOT_REF_SPEED = 0.5  # [peak/s] the set-pressure speed at which the pilot's dead time is 1.5 x its minimum
MAX_FILM_S = 0.4  # [s] the longest lag of the squeeze film
MAX_PILOT_S = 0.3  # [s] the slowest a pilot-operated valve of this size answers


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_water_bath(t: Array, rng: np.random.Generator) -> Array:
    """A 2-5 kg payload with 0.6-1.5 l of it under water at most: a pump raises and lowers the
    bath's level between 10-30 % and 70-95 % of that depth (ramps of 4-12 s, holds of 2-8 s), the
    buoyancy (1 kg/l) lightening the load; the load cell sees it through a 0.2 s lag."""
    mass, volume = float(rng.uniform(2.0, 5.0)), float(rng.uniform(0.6, 1.5))
    knots_t, knots_f = [0.0], [float(rng.uniform(0.1, 0.9))]
    while knots_t[-1] < t[-1]:
        level = float(rng.uniform(0.1, 0.3)) if knots_f[-1] > 0.5 else float(rng.uniform(0.7, 0.95))
        knots_t += [knots_t[-1] + float(rng.uniform(4.0, 12.0)), 0.0]
        knots_t[-1] = knots_t[-2] + float(rng.uniform(2.0, 8.0))
        knots_f += [level, level]
    submerged = np.interp(t, knots_t, knots_f)
    return lowpass(np.asarray(mass - volume * submerged, dtype=np.float64), float(t[1] - t[0]), 0.2)


def load_cylinder_preload(t: Array, rng: np.random.Generator) -> Array:
    """A second air cylinder pressing on the payload [kg-force]: stepped preloads of 0.5-4 kg every
    5-20 s, each reached through its valve's 0.3-0.8 s lag, plus a 0.05-0.15 kg wobble at
    0.1-0.3 Hz (its regulator hunting)."""
    dt = float(t[1] - t[0])
    steps = np.empty_like(t)
    now, level = 0.0, float(rng.uniform(0.5, 4.0))
    while now < t[-1] + dt:
        stop = now + float(rng.uniform(5.0, 20.0))
        steps[(t >= now) & (t < stop)] = level
        now, level = stop, float(rng.uniform(0.5, 4.0))
    wobble = float(rng.uniform(0.05, 0.15)) * np.sin(2 * np.pi * float(rng.uniform(0.1, 0.3)) * t + rng.uniform(0, 6.3))
    return np.asarray(lowpass(steps, dt, float(rng.uniform(0.3, 0.8))) + wobble, dtype=np.float64)


def temp_pid_blower(t: Array, rng: np.random.Generator) -> Array:
    """A hot-air blower on the rig under a PID loop: its set point steps between 22 and 34 degC
    every 20-45 s, the air answering as a second-order loop (0.01-0.03 Hz, damping 0.4-0.7: an
    overshoot), from a 20-24 degC room."""
    dt = float(t[1] - t[0])
    room = float(rng.uniform(20.0, 24.0))
    setpoint = np.empty_like(t)
    now, level = 0.0, float(rng.uniform(26.0, 34.0))
    while now < t[-1] + dt:
        stop = now + float(rng.uniform(20.0, 45.0))
        setpoint[(t >= now) & (t < stop)] = level
        now, level = stop, float(rng.uniform(22.0, 34.0))
    air = resonance(
        np.concatenate([[room], setpoint]), dt, float(rng.uniform(0.01, 0.03)), float(rng.uniform(0.4, 0.7))
    )
    return np.asarray(air[1:], dtype=np.float64)


def temp_water_jacket(t: Array, rng: np.random.Generator) -> Array:
    """A water jacket around the muscle swapped between cold (16-21 degC) and warm (27-34 degC)
    water every 15-40 s, the jacket's wall following each swap with a 6-15 s lag."""
    dt = float(t[1] - t[0])
    water = np.empty_like(t)
    now, warm = 0.0, bool(rng.random() < 0.5)
    while now < t[-1] + dt:
        stop = now + float(rng.uniform(15.0, 40.0))
        water[(t >= now) & (t < stop)] = float(rng.uniform(27.0, 34.0) if warm else rng.uniform(16.0, 21.0))
        now, warm = stop, not warm
    start = float(rng.uniform(20.0, 26.0))
    return lowpass(np.concatenate([[start], water]), dt, float(rng.uniform(6.0, 15.0)))[1:]


LOAD_PATTERNS = {"water_bath": load_water_bath, "cylinder_preload": load_cylinder_preload}
TEMPERATURE_PATTERNS = {"pid_blower": temp_pid_blower, "water_jacket": temp_water_jacket}


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record and their pattern names (independent of the effect)."""
    return drawn_columns(LOAD_PATTERNS, TEMPERATURE_PATTERNS, t, rng)


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "squeeze_film":  # lag [s] vented; thinning of the gap per peak pressure
        return {"film_tau_s": rng.uniform(0.01, 0.04), "thinning": rng.uniform(0.4, 1.0)}
    if form == "one_way_damper":  # damper time constant c / K [s]
        return {"damper_tau_s": rng.uniform(0.03, 0.12)}
    if form == "bailey_orowan":  # share of span per unit creep; stress exponent; creep and recovery times [s]
        return {
            "creep_share": rng.uniform(0.03, 0.08),
            "stress_power": rng.uniform(1.0, 1.5),
            "rate_exp": rng.uniform(1.5, 3.0),
            "creep_tau_s": rng.uniform(3.0, 10.0),
            "recovery_tau_s": rng.uniform(40.0, 150.0),
        }
    if form == "hold_slip_log":  # share of span after 20 s; time scale [s]; wiping travel [peak]
        return {
            "slip_share": rng.uniform(0.08, 0.2),
            "slip_t0_s": rng.uniform(0.3, 2.0),
            "band": rng.uniform(0.03, 0.07),
        }
    if form == "pilot_fill_time":  # shortest pilot dead time [s]
        return {"pilot_dead_s": rng.uniform(0.02, 0.08)}
    if form == "packet_radio":  # latency [s]; connection interval [s]; jitter share; seed of the packets
        return {
            "latency_s": rng.uniform(0.02, 0.09),
            "interval_s": rng.uniform(0.0075, 0.03),
            "jitter": rng.uniform(0.5, 1.0),
            "radio_seed": float(rng.integers(0, 2**31)),
        }
    if form == "elastic_catenary":  # cable weight [N/m], length [m], EA [N], pretension [N]
        return {
            "cable_scale": 1.0,
            "cable_n_m": rng.uniform(1.0, 3.0),
            "cable_m": rng.uniform(1.5, 3.0),
            "ea_n": rng.uniform(30e3, 80e3),
            "pretension_n": rng.uniform(10.0, 25.0),
        }
    if form == "overload_spring":  # compliance past the preload [mm/N]; preload (share of the stroke); knee [N]
        return {"compliance_mm_per_n": rng.uniform(0.02, 0.08), "preload_share": rng.uniform(0.3, 0.7), "knee_n": 2.0}
    if form == "ptfe_transition":  # friction change across the transitions; widths [K]; liner lag [s]
        return {
            "transition_gain": rng.uniform(0.8, 1.8),
            "width_19_k": rng.uniform(2.0, 4.0),
            "width_30_k": rng.uniform(2.0, 4.0),
            "liner_tau_s": rng.uniform(5.0, 20.0),
        }
    if form == "sealed_air_spring":  # piston area [mm^2]; fill pressure [bar abs]; gas column [mm]; lag [s]
        return {
            "spring_area_mm2": rng.uniform(400.0, 1500.0),
            "fill_bar_abs": rng.uniform(2.0, 4.0),
            "column_mm": rng.uniform(60.0, 150.0),
            "gas_tau_s": rng.uniform(10.0, 40.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND6_FORMS}")


def squeeze_film(x: Array, v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` [mm] through a lag of time constant ``tau0 (1 + c v)^3`` (exact per sample), at most
    :data:`MAX_FILM_S` (the film squeezed to its asperities)."""
    tau = np.minimum(q["film_tau_s"] * (1.0 + q["thinning"] * np.clip(v, 0.0, None)) ** 3, MAX_FILM_S)
    keep = np.exp(-dt_s / np.maximum(tau, 1e-9)).tolist()
    out = np.empty_like(x)
    y = float(x[0])
    for i, (xi, k) in enumerate(zip(x.tolist(), keep)):
        y = xi + (y - xi) * k
        out[i] = y
    return out


def one_way_damper(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` [mm] followed at once while it rises, through a lag ``damper_tau_s`` while below."""
    keep = math.exp(-dt_s / max(q["damper_tau_s"], 1e-9))
    out = np.empty_like(x)
    y = float(x[0])
    for i, xi in enumerate(x.tolist()):
        y = xi if xi >= y else xi + (y - xi) * keep
        out[i] = y
    return out


def bailey_orowan(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Creep [stress units]: ``c' = sign(s_a - b) |s_a - b|^n / tau_c``, ``s_a = v^m``, the back
    stress ``b' = c' - b / tau_r`` (hardening, static recovery); explicit, from rest."""
    stress = (np.clip(v, 0.0, None) ** q["stress_power"]).tolist()
    n, tau_c, tau_r = q["rate_exp"], q["creep_tau_s"], q["recovery_tau_s"]
    out = np.empty_like(v)
    c = b = 0.0
    for i, s in enumerate(stress):
        over = s - b
        rate = math.copysign(abs(over) ** n, over) / tau_c
        c += rate * dt_s
        b += (rate - b / tau_r) * dt_s
        out[i] = c
    return out


def hold_slip_log(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Slip [share of the 20 s slip]: while ``v`` stays within ``band`` of where it settled, the
    slip grows by ``v d ln(1 + t_hold / t0)`` in the direction of the last move; every bit of
    travel ``dv`` wipes a share ``|dv| / band`` of it out."""
    t0, band = q["slip_t0_s"], q["band"]
    norm = math.log1p(20.0 / t0)
    out = np.empty_like(v)
    anchor, direction, hold, slip, prev = float(v[0]), 1.0, 0.0, 0.0, float(v[0])
    for i, vi in enumerate(v.tolist()):
        slip *= math.exp(-abs(vi - prev) / band)
        if abs(vi - anchor) > band:
            direction, anchor, hold = math.copysign(1.0, vi - anchor), vi, 0.0
        else:
            slip += direction * max(vi, 0.0) * (math.log1p((hold + dt_s) / t0) - math.log1p(hold / t0)) / norm
            hold += dt_s
        out[i] = slip
        prev = vi
    return out


def pilot_lag_s(u: Array, dt_s: float, q: dict[str, float], peak: float) -> Array:
    """The pilot's dead time [s]: ``pilot_dead_s (1 + 1 / (1 + r / r0))`` for the set pressure's
    speed ``r`` (smoothed over 50 ms, [peak/s]), ``r0`` = :data:`PILOT_REF_SPEED`, at most
    :data:`MAX_PILOT_S`."""
    speed = np.abs(np.gradient(lowpass(u, dt_s, 0.05), dt_s)) / peak
    lag = q["pilot_dead_s"] * (1.0 + 1.0 / (1.0 + speed / PILOT_REF_SPEED))
    return np.asarray(np.minimum(lag, MAX_PILOT_S), dtype=np.float64)


def radio_lag_s(n: int, dt_s: float, q: dict[str, float]) -> Array:
    """The radio link's delay [s] of each sample: the latency plus its packet's jitter (uniform,
    up to ``jitter`` intervals) plus one interval for the 3 % of the packets sent again."""
    rng = np.random.default_rng(int(q["radio_seed"]))
    packet = (np.arange(n) * dt_s / q["interval_s"]).astype(np.int64)
    count = int(packet[-1]) + 1
    extra = q["jitter"] * rng.random(count) + (rng.random(count) < 0.03)
    return np.asarray(q["latency_s"] + q["interval_s"] * extra[packet], dtype=np.float64)


def cable_give_mm(tension_n: Array, q: dict[str, float]) -> Array:
    """What the catenary cable takes of the stroke [mm]: its sag ``w^2 l^3 / (24 T^2)`` plus its
    stretch ``T l / EA``, times ``cable_scale`` (the tension kept above 2 N)."""
    tension = np.maximum(tension_n, 2.0)
    sag = q["cable_n_m"] ** 2 * q["cable_m"] ** 3 / (24.0 * tension * tension)
    return np.asarray(1000.0 * q["cable_scale"] * (sag + tension * q["cable_m"] / q["ea_n"]), dtype=np.float64)


def drive_of(u: Array, dt_s: float, form: str, q: dict[str, float], peak: float) -> Array:
    """The set pressure [bar] reaching the core: ``u`` unless ``form`` acts on the input side."""
    if form == "pilot_fill_time":
        return variable_delay(u, pilot_lag_s(u, dt_s, q, peak) / dt_s)
    return u


def liner_width(temperature: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Friction factor of the PTFE liner: ``1 + gain (S(T_l) - S(T_l(0)))``, ``S`` two logistic
    steps at 19 and 30 degC (the second half as high), ``T_l`` the temperature through the
    liner's lag; never below 0.2."""
    liner = lowpass(temperature, dt_s, q["liner_tau_s"])

    def steps(x: Array) -> Array:
        low = 1.0 / (1.0 + np.exp(-(x - 19.0) / q["width_19_k"]))
        high = 0.5 / (1.0 + np.exp(-(x - 30.0) / q["width_30_k"]))
        return np.asarray(low + high, dtype=np.float64)

    s = steps(liner)
    return np.asarray(np.clip(1.0 + q["transition_gain"] * (s - s[0]), 0.2, None), dtype=np.float64)


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
    off), through the rig (:func:`~bench.plants.blind6_rig.stroke_reading`).

    ``base`` is the effect-free core output (computed when not given). The load and temperature
    forms act through their column's change since the record's start (the plant as identified
    then: the cable's sag and the spring's give at the starting payload are part of it): with the
    columns held at their first value they are the effect-free plant."""
    peak = params["peak"]
    if form == "pilot_fill_time":
        x = core(drive_of(u, dt_s, form, q, peak), dt_s, params)
    elif form == "ptfe_transition":
        x = core(u, dt_s, params, liner_width(temperature, dt_s, q))
    else:
        x = core(u, dt_s, params) if base is None else base
    span = float(np.ptp(x))
    v = np.clip(u / peak, 0.0, None)
    k_load = params["k_load_n_mm"]
    if form == "squeeze_film":
        x = squeeze_film(x, v, dt_s, q)
    elif form == "one_way_damper":
        x = one_way_damper(x, dt_s, q)
    elif form == "bailey_orowan":
        x = x + q["creep_share"] * span * bailey_orowan(v, dt_s, q)
    elif form == "hold_slip_log":
        x = x + q["slip_share"] * span * hold_slip_log(v, dt_s, q)
    elif form == "packet_radio":
        x = variable_delay(x, radio_lag_s(x.size, dt_s, q) / dt_s)
    elif form == "elastic_catenary":
        tension = G_MS2 * np.clip(load, 0.0, None) + q["pretension_n"] + k_load * x
        held = G_MS2 * max(float(load[0]), 0.0) + q["pretension_n"] + k_load * x
        x = x - (cable_give_mm(tension, q) - cable_give_mm(held, q))
    elif form == "overload_spring":
        tension = G_MS2 * np.clip(load, 0.0, None) + k_load * x
        preload = G_MS2 * max(float(load[0]), 0.0) + k_load * q["preload_share"] * span
        knee = q["knee_n"]
        held = G_MS2 * max(float(load[0]), 0.0) + k_load * x
        give = knee * (np.logaddexp(0.0, (tension - preload) / knee) - np.logaddexp(0.0, (held - preload) / knee))
        x = x - q["compliance_mm_per_n"] * give
    elif form == "sealed_air_spring":
        gas = lowpass(temperature, dt_s, q["gas_tau_s"]) + KELVIN
        column = q["column_mm"]
        force = 0.1 * q["fill_bar_abs"] * q["spring_area_mm2"] * (gas / gas[0] - 1.0) * column / (column - x)
        x = x - force / k_load
    return stroke_reading(x, u, dt_s, params)
