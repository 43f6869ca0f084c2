"""Every effect in two forms none of the other five families uses, and the always-moving columns.

Rate dependence: a payload moving through water (a submerged soft gripper) whose quadratic drag
``c v|v|`` is held by the muscle's stiffness, so the stroke lags by ``c v^2 / K``; a rod seal of
Perzyna viscoplastic rubber, which slides at a rate that is a power ``m`` (1.2-1.6) of its
overstress, so the lag grows as ``v^(1/m)``. Creep: the sleeve's stretched-exponential
(Kohlrausch-Williams-Watts) creep under the pressure's membrane stress, superposed over the
pressure history (Boltzmann, a Prony series fitted to the KWW kernel); braid settling by slip
avalanches, discrete jumps whose Poisson rate grows with the pressure and falls with the slip
already taken, re-seating slowly while vented. Transport delay: the stroke channel on a second
DAQ whose clock runs 0.2-0.6 % slow and is re-synchronised every 15-35 s (a delay that grows
and resets), after a fixed USB latency; a camera marker tracker (30-60 frames/s, the exposure
averages the stroke, frames arrive 1.5-3 frames late and are interpolated). Load dependence:
the payload's change rides on the compliant mounting plate, which sags and rings slower; the
payload pulls through the muscle's tangent stiffness (the sag is larger at low pressure).
Temperature drift: a dome-loaded regulator whose gas reference follows the gas law (the
absolute set pressure times ``T_dome / T_dome(0)`` in kelvin); the silicone grease between the
bladder and the braid, whose yield (a factor on the core's friction, through ``width``) follows
the Vogel-Fulcher-Tammann law ``exp(B / (T - T_v))`` in the grease's lagged temperature.

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: a sand hopper that pours into a bag and a trapdoor that dumps it, or a person
pressing on the payload. Temperature: an infrared lamp switched on and off, or a chiller loop's
relaxation sawtooth.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import nnls

from bench.plants.blind4_cores import Core
from bench.plants.blind4_rig import G_MS2, rig_reading, stiffness_n_mm, supply_droop
from bench.plants.filters import lowpass, variable_delay
from bench.plants.recording import drawn_columns

Array = NDArray[np.float64]
KELVIN = 273.15
ATM_BAR = 1.013
BLIND4_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("hydro_drag", "perzyna_seal"),
    "creep": ("kww_sleeve", "slip_avalanches"),
    "transport_delay": ("clock_drift_resync", "vision_tracker"),
    "load_dependence": ("mount_sag_inertia", "tangent_stiffness_sag"),
    "temperature_drift": ("dome_regulator", "grease_viscosity"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "hydro_drag": "drag_n_s2_mm2",
    "perzyna_seal": "viscosity_scale",
    "kww_sleeve": "creep_share",
    "slip_avalanches": "jump_mm",
    "clock_drift_resync": "skew",
    "vision_tracker": "frame_s",
    "mount_sag_inertia": "payload_share",
    "tangent_stiffness_sag": "load_share",
    "dome_regulator": "dome_share",
    "grease_viscosity": "activation_scale",
}


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_sand_hopper(t: Array, rng: np.random.Generator) -> Array:
    """A bag under a hopper: from 0.3-0.8 kg, the gate opens for 0.6-2 s (pouring 0.3-0.8 kg/s)
    after exponential waits (mean 5 s, the first within 1-4 s); above 2.5-4 kg a trapdoor dumps
    the bag to 0.3-0.8 kg in 1 s."""
    knots_t, knots_l = [0.0, float(rng.uniform(1.0, 4.0))], [float(rng.uniform(0.3, 0.8))] * 2
    full = float(rng.uniform(2.5, 4.0))
    while knots_t[-1] < t[-1]:
        pour = float(rng.uniform(0.6, 2.0))
        knots_t.append(knots_t[-1] + pour)
        knots_l.append(knots_l[-1] + pour * float(rng.uniform(0.3, 0.8)))
        if knots_l[-1] > full:
            knots_t.append(knots_t[-1] + 1.0)
            knots_l.append(float(rng.uniform(0.3, 0.8)))
        knots_t.append(knots_t[-1] + float(rng.exponential(5.0)) + 0.2)
        knots_l.append(knots_l[-1])
    return np.asarray(np.interp(t, knots_t, knots_l), dtype=np.float64)


def load_hand_press(t: Array, rng: np.random.Generator) -> Array:
    """A person pressing on the payload: 0.5-1.5 kg at rest plus presses of 1-3 kg held 1-4 s,
    with raised-cosine edges of 0.3-0.8 s, every 2-8 s (the first within 3 s)."""
    out = np.full_like(t, float(rng.uniform(0.5, 1.5)))
    now = float(rng.uniform(0.5, 3.0))
    while now < t[-1]:
        force, hold, edge = float(rng.uniform(1.0, 3.0)), float(rng.uniform(1.0, 4.0)), float(rng.uniform(0.3, 0.8))
        s = t - now
        rise = 0.5 - 0.5 * np.cos(np.pi * np.clip(s / edge, 0.0, 1.0))
        fall = 0.5 - 0.5 * np.cos(np.pi * np.clip((s - edge - hold) / edge, 0.0, 1.0))
        out += force * (rise - fall)
        now += 2.0 * edge + hold + float(rng.uniform(2.0, 8.0))
    return out


def temp_ir_lamp(t: Array, rng: np.random.Generator) -> Array:
    """An infrared lamp on the rig, on for 12-30 s and off for 10-30 s (starting on after 0-2
    s): heating toward +5-10 K above 19-26 degC with a 4-10 s time constant, cooling back."""
    base, rise = float(rng.uniform(19.0, 26.0)), float(rng.uniform(5.0, 10.0))
    switch, on, now = [], True, float(rng.uniform(0.0, 2.0))
    while now < t[-1]:
        switch.append(now)
        now += float(rng.uniform(12.0, 30.0) if on else rng.uniform(10.0, 30.0))
        on = not on
    lamp = (np.searchsorted(np.asarray(switch), t, side="right") % 2 == 1).astype(np.float64)
    return np.asarray(base + rise * lowpass(lamp, float(t[1] - t[0]), float(rng.uniform(4.0, 10.0))))


def temp_chiller_saw(t: Array, rng: np.random.Generator) -> Array:
    """A chiller loop around the muscle: from the set point (15-22 degC) the coolant warms at
    0.08-0.2 K/s until 3-6 K above it, then the compressor pulls it back with a 2-5 s time
    constant until 0.2 K above the set point; repeat."""
    dt = float(t[1] - t[0])
    rate, band, tau = float(rng.uniform(0.08, 0.2)), float(rng.uniform(3.0, 6.0)), float(rng.uniform(2.0, 5.0))
    out = np.empty_like(t)
    x, cooling = float(rng.uniform(0.2, 1.0)), False
    for i in range(t.size):
        if cooling:
            x -= x * dt / tau
            cooling = x > 0.2
        else:
            x += rate * dt
            cooling = x >= band
        out[i] = x
    return np.asarray(rng.uniform(15.0, 22.0) + out, dtype=np.float64)


LOAD_PATTERNS = {"sand_hopper": load_sand_hopper, "hand_press": load_hand_press}
TEMPERATURE_PATTERNS = {"ir_lamp": temp_ir_lamp, "chiller_saw": temp_chiller_saw}


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record and their pattern names (independent of the effect)."""
    return drawn_columns(LOAD_PATTERNS, TEMPERATURE_PATTERNS, t, rng)


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "hydro_drag":  # quadratic drag coefficient [N s^2 / mm^2]
        return {"drag_n_s2_mm2": rng.uniform(0.01, 0.04)}
    if form == "perzyna_seal":  # seal play [mm], reference rate [mm/s] at 0.3 mm overstress, exponent
        return {
            "viscosity_scale": 1.0,
            "seal_mm": rng.uniform(0.02, 0.05),
            "rate_mm_s": rng.uniform(5.0, 15.0),
            "exponent": rng.uniform(1.2, 1.6),
        }
    if form == "kww_sleeve":  # share of span; KWW time [s] and stretch; stress exponent
        return {
            "creep_share": rng.uniform(0.04, 0.08),
            "tau_s": rng.uniform(15.0, 60.0),
            "beta": rng.uniform(0.35, 0.6),
            "stress_exp": rng.uniform(1.2, 2.0),
        }
    if form == "slip_avalanches":  # mean jump [mm]; rate at full pressure [1/s]; exponent; jumps to
        return {  # saturate; vented re-seating time [s]; seed of the jumps
            "jump_mm": rng.uniform(0.03, 0.08),
            "rate_hz": rng.uniform(0.8, 2.0),
            "stress_exp": rng.uniform(1.5, 2.5),
            "saturation_jumps": rng.uniform(25.0, 60.0),
            "reseat_s": rng.uniform(20.0, 60.0),
            "seed": float(rng.integers(1 << 30)),
        }
    if form == "clock_drift_resync":  # clock skew; resync period [s]; USB latency [s]
        return {
            "skew": rng.uniform(0.002, 0.006),
            "resync_s": rng.uniform(15.0, 35.0),
            "usb_s": rng.uniform(0.004, 0.012),
        }
    if form == "vision_tracker":  # frame period [s]; exposure share of a frame; latency [frames]
        return {
            "frame_s": 1.0 / rng.uniform(30.0, 60.0),
            "exposure_share": rng.uniform(0.3, 0.7),
            "latency_frames": rng.uniform(1.5, 3.0),
        }
    if form == "mount_sag_inertia":
        return {"payload_share": 1.0}
    if form == "tangent_stiffness_sag":  # share of the payload the muscle carries (a counter-spring takes the rest)
        return {"load_share": rng.uniform(0.2, 0.5)}
    if form == "dome_regulator":  # share of the gas law that reaches the set point; dome lag [s]
        return {"dome_share": rng.uniform(0.7, 1.0), "dome_tau_s": rng.uniform(4.0, 12.0)}
    if form == "grease_viscosity":  # Vogel-Fulcher-Tammann B [K] and T_v [K]; grease lag [s]
        return {
            "activation_scale": 1.0,
            "vft_b_k": rng.uniform(900.0, 1400.0),
            "vft_tv_k": rng.uniform(190.0, 215.0),
            "grease_tau_s": rng.uniform(3.0, 10.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND4_FORMS}")


def _hydro_drag(x: Array, dt_s: float, stiffness: Array, c: float) -> Array:
    """Stroke [mm] lagging ``x`` by ``e`` with ``K e = c v |v|``: each sample solves the step
    ``s^2 + beta s = beta |x - y|``, ``beta = dt^2 K / c``, exactly."""
    beta = dt_s * dt_s * stiffness / max(c, 1e-12)
    out = np.empty_like(x)
    y = float(x[0])
    for i, (xi, bi) in enumerate(zip(x.tolist(), beta.tolist())):
        d = xi - y
        s = 0.5 * (math.sqrt(bi * bi + 4.0 * bi * abs(d)) - bi)
        y += s if d > 0.0 else -s
        out[i] = y
    return out


def _perzyna_seal(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Stroke [mm] through a seal that slides at ``rate ((|e| - r) / 0.3 mm)^m / scale`` when the
    lag ``e`` exceeds its play ``r`` (explicit, never past the play)."""
    r, m = q["seal_mm"], q["exponent"]
    gain = dt_s * q["rate_mm_s"] / max(q["viscosity_scale"], 1e-9)
    out = np.empty_like(x)
    y = float(x[0])
    for i, xi in enumerate(x.tolist()):
        over = abs(xi - y) - r
        if over > 0.0:
            s = min(gain * (over / 0.3) ** m, over)
            y += s if xi > y else -s
        out[i] = y
    return out


KWW_TAUS_S = np.geomspace(0.3, 3000.0, 15)


@cache
def _kww_weights(tau_s: float, beta: float) -> tuple[float, ...]:
    """Non-negative Prony weights with ``sum w_j (1 - exp(-t / tau_j)) ~ 1 - exp(-(t / tau)^beta)``."""
    t = np.geomspace(0.05, 5000.0, 120)
    basis = -np.expm1(-t[:, None] / KWW_TAUS_S[None, :])
    w, _ = nnls(basis, -np.expm1(-((t / tau_s) ** beta)))
    return tuple(float(v) for v in w)


def _kww_creep(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Creep [share] under the membrane stress ``v^n``: Boltzmann superposition with the KWW kernel."""
    stress = np.clip(v, 0.0, None) ** q["stress_exp"]
    out = np.zeros_like(v)
    for w, tau in zip(_kww_weights(round(q["tau_s"], 6), round(q["beta"], 6)), KWW_TAUS_S.tolist()):
        if w > 1e-6:
            out += w * lowpass(stress, dt_s, tau)
    return out


def _slip_avalanches(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Accumulated braid slip [mm]: jumps (exponential, mean ``jump``) at the Poisson rate
    ``rate v^n exp(-s / (saturation jump))``; re-seating ``s' = -s (1 - v) / reseat``."""
    rng = np.random.default_rng(int(q["seed"]))
    draws, sizes = rng.random(v.size), rng.exponential(1.0, v.size)
    drive = q["rate_hz"] * dt_s * np.clip(v, 0.0, 1.0) ** q["stress_exp"]
    reseat = dt_s * np.clip(1.0 - v, 0.0, 1.0) / q["reseat_s"]
    sat = q["saturation_jumps"] * q["jump_mm"]
    out = np.empty_like(v)
    s = 0.0
    for i, (di, ri, zi, ki) in enumerate(zip(drive.tolist(), reseat.tolist(), draws.tolist(), sizes.tolist())):
        if zi < di * math.exp(-s / sat):
            s += q["jump_mm"] * ki
        s -= s * ri
        out[i] = s
    return out


def _clock_drift(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x`` read ``usb + skew (t mod resync)`` late (the second DAQ's clock falls behind and is
    re-synchronised)."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    return variable_delay(x, (q["usb_s"] + q["skew"] * (t % q["resync_s"])) / dt_s)


def _vision_tracker(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Camera frames every ``frame`` s, each the mean of ``x`` over its exposure, delivered
    ``latency`` frames after the exposure starts and linearly interpolated by the logger."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    frame, exposure = q["frame_s"], q["exposure_share"] * q["frame_s"]
    starts = np.arange(-q["latency_frames"] * frame, t[-1] + frame, frame)
    offsets = np.linspace(0.0, exposure, 6)
    frames = np.mean([np.interp(starts + o, t, x) for o in offsets], axis=0)
    return np.asarray(np.interp(t, starts + q["latency_frames"] * frame, frames), dtype=np.float64)


def drive_of(u: Array, dt_s: float, form: str, q: dict[str, float], temperature: Array) -> Array:
    """The set pressure [bar] reaching the core: ``u`` unless ``form`` acts on the input side."""
    if form == "dome_regulator":
        dome = lowpass(temperature, dt_s, q["dome_tau_s"]) - temperature[0]
        gas = q["dome_share"] * dome / (temperature[0] + KELVIN)  # the absolute reference moves
        return np.asarray(u + (u + ATM_BAR) * gas, dtype=np.float64)
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
    off), through the rig (:func:`~bench.plants.blind4_rig.rig_reading`).

    ``base`` is the effect-free core output for the drooped supply (computed when not given).
    The load and temperature forms act through the change of their column since the record's
    start (the plant as identified then)."""
    droop = supply_droop(u, dt_s, params)
    if form == "dome_regulator":
        x = core(drive_of(droop, dt_s, form, q, temperature), dt_s, params)
    elif form == "grease_viscosity":
        grease = lowpass(temperature, dt_s, q["grease_tau_s"]) + KELVIN - q["vft_tv_k"]
        vft = q["activation_scale"] * q["vft_b_k"] * (1.0 / grease - 1.0 / grease[0])
        x = core(droop, dt_s, params, np.exp(np.clip(vft, -3.0, 1.1)))  # at most 3x the friction
    else:
        x = core(droop, dt_s, params) if base is None else base
    span = float(np.ptp(x))
    v = np.clip(droop / params["peak"], 0.0, None)
    if form == "hydro_drag":
        x = _hydro_drag(x, dt_s, stiffness_n_mm(droop, params), q["drag_n_s2_mm2"])
    elif form == "perzyna_seal":
        x = _perzyna_seal(x, dt_s, q)
    elif form == "kww_sleeve":
        x = x - q["creep_share"] * span * _kww_creep(v, dt_s, q)
    elif form == "slip_avalanches":
        x = x - _slip_avalanches(v, dt_s, q)
    elif form == "tangent_stiffness_sag":
        x = x - q["load_share"] * G_MS2 * (load - load[0]) / stiffness_n_mm(droop, params)
    if form == "mount_sag_inertia":
        reading = rig_reading(x, dt_s, params, extra_mass_kg=q["payload_share"] * (load - load[0]))
    else:
        reading = rig_reading(x, dt_s, params)
    if form == "clock_drift_resync":
        return _clock_drift(reading, dt_s, q)
    if form == "vision_tracker":
        return _vision_tracker(reading, dt_s, q)
    return reading
