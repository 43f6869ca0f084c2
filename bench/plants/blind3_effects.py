"""Every effect in two forms none of the other four families uses, and the always-moving columns.

Input side (the pressure that reaches the core): a proportional valve whose flow is limited by
ISO 6358 sonic conductance (choked when the pressure ratio is below ``b``), so fast moves are
slew-limited (rate dependence); a long tube as an acoustic dead time ``L / c`` plus a diffusive
Erlang dispersion growing with ``L^2`` (transport delay); the pressure regulator's
piezoresistive sensor whose span drifts with its own (lagged) temperature (temperature drift).
Output side (the stroke): a rod seal with rate-and-state friction (Dieterich-Ruina: a
log-velocity strength with a state that evolves over a slip distance; rate dependence);
Norton-Bailey strain-hardening creep with slow recovery, and a Schapery nonlinear viscoelastic
chain whose time scale shrinks with the pressure (creep); a sigma-delta ADC on the stroke
channel only, whose sinc^3 decimation filter delays it by 1.5 conversions and holds it between
conversions (transport delay); the payload's weight through a Hertzian rubber pad (``delta ~
F^(2/3)``) and an eccentric payload bowing a slender muscle (foreshortening ``pi^2 w^2 / 4L``,
``w ~ W e / k_lat(p)``) (load dependence); a magnetic stroke sensor whose magnet's remanence
and Hall sensitivity fall with temperature, read through the dipole law ``B ~ d^-3`` (temperature
drift).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: a person's limb effort in an exoskeleton cuff, or a tank that fills, sloshes and
drains. Temperature: an environmental chamber's ramp-and-soak, or a Peltier jacket driven by a
slow sine.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind3_cores import Core, position_sensor, stiffness_n_mm
from bench.plants.filters import lowpass
from bench.plants.recording import drawn_columns

Array = NDArray[np.float64]
G_MS2 = 9.81
SOUND_M_S = 343.0
BLIND3_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("choked_valve", "rate_state_seal"),
    "creep": ("norton_bailey", "schapery_bladder"),
    "transport_delay": ("erlang_line", "sinc3_adc"),
    "load_dependence": ("hertz_pad", "eccentric_bow"),
    "temperature_drift": ("regulator_span", "hall_magnet"),
}
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "choked_valve": "restriction_s",
    "rate_state_seal": "seal_mm",
    "norton_bailey": "creep_share",
    "schapery_bladder": "creep_share",
    "erlang_line": "length_m",
    "sinc3_adc": "conversion_s",
    "hertz_pad": "pad_scale",
    "eccentric_bow": "eccentricity_mm",
    "regulator_span": "span_scale",
    "hall_magnet": "tc_scale",
}
INPUT_SIDE = ("choked_valve", "erlang_line", "regulator_span")


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------


def load_limb_effort(t: Array, rng: np.random.Generator) -> Array:
    """The cuff load cell of an exoskeleton: the limb's weight share (0.8-2 kg) plus voluntary
    effort, 5-8 random sines of 0.03-0.3 Hz scaled to +-0.6-1.5 kg, never below 0.1 kg."""
    n = int(rng.integers(5, 9))
    freqs, phases = rng.uniform(0.03, 0.3, n), rng.uniform(0.0, 2.0 * np.pi, n)
    effort = np.sin(2.0 * np.pi * freqs[:, None] * t[None, :] + phases[:, None]).sum(axis=0)
    effort *= rng.uniform(0.6, 1.5) / max(float(np.max(np.abs(effort))), 1e-12)
    return np.asarray(np.maximum(rng.uniform(0.8, 2.0) + effort, 0.1), dtype=np.float64)


def load_tank_slosh(t: Array, rng: np.random.Generator) -> Array:
    """A tank on the payload filled at 0.08-0.2 kg/s from 0.4-0.8 kg to 2.5-4 kg, drained in 2-4 s;
    every start and stop sets the water sloshing (0.8-1.6 Hz, 0.1-0.3 kg, decaying in 2-5 s)."""
    knots_t, knots_l = [0.0], [float(rng.uniform(0.4, 0.8))]
    while knots_t[-1] < t[-1]:
        full, empty = float(rng.uniform(2.5, 4.0)), float(rng.uniform(0.4, 0.8))
        fill = (full - knots_l[-1]) / float(rng.uniform(0.08, 0.2))
        knots_t += [knots_t[-1] + fill, knots_t[-1] + fill + float(rng.uniform(2.0, 4.0))]
        knots_l += [full, empty]
    level = np.interp(t, knots_t, knots_l)
    f, decay = float(rng.uniform(0.8, 1.6)), float(rng.uniform(2.0, 5.0))
    slosh = np.zeros_like(t)
    for start in knots_t[1:]:
        after = t >= start
        s = t[after] - start
        slosh[after] += rng.uniform(0.1, 0.3) * np.exp(-s / decay) * np.sin(2.0 * np.pi * f * s)
    return np.asarray(np.maximum(level + slosh, 0.0), dtype=np.float64)


def temp_ramp_soak(t: Array, rng: np.random.Generator) -> Array:
    """An environmental chamber: from 20-25 degC, ramps of 0.15-0.4 K/s up to +4-9 K, soaks of
    8-20 s, ramps down to +0-1.5 K, soaks of 5-15 s, ...; the rig sees it through a 1-3 s lag."""
    base = float(rng.uniform(20.0, 25.0))
    knots_t, knots_c = [0.0], [base + float(rng.uniform(0.0, 1.5))]
    while knots_t[-1] < t[-1]:
        for lo, hi, soak in ((4.0, 9.0, (8.0, 20.0)), (0.0, 1.5, (5.0, 15.0))):
            level = base + float(rng.uniform(lo, hi))
            ramp = abs(level - knots_c[-1]) / float(rng.uniform(0.15, 0.4))
            knots_t += [knots_t[-1] + ramp, knots_t[-1] + ramp + float(rng.uniform(*soak))]
            knots_c += [level, level]
    return lowpass(np.interp(t, knots_t, knots_c), float(t[1] - t[0]), float(rng.uniform(1.0, 3.0)))


def temp_peltier_sine(t: Array, rng: np.random.Generator) -> Array:
    """A Peltier jacket around the muscle driven by a 0.01-0.03 Hz sine: +-2.5-5 K around 20-25
    degC, with a 10-25 % second harmonic (heating and cooling are not symmetric)."""
    f, phase = float(rng.uniform(0.01, 0.03)), float(rng.uniform(0.0, 2.0 * np.pi))
    wave = np.sin(2.0 * np.pi * f * t + phase) + rng.uniform(0.1, 0.25) * np.sin(4.0 * np.pi * f * t + 2.0 * phase)
    return np.asarray(rng.uniform(20.0, 25.0) + rng.uniform(2.5, 5.0) * wave, dtype=np.float64)


LOAD_PATTERNS = {"limb_effort": load_limb_effort, "tank_slosh": load_tank_slosh}
TEMPERATURE_PATTERNS = {"ramp_soak": temp_ramp_soak, "peltier_sine": temp_peltier_sine}


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record and their pattern names (independent of the effect)."""
    return drawn_columns(LOAD_PATTERNS, TEMPERATURE_PATTERNS, t, rng)


# ---- effects -------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "choked_valve":  # volume over sonic conductance [s]; supply margin [bar]; b; full opening
        return {
            "restriction_s": rng.uniform(0.8, 1.6),
            "supply_margin_bar": rng.uniform(1.5, 3.0),
            "b_critical": rng.uniform(0.2, 0.45),
            "full_open_share": rng.uniform(0.03, 0.06),
        }
    if form == "rate_state_seal":  # strength scale; direct (a) and evolution (b) terms; v0; slip memory
        return {
            "seal_mm": rng.uniform(3.0, 5.0),
            "a": 1.0,
            "b": rng.uniform(0.3, 0.7),
            "v0_mm_s": rng.uniform(20.0, 60.0),
            "dc_mm": rng.uniform(0.2, 1.0),
        }
    if form == "norton_bailey":  # share of span; stress exponent; hardening; reference time; recovery
        return {
            "creep_share": rng.uniform(0.05, 0.1),
            "stress_exp": rng.uniform(1.5, 3.0),
            "hardening": rng.uniform(1.0, 3.0),
            "t_ref_s": rng.uniform(20.0, 60.0),
            "recover_s": rng.uniform(150.0, 400.0),
        }
    if form == "schapery_bladder":  # share of span; g2 nonlinearity; decades of time shift at full pressure
        w = rng.dirichlet(np.full(4, 2.0))
        return {
            "creep_share": rng.uniform(0.05, 0.1),
            "g2_gain": rng.uniform(0.5, 1.5),
            "shift_decades": rng.uniform(0.5, 1.5),
            **{f"w{k}": float(w[k]) for k in range(4)},
        }
    if form == "erlang_line":  # tube length [m]; dispersion [s/m^2]; Erlang stages
        return {
            "length_m": rng.uniform(4.0, 15.0),
            "disp_s_m2": rng.uniform(1.5e-4, 3e-4),
            "stages": float(rng.integers(3, 7)),
        }
    if form == "sinc3_adc":  # conversion period [s] (group delay 1.5 x); phase of the conversions
        return {"conversion_s": rng.uniform(0.012, 0.03), "phase": rng.uniform(0.0, 1.0)}
    if form == "hertz_pad":  # pad radius [mm], effective modulus [MPa], preload [N]
        return {
            "pad_scale": 1.0,
            "radius_mm": rng.uniform(4.0, 10.0),
            "modulus_mpa": rng.uniform(2.0, 6.0),
            "preload_n": rng.uniform(2.0, 8.0),
        }
    if form == "eccentric_bow":  # payload offset [mm]; muscle length [mm]; lateral stiffness vented [N/mm], per bar
        return {
            "eccentricity_mm": rng.uniform(35.0, 60.0),
            "length_mm": rng.uniform(250.0, 400.0),
            "k_lat0_n_mm": rng.uniform(0.2, 0.4),
            "k_lat1_n_mm_bar": rng.uniform(0.1, 0.25),
        }
    if form == "regulator_span":  # span drift [1/K] (bridge and amplifier), its curvature [1/K^2], body lag [s]
        return {
            "span_scale": 1.0,
            "tcs_per_k": -rng.uniform(0.004, 0.007),
            "tcs2_per_k2": rng.uniform(-1.5e-4, 1.5e-4),
            "tau_s": rng.uniform(5.0, 20.0),
        }
    if form == "hall_magnet":  # gap at rest [mm]; magnet + Hall coefficient [1/K]; magnet lag [s]
        return {
            "tc_scale": 1.0,
            "gap_mm": rng.uniform(30.0, 60.0),
            "tc_per_k": -rng.uniform(0.0035, 0.006),
            "tau_s": rng.uniform(8.0, 25.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND3_FORMS}")


def _choked_valve(u: Array, dt_s: float, q: dict[str, float], peak: float) -> Array:
    """Muscle pressure [bar] filled/vented through ISO 6358 flow: ``p' = o p_up psi(p_dn / p_up)
    / R``, ``o = clip((u - p) / (s peak), -1, 1)`` the valve opening, ``psi = 1`` when choked
    (ratio <= ``b``) else ``sqrt(1 - ((r - b) / (1 - b))^2)``; fill from the supply ``peak +
    margin``, vent to atmosphere (absolute pressures, 1 bar ambient); never overshoots ``u``."""
    supply, b = peak + q["supply_margin_bar"] + 1.0, q["b_critical"]
    gain, full = dt_s / max(q["restriction_s"], 1e-6), q["full_open_share"] * peak
    out = np.empty_like(u)
    p = 0.0
    for i, ui in enumerate(u.tolist()):
        e = ui - p
        up, down = (supply, p + 1.0) if e > 0.0 else (p + 1.0, 1.0)
        r = down / up
        psi = 1.0 if r <= b else math.sqrt(max(1.0 - ((r - b) / (1.0 - b)) ** 2, 0.0))
        step = gain * min(abs(e) / full, 1.0) * up * max(psi, 0.02)
        p = ui if step >= abs(e) else p + (step if e > 0.0 else -step)
        out[i] = p
    return out


def _rate_state_seal(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The rod held by a seal whose strength [mm of play] is ``seal (a ln(1 + |v| / v0) - b phi)+``,
    ``phi' = (ln(1 + |v| / v0) - phi) |v| / dc`` (evolves over slip distance ``dc``); ``v`` the
    stroke speed [mm/s] (20 ms smoothing). A play of that radius around ``x``: 0 at rest."""
    speed = lowpass(np.abs(np.gradient(x, dt_s)), dt_s, 0.02)
    direct = np.log1p(speed / q["v0_mm_s"])
    out = np.empty_like(x)
    y, phi = float(x[0]), 0.0
    for i, (xi, di, vi) in enumerate(zip(x.tolist(), direct.tolist(), speed.tolist())):
        phi += (di - phi) * min(vi * dt_s / q["dc_mm"], 1.0)
        r = q["seal_mm"] * max(q["a"] * di - q["b"] * phi, 0.0)
        y = xi - r if y < xi - r else xi + r if y > xi + r else y
        out[i] = y
    return out


def _norton_bailey(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Creep strain (1 at ``t_ref`` under full pressure): ``e' = v^n / ((h + 1) t_ref (e + e0)^h) -
    e / recover`` integrated exactly for the hardening part, ``e0 = 0.02``."""
    h, e0 = q["hardening"], 0.02
    drive = np.clip(v, 0.0, None) ** q["stress_exp"] * dt_s / q["t_ref_s"]
    decay = dt_s / q["recover_s"]
    out = np.empty_like(v)
    w = e0
    for i, di in enumerate(drive.tolist()):
        w = (w ** (h + 1.0) + di) ** (1.0 / (h + 1.0))
        w -= (w - e0) * decay
        out[i] = w - e0
    return out


SCHAPERY_TAUS_S = (2.0, 8.0, 30.0, 120.0)


def _schapery(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Transient creep ``sum w_k q_k`` in reduced time: ``q_k' = (g2(v) v - q_k) / (tau_k a(v))``,
    ``g2 = 1 + g v^2``, ``a = 10^(-c v)`` (higher pressure: faster creep); scaled to 1 at full pressure."""
    v = np.clip(v, 0.0, None)
    target = (1.0 + q["g2_gain"] * v * v) * v / (1.0 + q["g2_gain"])
    total = np.zeros_like(v)
    for k, tau in enumerate(SCHAPERY_TAUS_S):
        share = -np.expm1(-dt_s / (tau * 10.0 ** (-q["shift_decades"] * v)))
        state = np.empty_like(v)
        s = 0.0
        for i, (gi, ai) in enumerate(zip(target.tolist(), share.tolist())):
            s += (gi - s) * ai
            state[i] = s
        total += q[f"w{k}"] * state
    return total


def _delayed(x: Array, dt_s: float, delay_s: float) -> Array:
    """``x`` read ``delay_s`` earlier (linear interpolation; the first value before the start)."""
    idx = np.arange(x.size, dtype=np.float64)
    return np.asarray(np.interp(idx - delay_s / dt_s, idx, x), dtype=np.float64)


def _erlang_line(u: Array, dt_s: float, q: dict[str, float]) -> Array:
    """Pressure [bar] at the muscle end of a tube: acoustic dead time ``L / 343 m/s`` then an
    Erlang-n dispersion of mean ``disp L^2`` (n equal lags)."""
    p = _delayed(u, dt_s, q["length_m"] / SOUND_M_S)
    stages = int(q["stages"])
    for _ in range(stages):
        p = lowpass(p, dt_s, max(q["disp_s_m2"] * q["length_m"] ** 2 / stages, 1e-6))
    return p


def _sinc3_adc(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The stroke channel's sigma-delta ADC: conversions every ``T`` at ``(k + phase) T`` average
    the signal over the last ``3 T`` with the sinc^3 (quadratic B-spline) weights, and the DAQ
    reads the latest finished conversion (group delay 1.5 ``T`` plus the hold)."""
    period = q["conversion_s"]
    t = np.arange(x.size, dtype=np.float64) * dt_s
    done = (np.floor(t / period - q["phase"]) + q["phase"]) * period  # the latest conversion instant
    s = (np.arange(48, dtype=np.float64) + 0.5) / 16.0  # in conversion periods, over [0, 3)
    w = np.where(s < 1.0, 0.5 * s * s, np.where(s < 2.0, 0.75 - (s - 1.5) ** 2, 0.5 * (3.0 - s) ** 2))
    w /= w.sum()
    out = np.zeros_like(x)
    for wk, sk in zip(w.tolist(), s.tolist()):
        out += wk * np.interp(done - sk * period, t, x)
    return out


def drive_of(u: Array, dt_s: float, form: str, q: dict[str, float], temperature: Array, peak: float) -> Array:
    """The pressure [bar] reaching the core: ``u`` unless ``form`` acts on the input side."""
    if form == "choked_valve":
        return _choked_valve(u, dt_s, q, peak)
    if form == "erlang_line":
        return _erlang_line(u, dt_s, q)
    if form == "regulator_span":
        body = lowpass(temperature, dt_s, q["tau_s"]) - temperature[0]
        span = 1.0 + q["span_scale"] * (q["tcs_per_k"] * body + q["tcs2_per_k2"] * body * body)
        return np.asarray(np.clip(u / np.maximum(span, 0.5), 0.0, None), dtype=np.float64)
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
    off), read through :func:`~bench.plants.blind3_cores.position_sensor`.

    ``base`` is the effect-free core output (computed when not given): the output-side forms
    start from it and take their scale from its span. The load and temperature forms act
    through the change of their column since the record's start (the plant as identified then).
    """
    peak = params["peak"]
    if form in INPUT_SIDE:
        return position_sensor(core(drive_of(u, dt_s, form, q, temperature, peak), dt_s, params), dt_s, params)
    x = core(u, dt_s, params) if base is None else base
    span = float(np.ptp(x))
    v = np.clip(u / peak, 0.0, None)
    if form == "rate_state_seal":
        x = _rate_state_seal(x, dt_s, q)
    elif form == "norton_bailey":
        x = x - q["creep_share"] * span * _norton_bailey(v, dt_s, q)
    elif form == "schapery_bladder":
        x = x - q["creep_share"] * span * _schapery(v, dt_s, q)
    elif form == "hertz_pad":  # relative to the payload at the start: the plant as identified at tare
        compliance = q["pad_scale"] * (9.0 / (16.0 * q["radius_mm"] * q["modulus_mpa"] ** 2)) ** (1.0 / 3.0)
        tension = q["preload_n"] + 0.2 * stiffness_n_mm(u, params) * np.clip(x, 0.0, None)  # N: share of the pull

        def squeeze(kg: Array | float) -> Array:
            return np.asarray(compliance * ((tension + G_MS2 * kg) ** (2.0 / 3.0) - tension ** (2.0 / 3.0)))

        x = x - (squeeze(load) - squeeze(float(load[0])))
    elif form == "eccentric_bow":
        k_lat = q["k_lat0_n_mm"] + q["k_lat1_n_mm_bar"] * np.clip(u, 0.0, None)

        def shortening(kg: Array | float) -> Array:
            bow = np.minimum(1.5 * G_MS2 * kg * q["eccentricity_mm"] / (q["length_mm"] * k_lat), 0.3 * q["length_mm"])
            return np.asarray(math.pi**2 * bow * bow / (4.0 * q["length_mm"]))

        x = x - (shortening(load) - shortening(float(load[0])))
    elif form == "hall_magnet":
        magnet = lowpass(temperature, dt_s, q["tau_s"]) - temperature[0]
        field = np.maximum(1.0 + q["tc_scale"] * q["tc_per_k"] * magnet, 0.5)
        x = (q["gap_mm"] + x) * field ** (-1.0 / 3.0) - q["gap_mm"]
    reading = position_sensor(x, dt_s, params)
    if form == "sinc3_adc":
        return _sinc3_adc(reading, dt_s, q)
    return reading
