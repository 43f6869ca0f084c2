"""Every effect in two forms unlike the tuning and fresh families', and the always-moving columns.

Effects act where a real rig has them. Input side: a tube whose dead time depends on the flow
direction and the pressure level; a valve controller that updates its command in frames after a
fixed latency (both before the hysteresis). Inside a core through
:class:`~bench.plants.blind_cores.Hooks`: a hysteresis width that saturates with the input speed,
or grows with the excitation frequency (estimated from the time between reversals); the payload
in the muscle's force balance; rubber that stiffens as it warms (entropic elasticity, through the
rubber's own thermal lag). Output side: a Kelvin-Voigt chain with a log-normal spread of time
constants driven by the muscle's tension (pressure and payload: the muscle lengthens); cyclic
ratcheting (the braid beds in with the distance travelled, plus a recoverable Kelvin part); a
payload that lowers the stroke end; the frame's thermal expansion shifting the zero.

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Temperature cycles (a heater switched on and off) and steps (a door, a fan), so it is
not collinear with time.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind_cores import Core, Hooks
from bench.plants.filters import lowpass, variable_delay

Array = NDArray[np.float64]
BLIND_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "creep": ("tension_chain", "cyclic_ratchet"),
    "rate_dependence": ("speed_threshold", "frequency_width"),
    "transport_delay": ("tube_flow", "valve_frames"),
    "load_dependence": ("payload_balance", "stroke_limit"),
    "temperature_drift": ("entropic_rubber", "zero_shift"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "tension_chain": "creep_share",
    "cyclic_ratchet": "creep_share",
    "speed_threshold": "gain",
    "frequency_width": "gain",
    "tube_flow": "dead_time_s",
    "valve_frames": "latency_s",
    "payload_balance": "lever",
    "stroke_limit": "limit_share_per_kg",
    "entropic_rubber": "stiffening_per_k",
    "zero_shift": "zero_share_per_10k",
}


def _asymmetric_lag(x: Array, dt_s: float, tau_up_s: float, tau_down_s: float) -> Array:
    """A lag that follows rises with ``tau_up_s`` and falls with ``tau_down_s`` [s]."""
    up, down = 1.0 - np.exp(-dt_s / tau_up_s), 1.0 - np.exp(-dt_s / tau_down_s)
    out = np.empty_like(x)
    s = float(x[0])
    for i, xi in enumerate(x.tolist()):
        s += (up if xi > s else down) * (xi - s)
        out[i] = s
    return out


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_payload_swap(t: Array, rng: np.random.Generator) -> Array:
    """Payloads of 0-5 kg (not round: bags of parts) swapped by hand every 8-30 s, each in 0.3 s."""
    knots_t, knots_l = [0.0], [float(rng.uniform(0.0, 2.5))]
    while knots_t[-1] < t[-1]:
        hold = float(rng.uniform(8.0, 30.0))
        new = float(rng.uniform(0.0, 5.0))
        if abs(new - knots_l[-1]) < 1.0:
            new = knots_l[-1] + 1.5 if knots_l[-1] < 2.5 else knots_l[-1] - 1.5
        knots_t += [knots_t[-1] + hold, knots_t[-1] + hold + 0.3]
        knots_l += [knots_l[-1], new]
    return np.interp(t, knots_t, knots_l)


def load_winch(t: Array, rng: np.random.Generator) -> Array:
    """A winch pre-tensioning the payload: ramps of 5-20 s between 0.5 and 5 kg, holds of 3-15 s."""
    knots_t, knots_l = [0.0], [float(rng.uniform(0.5, 2.0))]
    while knots_t[-1] < t[-1]:
        ramp, hold = float(rng.uniform(5.0, 20.0)), float(rng.uniform(3.0, 15.0))
        new = float(rng.uniform(3.0, 5.0) if knots_l[-1] < 2.5 else rng.uniform(0.5, 2.0))
        knots_t += [knots_t[-1] + ramp, knots_t[-1] + ramp + hold]
        knots_l += [new, new]
    return np.interp(t, knots_t, knots_l)


def load_pendulum(t: Array, rng: np.random.Generator) -> Array:
    """A swinging payload: 1-3 kg, one 1-2 kg step, and 0.3-0.8 kg sway at 0.6-1.2 Hz after 3-6 kicks."""
    base = rng.uniform(1.0, 3.0) + rng.uniform(1.0, 2.0) * (t > rng.uniform(0.3, 0.7) * t[-1])
    sway = np.zeros_like(t)
    freq, decay = rng.uniform(0.6, 1.2), rng.uniform(3.0, 8.0)
    for kick in rng.uniform(0.05, 0.95, int(rng.integers(3, 7))) * t[-1]:
        after = t >= kick
        sway[after] += (
            rng.uniform(0.3, 0.8) * np.exp(-(t[after] - kick) / decay) * np.sin(2 * np.pi * freq * (t[after] - kick))
        )
    return np.asarray(base + sway, dtype=np.float64)


def temp_heater_cycles(t: Array, rng: np.random.Generator) -> Array:
    """A heater on the muscle switched on for 10-40 s and off for 10-40 s: +6-15 K, heating with a
    6-15 s lag and cooling with a 15-40 s lag (the cycles do not follow time monotonically)."""
    dt = float(t[1] - t[0])
    on = np.zeros_like(t)
    start, state = float(rng.uniform(0.0, 15.0)), True
    while start < t[-1]:
        length = float(rng.uniform(10.0, 40.0))
        if state:
            on[(t >= start) & (t < start + length)] = 1.0
        start, state = start + length, not state
    rise = float(rng.uniform(6.0, 15.0))
    return rng.uniform(20.0, 24.0) + _asymmetric_lag(on * rise, dt, rng.uniform(6.0, 15.0), rng.uniform(15.0, 40.0))


def temp_door_steps(t: Array, rng: np.random.Generator) -> Array:
    """A room whose temperature steps by 3-7 K up or down at 2-4 times (a door, a fan, the sun),
    seen through a 3-8 s sensor lag."""
    n = int(rng.integers(2, 5))
    times = np.sort(rng.uniform(0.1, 0.9, n)) * t[-1]
    levels = np.cumsum(
        np.concatenate([[rng.uniform(19.0, 24.0)], rng.choice([-1.0, 1.0], n) * rng.uniform(3.0, 7.0, n)])
    )
    return lowpass(levels[np.searchsorted(times, t)], float(t[1] - t[0]), rng.uniform(3.0, 8.0))


def temp_warm_hold_cool(t: Array, rng: np.random.Generator) -> Array:
    """A trapezoid: warming by 5-12 K over 20-40 % of the record, a hold, then cooling back part way."""
    a, b = rng.uniform(0.05, 0.2), rng.uniform(0.3, 0.5)
    c = rng.uniform(0.6, 0.8)
    knots = np.array([0.0, a, a + b * (c - a), c, 1.0]) * t[-1]
    rise = rng.uniform(5.0, 12.0)
    return rng.uniform(20.0, 24.0) + np.interp(t, knots, [0.0, 0.0, rise, rise, rise * rng.uniform(0.2, 0.6)])


LOAD_PATTERNS = {"payload_swap": load_payload_swap, "winch": load_winch, "pendulum": load_pendulum}
TEMPERATURE_PATTERNS = {
    "heater_cycles": temp_heater_cycles,
    "door_steps": temp_door_steps,
    "warm_hold_cool": temp_warm_hold_cool,
}


def columns(t: Array, effect: str, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record, and the names of their patterns.

    A load effect gets payload swaps or the winch (clear, lasting changes); a temperature effect
    gets heater cycles or door steps (cycles and steps, not a monotonic warming). Otherwise any
    pattern, so swaying loads and warming curves also turn up where they do nothing.
    """
    loads = ("payload_swap", "winch") if effect == "load_dependence" else tuple(LOAD_PATTERNS)
    temps = ("heater_cycles", "door_steps") if effect == "temperature_drift" else tuple(TEMPERATURE_PATTERNS)
    load_name = loads[int(rng.integers(0, len(loads)))]
    temp_name = temps[int(rng.integers(0, len(temps)))]
    return LOAD_PATTERNS[load_name](t, rng), TEMPERATURE_PATTERNS[temp_name](t, rng), load_name, temp_name


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "tension_chain":  # Kelvin chain, log-normal time constants around tau_c_s, tension v (1 + load/5 kg)
        return {
            "creep_share": rng.uniform(0.06, 0.12),
            "tau_c_s": rng.uniform(8.0, 40.0),
            "log_sd": rng.uniform(0.6, 1.2),
        }
    if form == "cyclic_ratchet":  # bedding-in per travelled stroke, slow recovery; a recoverable Kelvin part
        return {
            "creep_share": rng.uniform(0.06, 0.12),
            "strokes": rng.uniform(3.0, 10.0),  # full strokes of travel to bed in by 63 %
            "recover_s": rng.uniform(60.0, 200.0),
            "kelvin_tau_s": rng.uniform(2.0, 10.0),
        }
    if form == "speed_threshold":  # width 1 + gain s / (s + s0), s = |u'|/peak [1/s]
        return {"gain": rng.uniform(0.5, 1.2), "s0": rng.uniform(0.05, 0.2)}
    if form == "frequency_width":  # width (f / f_ref)^gain in [1/3, 3], f from reversal intervals [Hz]
        return {"gain": rng.uniform(0.15, 0.35), "f_ref_hz": rng.uniform(0.03, 0.08)}
    if form == "tube_flow":  # dead time (1 + level_gain (1 - level)) (vent_ratio when venting)
        return {
            "dead_time_s": rng.uniform(0.03, 0.08),
            "level_gain": rng.uniform(0.5, 1.5),
            "vent_ratio": rng.uniform(1.3, 2.0),
        }
    if form == "valve_frames":  # a command frame of 20-50 ms, applied after a latency
        return {"frame_s": rng.uniform(0.02, 0.05), "latency_s": rng.uniform(0.05, 0.12)}
    if form == "payload_balance":  # lever ratio from the load cell's payload to the muscle
        return {"lever": rng.uniform(0.6, 1.2)}
    if form == "stroke_limit":  # the stroke end drops by this share of the span per kg
        return {"limit_share_per_kg": rng.uniform(0.01, 0.03), "margin_share": rng.uniform(0.0, 0.04)}
    if form == "entropic_rubber":  # rubber stiffness 1 + c (T_rubber - T0), rubber lag tau_s
        return {"stiffening_per_k": rng.uniform(0.01, 0.025), "rubber_tau_s": rng.uniform(5.0, 20.0)}
    if form == "zero_shift":  # zero shift [share of span per 10 K] of the frame, lag tau_s
        return {"zero_share_per_10k": rng.uniform(0.04, 0.08), "frame_tau_s": rng.uniform(20.0, 60.0)}
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND_FORMS}")


def reversal_frequency(u: Array, dt_s: float, band: float) -> Array:
    """Excitation frequency [Hz] ``1 / (2 * time between the last two reversals)`` of ``u``,
    reversals counted past a dead band ``band``; held between reversals, 0.01 Hz at first."""
    out = np.empty_like(u)
    freq, up = 0.01, True
    extreme, last_t = float(u[0]), 0.0
    for i, ui in enumerate(u.tolist()):
        if (up and ui > extreme) or (not up and ui < extreme):
            extreme = ui
        elif abs(ui - extreme) > band:
            now = i * dt_s
            freq = float(np.clip(0.5 / max(now - last_t, 1e-3), 0.005, 5.0))
            up, extreme, last_t = not up, ui, now
        out[i] = freq
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
    off: Array | None,
) -> Array:
    """Noise-free output [mm] of ``core`` with the effect ``form`` (``"none"``: switched off).

    ``off`` is the effect-free output (its span and top set the scale of the output-side forms).
    """
    peak = params["peak"]
    n = u.size
    hooks = Hooks.neutral(n)
    drive = u
    span = float(np.ptp(off)) if off is not None else 0.0
    if form == "speed_threshold":
        s = lowpass(np.abs(np.gradient(u, dt_s)) / peak, dt_s, 0.1)
        hooks = Hooks(1.0 + q["gain"] * s / (s + q["s0"]), hooks.load_kg, hooks.rubber)
    elif form == "frequency_width":
        f = lowpass(reversal_frequency(u, dt_s, 0.03 * peak), dt_s, 1.0)
        hooks = Hooks(np.clip((f / q["f_ref_hz"]) ** q["gain"], 1.0 / 3.0, 3.0), hooks.load_kg, hooks.rubber)
    elif form == "tube_flow":
        smooth = lowpass(u, dt_s, 0.05)
        venting = np.gradient(smooth, dt_s) < 0.0
        dead = (
            q["dead_time_s"] * (1.0 + q["level_gain"] * (1.0 - smooth / peak)) * np.where(venting, q["vent_ratio"], 1.0)
        )
        drive = variable_delay(u, lowpass(dead, dt_s, 0.05) / dt_s)
    elif form == "valve_frames":
        frame = max(1, int(round(q["frame_s"] / dt_s)))
        held = u[(np.arange(n) // frame) * frame]
        drive = variable_delay(held, np.full(n, q["latency_s"] / dt_s))
    elif form == "payload_balance":
        hooks = Hooks(hooks.width, q["lever"] * load, hooks.rubber)
    elif form == "entropic_rubber":
        rubber_t = lowpass(temperature, dt_s, q["rubber_tau_s"]) - temperature[0]
        hooks = Hooks(hooks.width, hooks.load_kg, np.maximum(1.0 + q["stiffening_per_k"] * rubber_t, 0.2))
    x = core(drive, dt_s, params, hooks)
    v = u / peak
    if form == "tension_chain":
        taus = np.geomspace(0.5, 400.0, 12)
        w = np.exp(-0.5 * (np.log(taus / q["tau_c_s"]) / q["log_sd"]) ** 2)
        tension = v * (1.0 + load / 5.0) / 2.0
        x = x - q["creep_share"] * span * sum(wk / w.sum() * lowpass(tension, dt_s, tk) for wk, tk in zip(w, taus))
    elif form == "cyclic_ratchet":
        travel = np.abs(np.diff(v, prepend=v[0]))
        bed = _ratchet(travel, dt_s, q["strokes"], q["recover_s"])
        x = x + q["creep_share"] * span * (0.6 * v * bed + 0.4 * lowpass(v, dt_s, q["kelvin_tau_s"]))
    elif form == "stroke_limit":
        top = float(np.max(off)) if off is not None else float(np.max(x))
        soft = 0.03 * span + 1e-9

        def limited(limit: Array | float) -> Array:
            return np.asarray(limit - soft * np.logaddexp(0.0, (limit - x) / soft), dtype=np.float64)

        head = top * (1.0 + q["margin_share"])  # only the payload moves the stroke end: none, no effect
        x = x + limited(head - q["limit_share_per_kg"] * span * load) - limited(head)
    elif form == "zero_shift":
        frame_t = lowpass(temperature, dt_s, q["frame_tau_s"]) - temperature[0]
        x = x + q["zero_share_per_10k"] * span * frame_t / 10.0
    return x


def _ratchet(travel: Array, dt_s: float, strokes: float, recover_s: float) -> Array:
    """Bedding-in state [0, 1]: ``b' = |v'| (1 - b) / strokes - b / recover_s`` (per-sample travel ``travel``)."""
    out = np.empty_like(travel)
    b = 0.0
    decay = dt_s / recover_s
    for i, dv in enumerate(travel.tolist()):
        b += dv * (1.0 - b) / strokes - decay * b
        out[i] = b
    return out
