"""Every effect in two forms none of the other three families uses, and the always-moving columns.

Input side (the pressure that reaches the muscle, before the core): a turbulent orifice whose
pressure drop grows with the square of the flow (rate dependence); a fieldbus that delivers the
command after a latency of whole bus cycles with per-cycle jitter; a long line with a dead time
and a reflected echo (transport delay); the valve's pressure sensor whose zero drifts with its
own (lagged) temperature (temperature drift). Output side (after the core): a Zener element
in the rubber (strain-rate stiffening: fast moves are resisted by a relaxing extra stiffness);
Burgers flow (a Maxwell dashpot driven by the pressure's tension, plus a Kelvin part) and an
Eyring (sinh, stress-activated) braid settling that relaxes logarithmically (creep); a payload
pressing a linear guide whose Coulomb friction is the load's weight over the muscle's
pressure-dependent stiffness, and a payload on a lever whose arm changes with the joint angle
(load dependence); a nylon sensor tether that lengthens and softens as it warms, in proportion
to the tension it carries (temperature drift).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Temperature follows clouds passing a window or a thermostat cycling a compressor.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind2_cores import Core, stiffness_n_mm
from bench.plants.filters import lowpass, variable_delay
from bench.plants.recording import drawn_columns

Array = NDArray[np.float64]
BLIND2_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("zener_rubber", "orifice_drop"),
    "creep": ("burgers_flow", "eyring_braid"),
    "transport_delay": ("bus_latency", "line_echo"),
    "load_dependence": ("guide_friction", "lever_geometry"),
    "temperature_drift": ("valve_sensor_offset", "nylon_tether"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "zener_rubber": "stiffening",
    "orifice_drop": "resistance",
    "burgers_flow": "creep_share",
    "eyring_braid": "creep_share",
    "bus_latency": "latency_s",
    "line_echo": "dead_time_s",
    "guide_friction": "mu",
    "lever_geometry": "lever_ratio",
    "valve_sensor_offset": "bar_per_k",
    "nylon_tether": "tether_scale",
}
INPUT_SIDE = ("orifice_drop", "bus_latency", "line_echo", "valve_sensor_offset")


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_dumbbell_sets(t: Array, rng: np.random.Generator) -> Array:
    """Sets with a 1.5-5 kg weight held for 6-18 s, rests of 4-12 s on a 0.2-0.8 kg cradle;
    each pick-up or put-down takes 0.4-1 s."""
    knots_t, knots_l = [0.0], [float(rng.uniform(0.2, 0.8))]
    holding = False
    while knots_t[-1] < t[-1]:
        level = float(rng.uniform(1.5, 5.0) if not holding else rng.uniform(0.2, 0.8))
        move, stay = (
            float(rng.uniform(0.4, 1.0)),
            float(rng.uniform(6.0, 18.0) if not holding else rng.uniform(4.0, 12.0)),
        )
        knots_t += [knots_t[-1] + move, knots_t[-1] + move + stay]
        knots_l += [level, level]
        holding = not holding
    return np.asarray(np.interp(t, knots_t, knots_l), dtype=np.float64)


def load_drip_and_dump(t: Array, rng: np.random.Generator) -> Array:
    """A container filled by a drip from 0.3-1 kg to 2.5-4.5 kg over 12-35 s, then dumped in 1 s."""
    knots_t, knots_l = [0.0], [float(rng.uniform(0.3, 1.0))]
    while knots_t[-1] < t[-1]:
        fill, full, empty = float(rng.uniform(12.0, 35.0)), float(rng.uniform(2.5, 4.5)), float(rng.uniform(0.3, 1.0))
        knots_t += [knots_t[-1] + fill, knots_t[-1] + fill + 1.0]
        knots_l += [full, empty]
    return np.asarray(np.interp(t, knots_t, knots_l), dtype=np.float64)


def temp_clouds(t: Array, rng: np.random.Generator) -> Array:
    """Sun on the rig through a window: clouds pass every 4-15 s for 3-10 s, each cooling the
    surface by 2-6 K, seen through a 2-6 s thermal lag."""
    sun = np.ones_like(t)
    start = float(rng.uniform(0.0, 5.0))
    while start < t[-1]:
        length = float(rng.uniform(3.0, 10.0))
        sun[(t >= start) & (t < start + length)] = 1.0 - rng.uniform(0.4, 1.0)
        start += length + float(rng.uniform(4.0, 15.0))
    heat = sun * rng.uniform(3.0, 6.0)
    return rng.uniform(19.0, 25.0) + lowpass(heat, float(t[1] - t[0]), rng.uniform(2.0, 6.0))


def temp_thermostat(t: Array, rng: np.random.Generator) -> Array:
    """A compressor beside the rig warming the air at 0.2-0.6 K/s until a thermostat starts a
    fan at +3-7 K, which cools at 0.15-0.4 K/s down to +0-1 K, and so on (a hysteresis cycle)."""
    dt = float(t[1] - t[0])
    hi, lo = float(rng.uniform(3.0, 7.0)), float(rng.uniform(0.0, 1.0))
    warm, cool = float(rng.uniform(0.2, 0.6)), float(rng.uniform(0.15, 0.4))
    out = np.empty_like(t)
    x, heating = float(rng.uniform(lo, hi)), bool(rng.integers(0, 2))
    for i in range(t.size):
        x += dt * (warm if heating else -cool)
        if heating and x >= hi:
            heating = False
        elif not heating and x <= lo:
            heating = True
        out[i] = x
    return rng.uniform(19.0, 25.0) + lowpass(out, dt, 1.5)


LOAD_PATTERNS = {"dumbbell_sets": load_dumbbell_sets, "drip_and_dump": load_drip_and_dump}
TEMPERATURE_PATTERNS = {"clouds": temp_clouds, "thermostat": temp_thermostat}


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record and their pattern names (independent of the effect)."""
    return drawn_columns(LOAD_PATTERNS, TEMPERATURE_PATTERNS, t, rng)


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "zener_rubber":  # share of the move the fast extra stiffness takes; its relaxation
        return {"stiffening": rng.uniform(0.15, 0.3), "relax_s": rng.uniform(0.15, 0.6)}
    if form == "orifice_drop":  # p' = sign(e) sqrt(|e|) / resistance [bar^0.5 s]
        return {"resistance": rng.uniform(0.12, 0.25)}
    if form == "burgers_flow":  # Maxwell flow over flow_s plus a Kelvin part (tau), of the span
        return {"creep_share": rng.uniform(0.05, 0.1), "flow_s": 60.0, "kelvin_tau_s": rng.uniform(5.0, 20.0)}
    if form == "eyring_braid":  # z' = (s0 / tau_s) sinh((v - z) / s0): near rest it relaxes in tau_s
        return {"creep_share": rng.uniform(0.06, 0.1), "tau_s": rng.uniform(60.0, 240.0), "s0": rng.uniform(0.08, 0.15)}
    if form == "bus_latency":  # whole bus cycles of cycle_s, +-1 cycle of jitter per cycle
        return {
            "latency_s": rng.uniform(0.05, 0.12),
            "cycle_s": rng.uniform(0.004, 0.01),
            "jitter_seed": float(rng.integers(1 << 30)),
        }
    if form == "line_echo":  # dead time and a reflection arriving 2 dead times later
        return {"dead_time_s": rng.uniform(0.03, 0.07), "reflection": rng.uniform(0.1, 0.3)}
    if form == "guide_friction":  # Coulomb coefficient of the guide the payload presses on
        return {"mu": rng.uniform(0.1, 0.25)}
    if form == "lever_geometry":  # share of the payload's weight at the lever; angle at y = 0; arm [mm]
        return {
            "lever_ratio": rng.uniform(0.12, 0.3),
            "phi0_rad": rng.uniform(-0.5, 0.5),
            "arm_mm": rng.uniform(40.0, 80.0),
        }
    if form == "valve_sensor_offset":  # zero drift of the valve's pressure sensor; valve body lag
        return {"bar_per_k": rng.uniform(0.025, 0.05), "valve_tau_s": rng.uniform(5.0, 20.0)}
    if form == "nylon_tether":  # length [m], expansion [1/K], compliance [mm/N], softening [1/K], lag [s]
        return {
            "tether_scale": 1.0,
            "length_m": rng.uniform(0.5, 1.5),
            "alpha_per_k": rng.uniform(8e-5, 1.5e-4),
            "compliance_mm_n": rng.uniform(0.02, 0.05),
            "softening_per_k": rng.uniform(0.02, 0.04),
            "tau_s": rng.uniform(5.0, 20.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND2_FORMS}")


def _orifice(u: Array, dt_s: float, resistance: float) -> Array:
    """Muscle pressure [bar] behind a turbulent orifice: ``p' = sign(u - p) sqrt(|u - p|) / R``."""
    out = np.empty_like(u)
    p, g = 0.0, dt_s / max(resistance, 1e-6)
    for i, ui in enumerate(u.tolist()):
        e = ui - p
        step = g * math.sqrt(abs(e))
        p = ui if step >= abs(e) else p + (step if e > 0 else -step)
        out[i] = p
    return out


def _eyring(v: Array, dt_s: float, rate: float, s0: float) -> Array:
    """Stress-activated settling ``z' = rate sinh((v - z) / s0)``, never overshooting ``v``."""
    out = np.empty_like(v)
    z = 0.0
    for i, vi in enumerate(v.tolist()):
        e = vi - z
        step = dt_s * rate * math.sinh(min(abs(e) / s0, 50.0))
        z = vi if step >= abs(e) else z + (step if e > 0 else -step)
        out[i] = z
    return out


def _guide_play(x: Array, radius: Array) -> Array:
    """The guide holds the output while the net force stays within friction: a play of ``radius`` [mm]."""
    out = np.empty_like(x)
    y = float(x[0])
    for i, (xi, ri) in enumerate(zip(x.tolist(), radius.tolist())):
        y = xi - ri if y < xi - ri else xi + ri if y > xi + ri else y
        out[i] = y
    return out


def drive_of(u: Array, dt_s: float, form: str, q: dict[str, float], temperature: Array) -> Array:
    """The pressure [bar] reaching the core: ``u`` unless ``form`` acts on the input side."""
    if form == "orifice_drop":
        return _orifice(u, dt_s, q["resistance"])
    if form == "bus_latency":
        cycle = q["cycle_s"]
        n_cycles = int(u.size * dt_s / cycle) + 2
        jitter = np.random.default_rng(int(q["jitter_seed"])).integers(-1, 2, n_cycles) * cycle
        k = (np.arange(u.size) * dt_s / cycle).astype(int)
        sampled = u[np.minimum(np.round(k * cycle / dt_s).astype(int), u.size - 1)]  # read once per cycle
        lag = (max(q["latency_s"], cycle) + jitter[k]) / dt_s
        return variable_delay(sampled, lag)
    if form == "line_echo":
        d = q["dead_time_s"] / dt_s
        r = min(q["reflection"], 0.6)
        lag = np.full(u.size, d)
        return (1.0 - r) * variable_delay(u, lag) + r * variable_delay(u, 3.0 * lag)
    if form == "valve_sensor_offset":
        valve_t = lowpass(temperature, dt_s, q["valve_tau_s"]) - temperature[0]
        return np.asarray(np.clip(u - q["bar_per_k"] * valve_t, 0.0, None), dtype=np.float64)
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
    """Noise-free output [mm] of ``core`` with the effect ``form`` (``"none"``: switched off).

    ``base`` is the effect-free core output (computed when not given): the output-side forms
    start from it and take their scale from its span.
    """
    if form in INPUT_SIDE:
        return core(drive_of(u, dt_s, form, q, temperature), dt_s, params)
    x = core(u, dt_s, params) if base is None else base
    span = float(np.ptp(x))
    v = np.clip(u / params["peak"], 0.0, None)
    if form == "zener_rubber":
        return x - min(q["stiffening"], 0.9) * (x - lowpass(x, dt_s, q["relax_s"]))
    if form == "burgers_flow":
        flow = np.cumsum(v) * dt_s / q["flow_s"]
        return x + 0.5 * q["creep_share"] * span * (flow + lowpass(v, dt_s, q["kelvin_tau_s"]))
    if form == "eyring_braid":
        return x + q["creep_share"] * span * _eyring(v, dt_s, q["s0"] / q["tau_s"], q["s0"])
    if form == "guide_friction":
        return _guide_play(x, q["mu"] * 9.81 * load / stiffness_n_mm(u, params))
    if form == "lever_geometry":
        angle = q["phi0_rad"] + x / q["arm_mm"]
        sagged = x - q["lever_ratio"] * 9.81 * load * np.cos(angle) / stiffness_n_mm(u, params)
        return np.asarray(np.maximum(sagged, np.minimum(x, 0.0)), dtype=np.float64)  # the rest stop holds
    if form == "nylon_tether":
        dtemp = lowpass(temperature, dt_s, q["tau_s"]) - temperature[0]
        tension = 20.0 + stiffness_n_mm(u, params) * x  # N: sensor spring preload plus the muscle's pull
        stretch = q["length_m"] * 1000.0 * q["alpha_per_k"] * dtemp
        stretch = stretch + q["compliance_mm_n"] * tension * np.expm1(q["softening_per_k"] * dtemp)
        return x - q["tether_scale"] * stretch
    return x
