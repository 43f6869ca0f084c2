"""Every effect in two forms unlike :mod:`bench.plants.effects`, and the always-moving columns.

Effects act where a real rig has them: in the input line (a dead time that grows as the
pressure falls; a dead zone the hanging mass opens), inside a core through
:class:`~bench.plants.fresh_cores.Hooks` (a relay/friction threshold growing with the log of the
speed; a viscous element on the hysteresis state; the load in the muscle's force balance with
a stiffening load spring; the bladder's stiffness softening with temperature) or on the output
(power-law creep driven by the pressure; creep that only acts above a pressure level; sensor
latency; temperature through a nonlinear offset plus a gain). Load [kg] and temperature [degC]
columns always move; when they are not the effect they are decoys, and the warming curve is
sometimes a decoy too.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass, variable_delay
from bench.plants.fresh_cores import Core, Hooks

Array = NDArray[np.float64]
FRESH_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("log_threshold", "viscous_state"),
    "creep": ("power_law", "above_pressure"),
    "transport_delay": ("pressure_dependent", "sensor_latency"),
    "load_dependence": ("force_balance", "dead_zone"),
    "temperature_drift": ("offset_gain", "stiffness"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "log_threshold": "widening",
    "viscous_state": "relax_s",
    "power_law": "creep_share",
    "above_pressure": "creep_share",
    "pressure_dependent": "dead_time_scale",
    "sensor_latency": "latency_s",
    "force_balance": "load_scale",
    "dead_zone": "dead_zone_per_kg",
    "offset_gain": "temp_scale",
    "stiffness": "softening_per_k",
}


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_plates(t: Array, rng: np.random.Generator) -> Array:
    """0.5 kg plates put on and taken off by hand (0-6 kg) at 4-8 times, each over 0.5 s."""
    n = int(rng.integers(4, 9))
    times = np.sort(rng.uniform(0.12, 0.95, n)) * t[-1]
    levels = np.round(rng.uniform(0.0, 6.0, n + 1) * 2.0) / 2.0
    if abs(levels[1] - levels[0]) < 1.0:  # at least one clear change
        levels[1] = levels[0] + 2.0 if levels[0] < 3.0 else levels[0] - 2.0
    knots_t, knots_l = [0.0], [float(levels[0])]
    for k, when in enumerate(times.tolist()):
        start = max(when, knots_t[-1] + 0.01)
        knots_t += [start, start + 0.5]
        knots_l += [float(levels[k]), float(levels[k + 1])]
    return np.interp(t, knots_t, knots_l)


def load_bucket(t: Array, rng: np.random.Generator) -> Array:
    """A bucket filled and emptied slowly: linear between 0.5-2.5 kg and 3.5-6 kg, 8-30 s each way."""
    high = bool(rng.integers(0, 2))
    knots_t, knots_l = [0.0], [float(rng.uniform(3.5, 6.0) if high else rng.uniform(0.5, 2.5))]
    while knots_t[-1] < t[-1]:
        high = not high
        knots_t.append(knots_t[-1] + float(rng.uniform(8.0, 30.0)))
        knots_l.append(float(rng.uniform(3.5, 6.0) if high else rng.uniform(0.5, 2.5)))
    return np.interp(t, knots_t, knots_l)


def temp_warming(t: Array, rng: np.random.Generator) -> Array:
    """The muscle warming up from 21-24 degC by 8-18 K with a 20-80 s time constant."""
    return rng.uniform(21.0, 24.0) + rng.uniform(8.0, 18.0) * (1.0 - np.exp(-t / rng.uniform(20.0, 80.0)))


def temp_heat_gun(t: Array, rng: np.random.Generator) -> Array:
    """A heat gun on between 15-35 % and 55-80 % of the record: +10-20 K, 10-30 s lag each way."""
    on = (t >= rng.uniform(0.15, 0.35) * t[-1]) & (t < rng.uniform(0.55, 0.8) * t[-1])
    return rng.uniform(21.0, 24.0) + lowpass(on * rng.uniform(10.0, 20.0), float(t[1] - t[0]), rng.uniform(10.0, 30.0))


def temp_room_hvac(t: Array, rng: np.random.Generator) -> Array:
    """A room whose air conditioning cycles (period 30-90 s, 1-3 K) plus a slow 0.5-2 K wander."""
    dt = float(t[1] - t[0])
    cycle = np.tanh(3.0 * np.sin(2 * np.pi * t / rng.uniform(30.0, 90.0) + rng.uniform(0, 2 * np.pi)))
    wander = lowpass(np.cumsum(rng.normal(0.0, 1.0, t.size)) * np.sqrt(dt), dt, 10.0)
    wander = (wander - wander.mean()) / (np.ptp(wander) or 1.0)
    return rng.uniform(20.0, 25.0) + rng.uniform(0.5, 1.5) * cycle + rng.uniform(0.5, 2.0) * wander


LOAD_PATTERNS = {"plates": load_plates, "bucket": load_bucket}
TEMPERATURE_PATTERNS = {"warming": temp_warming, "heat_gun": temp_heat_gun, "room_hvac": temp_room_hvac}


def columns(t: Array, effect: str, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record, and the names of their patterns.

    A temperature effect gets a warming or a heat gun (enough heat to act); otherwise any of
    the three, so a warming curve also turns up where temperature does nothing.
    """
    load_name = ("plates", "bucket")[int(rng.integers(0, 2))]
    pool = ("warming", "heat_gun") if effect == "temperature_drift" else tuple(TEMPERATURE_PATTERNS)
    temp_name = pool[int(rng.integers(0, len(pool)))]
    return LOAD_PATTERNS[load_name](t, rng), TEMPERATURE_PATTERNS[temp_name](t, rng), load_name, temp_name


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "log_threshold":  # width = 1 + widening * log(1 + speed / v0), speed in peak/s
        return {"widening": rng.uniform(0.15, 0.35), "v0": rng.uniform(0.02, 0.06), "speed_tau_s": 0.3}
    if form == "viscous_state":  # time constant of the hysteresis state's viscous element
        return {"relax_s": rng.uniform(0.08, 0.4)}
    if form == "power_law":  # creep compliance ~ t^exponent over 0.5-500 s, driven by pressure
        return {"creep_share": rng.uniform(0.08, 0.16), "exponent": rng.uniform(0.2, 0.5)}
    if form == "above_pressure":
        return {
            "creep_share": rng.uniform(0.06, 0.12),
            "threshold": rng.uniform(0.4, 0.6),  # of peak
            "tau_up_s": rng.uniform(5.0, 20.0),
            "tau_recover_s": rng.uniform(20.0, 60.0),
        }
    if form == "pressure_dependent":  # dead time [s] = scale * (high + (low - high) exp(-v / 0.25))
        return {
            "dead_time_scale": 1.0,
            "dead_time_high_s": rng.uniform(0.03, 0.08),
            "dead_time_low_s": rng.uniform(0.12, 0.3),
        }
    if form == "sensor_latency":
        return {"latency_s": rng.uniform(0.06, 0.2), "jitter": rng.uniform(0.05, 0.15)}
    if form == "force_balance":  # share of the hanging weight on the muscle (lever); the load spring stiffens
        return {"load_scale": rng.uniform(0.4, 0.8), "spring_stiffening": rng.uniform(0.2, 0.6)}
    if form == "dead_zone":  # fraction of peak per kg
        return {"dead_zone_per_kg": rng.uniform(0.01, 0.025)}
    if form == "offset_gain":  # y (1 + gain (dT/10)) + offset span tanh((dT/12)^2), scaled
        return {"temp_scale": 1.0, "gain_per_10k": rng.uniform(0.02, 0.05), "offset_share": rng.uniform(0.02, 0.05)}
    if form == "stiffness":  # bladder stiffness exp(-softening dT)
        return {"softening_per_k": rng.uniform(0.01, 0.025)}
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {FRESH_FORMS}")


def _gated_creep(v: Array, dt_s: float, q: dict[str, float], span: float) -> Array:
    target = q["creep_share"] * span * np.maximum(0.0, v - q["threshold"]) / (1.0 - q["threshold"])
    up, down = 1.0 - np.exp(-dt_s / q["tau_up_s"]), 1.0 - np.exp(-dt_s / q["tau_recover_s"])
    out = np.empty_like(v)
    s = 0.0
    for i, goal in enumerate(target.tolist()):
        s += (up if goal > s else down) * (goal - s)
        out[i] = s
    return out


def render(
    core: Core,
    params: dict[str, float],
    u: Array,
    dt_s: float,
    form: str,
    q: dict[str, float],
    load: Array,
    temperature: Array,
    span_mm: float,
) -> Array:
    """Noise-free output [mm] of ``core`` with the effect ``form`` (``"none"``: switched off).

    ``span_mm`` is the effect-free output span, the scale of the output-side forms.
    """
    peak = params["peak"]
    n = u.size
    hooks = Hooks.neutral(n)
    drive = u
    d_temp = temperature - temperature[0]
    if form == "log_threshold":
        speed = lowpass(np.abs(np.gradient(u, dt_s)) / peak, dt_s, q["speed_tau_s"])
        hooks = Hooks(1.0 + q["widening"] * np.log1p(speed / q["v0"]), hooks.load_kg, hooks.stiffness)
    elif form == "pressure_dependent":
        level = lowpass(u, dt_s, 0.1) / peak
        dead = q["dead_time_scale"] * (
            q["dead_time_high_s"] + (q["dead_time_low_s"] - q["dead_time_high_s"]) * np.exp(-level / 0.25)
        )
        drive = variable_delay(u, dead / dt_s)
    elif form == "dead_zone":
        zone = np.minimum(q["dead_zone_per_kg"] * load * peak, 0.5 * peak)
        drive = peak * np.maximum(0.0, u - zone) / (peak - zone)
    elif form == "force_balance":
        stiff = 1.0 + q["spring_stiffening"] * q["load_scale"] * load / 6.0
        hooks = Hooks(hooks.width, q["load_scale"] * load, stiff)
    elif form == "stiffness":
        hooks = Hooks(hooks.width, hooks.load_kg, np.exp(-q["softening_per_k"] * d_temp))
    elif form == "viscous_state":
        hooks = Hooks(hooks.width, hooks.load_kg, hooks.stiffness, q["relax_s"])
    x = core(drive, dt_s, params, hooks)
    if form == "power_law":
        taus = np.geomspace(0.5, 500.0, 10)
        weights = taus ** q["exponent"]
        weights /= weights.sum()
        v = u / peak
        x = x + q["creep_share"] * span_mm * sum(w * lowpass(v, dt_s, tau) for w, tau in zip(weights, taus))
    elif form == "above_pressure":
        x = x + _gated_creep(u / peak, dt_s, q, span_mm)
    elif form == "sensor_latency":
        t = np.arange(n) * dt_s
        jitter = 1.0 + q["jitter"] * np.sin(2 * np.pi * t / 37.0) * np.sin(2 * np.pi * t / 11.0)
        x = variable_delay(x, q["latency_s"] * jitter / dt_s)
    elif form == "offset_gain":
        s = q["temp_scale"]
        x = x * (1.0 + s * q["gain_per_10k"] * d_temp / 10.0) + s * q["offset_share"] * span_mm * np.tanh(
            (d_temp / 12.0) ** 2
        )
    return x
