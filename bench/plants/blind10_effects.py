"""Every effect in two forms, one plain and one unusual, and the always-moving columns (blind10).

For each effect one form is the *plain* textbook form a lab would most likely meet, in a
parameterisation or range the other families do not use; the other is *unusual*, unlike every
other family's form. Three forms act *inside* the core (:data:`INSIDE_FORMS`: the core re-driven
with another pressure or with ``mods``, see :mod:`bench.plants.blind10_cores`); the rest act on the
contraction or on its reading after it.

Rate dependence: plain, a *linear viscous dashpot* on the payload (``c x'``) held by the balance's
own stiffness ``K(p, x)``, i.e. a first-order lag of the stroke whose time constant ``c / K`` is
8-30 ms at the top and longer where the muscle is soft (after); unusual, the bladder's *hysteretic
self-heating*: the rubber warms with the power it dissipates (its stroke speed) and sheds the heat
in 8-30 s, and the warm rubber is softer (its Gent modulus divided by ``1 + s H``, ``H`` the heat,
through the force balance), so after a stretch of fast cycling the muscle contracts further
(inside). Creep: plain, *first-order
(single Kelvin) creep driven by the pressure* (``y = x - c S (v - lag(v, tau))``, tau 3-12 s:
after a pressure step the last few percent of the stroke come exponentially; after); unusual,
*Struik physical ageing*: the same delayed share, but its retardation time grows with the time
since the sleeve was last *rejuvenated* by a large pressure change, ``tau0 (1 + age / t_a)^mu``
(after). Transport delay: plain, a *pure dead time* of 20-60 ms in the line between the
transmitter (at the booster's outlet) and the muscle (inside); unusual, the stroke read through a
*PLC* whose *scan time grows with its workload* (the motion logic runs more code while the set
pressure moves: scans of 6-20 ms at rest, up to 2-4 x that while it moves fast; each scan reads
the input image after the input module's 2-6 ms filter at the scan's start and publishes it at the
scan's end, the logger holding the last published value; after). Load dependence: plain, a
*linear compliance* in the load path (``0.3-2 mm/kg`` of sag: a soft rope or spring; after); unusual, the hanging
rope's knots *bedding in*: the sag follows rises of the load quickly (0.3-1 s) and recovers from
falls only slowly (15-60 s), an envelope of the load (after). Temperature drift: plain, a
*linear temperature coefficient of the stroke's gain* (0.4-1.2 %/K through the muscle wall's
5-20 s thermal lag; after); unusual, an *R-phase NiTi bias spring* returning the payload: near
room temperature its martensite share follows the (lagged) temperature with a thermal hysteresis
(Liang-Rogers cosine kinetics between ``M_f < M_s < T0 < A_s < A_f``, the transformations starting
0.05-0.4 K either side of the start and spreading over 1.5-4 K; starting mixed), and its stiffness
with it (the austenite 15-50 % stiffer), through the force balance (inside).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: a ball rolling on a beam over the load cell whose tilt a servo flips every 3-8 s,
or a pendulum swinging from the payload's pan (the string's tension ``m (g cos th + L th'^2)``,
at twice the swing's frequency), pushed to a new amplitude every 6-15 s. Temperature: an ice
pack pressed on the muscle now and then, or the load stage's motor beside the probe warming
with the load's activity (a decoy correlated with the load column).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind10_cores import BLIND10_DRIVES, normalised_pressure, stiffness_n_mm
from bench.plants.blind10_rig import stroke_reading
from bench.plants.filters import lowpass, variable_delay

Array = NDArray[np.float64]
BLIND10_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("linear_dashpot", "bladder_self_heating"),
    "creep": ("first_order_pressure_creep", "struik_ageing_creep"),
    "transport_delay": ("supply_dead_time", "plc_scan_workload"),
    "load_dependence": ("linear_compliance", "rope_bedding_in"),
    "temperature_drift": ("linear_gain_tempco", "nitinol_bias_spring"),
}
PLAIN_FORMS: tuple[str, ...] = tuple(forms[0] for e, forms in BLIND10_FORMS.items() if e != "none")
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "linear_dashpot": "tau_top_s",
    "bladder_self_heating": "softening_per_heat",
    "first_order_pressure_creep": "creep_share",
    "struik_ageing_creep": "ageing_share",
    "supply_dead_time": "dead_time_s",
    "plc_scan_workload": "scan_s",
    "linear_compliance": "sag_mm_per_kg",
    "rope_bedding_in": "bedding_mm_per_kg",
    "linear_gain_tempco": "gain_per_k",
    "nitinol_bias_spring": "austenite_stiffening",
}
INSIDE_FORMS: tuple[str, ...] = ("bladder_self_heating", "supply_dead_time", "nitinol_bias_spring")
G_MS2 = 9.81
HEAT_SPEED_MM_S = 20.0  # the stroke speed whose dissipation holds the heat state at 1


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------------


def load_ball_on_beam(t: Array, rng: np.random.Generator) -> Array:
    """A 1-3 kg ball rolling on a 0.4-0.8 m beam (1-2 kg) pivoted at one end over the load cell at
    the other; a servo flips the beam's tilt to the other side (2-6 deg, over 0.3 s) every 3-8 s, the
    first within 2 s; the ball rolls (``5/7 g sin(tilt)``, rolling loss 0.2-0.5 /s) and bounces off
    the end stops (restitution 0.2-0.5). The cell carries half the beam and ``m s / L`` of the ball."""
    dt = float(t[1] - t[0])
    ball, beam, length = float(rng.uniform(1.0, 3.0)), float(rng.uniform(1.0, 2.0)), float(rng.uniform(0.4, 0.8))
    loss, bounce = float(rng.uniform(0.2, 0.5)), float(rng.uniform(0.2, 0.5))
    tilt_t, tilt = [0.0], [float(rng.choice([-1.0, 1.0])) * float(rng.uniform(2.0, 6.0))]
    now = float(rng.uniform(0.5, 2.0))
    while now < t[-1] + 10.0:
        tilt_t += [now, now + 0.3]
        tilt += [tilt[-1], -math.copysign(float(rng.uniform(2.0, 6.0)), tilt[-1])]
        now += float(rng.uniform(3.0, 8.0))
    angle = np.radians(np.interp(t, tilt_t, tilt))
    pos, speed = float(rng.uniform(0.2, 0.8)) * length, 0.0
    out = np.empty(t.size)
    for i, a in enumerate(angle.tolist()):
        speed += dt * (5.0 / 7.0 * G_MS2 * math.sin(a) - loss * speed)
        pos += dt * speed
        if pos < 0.0 or pos > length:
            pos = min(max(pos, 0.0), length)
            speed = -bounce * speed
        out[i] = 0.5 * beam + ball * pos / length
    return out


def load_pendulum_tension(t: Array, rng: np.random.Generator) -> Array:
    """A 1.5-4 kg bob on a 0.25-0.7 m string hanging from the payload's pan (0.5-1.5 kg): the string's
    tension ``m (g cos th + L th'^2)`` read in kg; damping ratio 0.01-0.04; every 6-15 s (the
    first within 2 s) a push sets the swing's amplitude to 25-50 deg."""
    dt = float(t[1] - t[0])
    bob, length, pan = float(rng.uniform(1.5, 4.0)), float(rng.uniform(0.25, 0.7)), float(rng.uniform(0.5, 1.5))
    w0 = math.sqrt(G_MS2 / length)
    zeta = float(rng.uniform(0.01, 0.04))
    subs = max(1, int(math.ceil(w0 * dt / 0.05)))
    h = dt / subs
    pushes = [float(rng.uniform(0.3, 2.0))]
    while pushes[-1] < t[-1]:
        pushes.append(pushes[-1] + float(rng.uniform(6.0, 15.0)))
    amps = np.radians(rng.uniform(25.0, 50.0, len(pushes))).tolist()
    th, om, k = 0.0, 0.0, 0
    out = np.empty(t.size)
    for i, ti in enumerate(t.tolist()):
        if k < len(pushes) and ti >= pushes[k]:
            amp = amps[k]
            if abs(th) < amp:
                om = math.copysign(math.sqrt(2.0 * G_MS2 / length * (math.cos(th) - math.cos(amp))), om or 1.0)
            else:
                th, om = math.copysign(amp, th), 0.0
            k += 1
        for _ in range(subs):
            om += h * (-(G_MS2 / length) * math.sin(th) - 2.0 * zeta * w0 * om)
            th += h * om
        out[i] = pan + bob * (math.cos(th) + length * om * om / G_MS2)
    return out


def temp_ice_pack(t: Array, rng: np.random.Generator) -> Array:
    """A 19-26 degC room drifting by 0.3-1 K over 300-900 s, and an ice pack pressed on the muscle
    beside the probe for 2-8 s every 10-30 s (the first within 1-6 s): towards 4-10 K below the room
    at 3-8 s while it is on, back at 10-30 s."""
    dt = float(t[1] - t[0])
    room = float(rng.uniform(19.0, 26.0)) + float(rng.uniform(0.3, 1.0)) * np.sin(
        2.0 * np.pi * t / float(rng.uniform(300.0, 900.0)) + float(rng.uniform(0.0, 6.3))
    )
    depth, tau_on, tau_off = float(rng.uniform(4.0, 10.0)), float(rng.uniform(3.0, 8.0)), float(rng.uniform(10.0, 30.0))
    on = np.zeros(t.size, dtype=bool)
    now = float(rng.uniform(1.0, 6.0))
    while now < t[-1]:
        length = float(rng.uniform(2.0, 8.0))
        on |= (t >= now) & (t < now + length)
        now += length + float(rng.uniform(10.0, 30.0))
    a_on, a_off = 1.0 - math.exp(-dt / tau_on), 1.0 - math.exp(-dt / tau_off)
    cool = np.empty(t.size)
    c = 0.0
    for i, pressed in enumerate(on.tolist()):
        c += ((depth - c) * a_on) if pressed else (-c * a_off)
        cool[i] = c
    return np.asarray(room - cool, dtype=np.float64)


def temp_stage_motor(t: Array, rng: np.random.Generator, load: Array) -> Array:
    """A 20-27 degC room, and the load stage's drive motor beside the probe warming with the load's
    activity: ``a`` (2-5 K) x ``|d load / dt| / (0.5 kg/s)`` (at most 1: the drive's current limit)
    through the motor's 8-25 s thermal lag, from cold."""
    dt = float(t[1] - t[0])
    activity = np.clip(np.abs(np.gradient(load, dt)) / 0.5, 0.0, 1.0)
    activity[0] = 0.0
    heat = float(rng.uniform(2.0, 5.0)) * lowpass(activity, dt, float(rng.uniform(8.0, 25.0)))
    return np.asarray(float(rng.uniform(20.0, 27.0)) + heat, dtype=np.float64)


LOAD_PATTERNS = {"ball_on_beam": load_ball_on_beam, "pendulum_tension": load_pendulum_tension}
TEMPERATURE_PATTERNS = ("ice_pack", "stage_motor")


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record, and their pattern names (independent of the
    effect)."""
    load_name = tuple(LOAD_PATTERNS)[int(rng.integers(0, len(LOAD_PATTERNS)))]
    temp_name = TEMPERATURE_PATTERNS[int(rng.integers(0, len(TEMPERATURE_PATTERNS)))]
    load = LOAD_PATTERNS[load_name](t, rng)
    temperature = temp_ice_pack(t, rng) if temp_name == "ice_pack" else temp_stage_motor(t, rng, load)
    return load, temperature, load_name, temp_name


# ---- effects ---------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "linear_dashpot":  # the lag's time constant at the top [s]
        return {"tau_top_s": rng.uniform(0.008, 0.03)}
    if form == "bladder_self_heating":  # softening per unit heat; heat shed time [s]
        return {"softening_per_heat": rng.uniform(0.1, 0.4), "heat_tau_s": rng.uniform(8.0, 30.0)}
    if form == "first_order_pressure_creep":  # delayed share of the stroke per unit pressure share; tau [s]
        return {"creep_share": rng.uniform(0.03, 0.1), "creep_tau_s": rng.uniform(3.0, 12.0)}
    if form == "struik_ageing_creep":  # share; tau0 [s]; ageing time [s]; ageing exponent; rejuvenating jump
        return {
            "ageing_share": rng.uniform(0.04, 0.1),
            "tau0_s": rng.uniform(0.5, 2.0),
            "ageing_s": rng.uniform(2.0, 8.0),
            "ageing_mu": rng.uniform(0.7, 1.0),
            "rejuvenate_share": rng.uniform(0.3, 0.5),
        }
    if form == "supply_dead_time":
        return {"dead_time_s": rng.uniform(0.02, 0.06)}
    if form == "plc_scan_workload":  # scan at rest [s]; growth at full workload; input filter [s]; full speed [peak/s]
        return {
            "scan_s": rng.uniform(0.006, 0.02),
            "workload_growth": rng.uniform(1.0, 3.0),
            "input_filter_s": rng.uniform(0.002, 0.006),
            "busy_speed_share_s": rng.uniform(1.0, 3.0),
        }
    if form == "linear_compliance":
        return {"sag_mm_per_kg": rng.uniform(0.3, 2.0)}
    if form == "rope_bedding_in":  # sag per kg; bedding-in and recovery times [s]
        return {
            "bedding_mm_per_kg": rng.uniform(0.2, 0.9),
            "bed_tau_s": rng.uniform(0.3, 1.0),
            "recover_tau_s": rng.uniform(15.0, 60.0),
        }
    if form == "linear_gain_tempco":  # gain change per K; the wall's thermal lag [s]
        return {"gain_per_k": rng.uniform(0.004, 0.012), "wall_tau_s": rng.uniform(5.0, 20.0)}
    if form == "nitinol_bias_spring":  # E_A / E_M - 1; windows [K from T0]; start martensite share; lag [s]
        a_s, m_s = float(rng.uniform(0.05, 0.4)), -float(rng.uniform(0.05, 0.4))
        return {
            "austenite_stiffening": rng.uniform(0.15, 0.5),
            "a_s_k": a_s,
            "a_f_k": a_s + float(rng.uniform(1.5, 4.0)),
            "m_s_k": m_s,
            "m_f_k": m_s - float(rng.uniform(1.5, 4.0)),
            "martensite0": rng.uniform(0.3, 0.7),
            "spring_tau_s": rng.uniform(3.0, 10.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND10_FORMS}")


def first_order(x: Array, dt_s: float, tau_s: Array) -> Array:
    """``y' = (x - y) / tau`` with a per-sample time constant (exact for ``x`` held over each
    sample), from rest on ``x[0]``."""
    keep = np.exp(-dt_s / np.clip(tau_s, 1e-9, None)).tolist()
    out = np.empty(x.size)
    y = float(x[0])
    for i, (xi, ki) in enumerate(zip(x.tolist(), keep)):
        y = xi + (y - xi) * ki
        out[i] = y
    return out


def heat_state(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The bladder's heat [units of what 20 mm/s of travel holds]: ``H' = (|x'| / 20 - H) / tau``,
    the speed smoothed over 50 ms, from cold."""
    speed = np.abs(lowpass(np.gradient(x, dt_s), dt_s, 0.05))
    speed[0] = 0.0
    return lowpass(speed / HEAT_SPEED_MM_S, dt_s, q["heat_tau_s"])


def ageing_lag(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``v`` followed with the retardation time ``tau0 (1 + age / t_a)^mu``, the age counting from
    the last time ``v`` moved ``rejuvenate_share`` away from where it was then (exact per sample)."""
    tau0, t_a, mu, jump = q["tau0_s"], q["ageing_s"], q["ageing_mu"], q["rejuvenate_share"]
    out = np.empty(v.size)
    c, anchor, age = float(v[0]), float(v[0]), 0.0
    for i, vi in enumerate(v.tolist()):
        if abs(vi - anchor) > jump:
            anchor, age = vi, 0.0
        tau = tau0 * (1.0 + age / t_a) ** mu
        c = vi + (c - vi) * math.exp(-dt_s / tau)
        out[i] = c
        age += dt_s
    return out


def plc_reading(x: Array, u: Array, dt_s: float, peak: float, q: dict[str, float]) -> Array:
    """``x`` as the PLC publishes it: scans of ``scan_s (1 + growth w)`` (``w`` the workload, the set
    pressure's speed over ``busy_speed_share_s`` x the peak per second smoothed over 0.2 s, at most
    1); each scan reads ``x`` ``input_filter_s`` before its start and publishes at its end; held
    (``x[0]`` before the first publication)."""
    t = np.arange(x.size, dtype=np.float64) * dt_s
    work = np.clip(np.abs(lowpass(np.gradient(u, dt_s), dt_s, 0.2)) / (q["busy_speed_share_s"] * peak), 0.0, 1.0)
    starts: list[float] = []
    ends: list[float] = []
    now = 0.0
    while now <= t[-1]:
        scan = q["scan_s"] * (1.0 + q["workload_growth"] * float(np.interp(now, t, work)))
        starts.append(now)
        ends.append(now + scan)
        now += scan
    values = np.interp(np.array(starts) - q["input_filter_s"], t, x, left=float(x[0]))
    k = np.searchsorted(np.array(ends), t, side="right") - 1
    return np.asarray(np.where(k >= 0, values[np.clip(k, 0, None)], x[0]), dtype=np.float64)


def bedding_sag(load: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The knots' sag [mm]: towards ``bedding_mm_per_kg`` x the load's change since the start, at
    ``bed_tau_s`` while the target is above it and ``recover_tau_s`` while below (exact per sample)."""
    target = q["bedding_mm_per_kg"] * (load - load[0])
    fast, slow = math.exp(-dt_s / q["bed_tau_s"]), math.exp(-dt_s / q["recover_tau_s"])
    out = np.empty(load.size)
    s = 0.0
    for i, ti in enumerate(target.tolist()):
        s = ti + (s - ti) * (fast if ti > s else slow)
        out[i] = s
    return out


def martensite_share(temp: Array, q: dict[str, float]) -> Array:
    """The NiTi spring's martensite share for its temperature's change ``temp`` [K] since the
    start (Liang-Rogers: heating from ``xi_s`` gives ``xi_s / 2 (cos(pi (T - A_s) / (A_f - A_s)) +
    1)``, cooling from ``xi_s`` gives ``(1 - xi_s) / 2 cos(pi (T - M_f) / (M_s - M_f)) + (1 + xi_s) /
    2``, each only moving the share its own way; ``xi_s`` taken at each turn of the temperature)."""
    a_s, a_f, m_s, m_f = q["a_s_k"], q["a_f_k"], q["m_s_k"], q["m_f_k"]
    xi = start = q["martensite0"]
    heating: bool | None = None
    prev = float(temp[0])
    out = np.empty(temp.size)
    for i, ti in enumerate(temp.tolist()):
        if ti > prev:
            if heating is not True:
                heating, start = True, xi
            s = min(max((ti - a_s) / (a_f - a_s), 0.0), 1.0)
            xi = min(xi, start / 2.0 * (math.cos(math.pi * s) + 1.0))
        elif ti < prev:
            if heating is not False:
                heating, start = False, xi
            s = min(max((ti - m_f) / (m_s - m_f), 0.0), 1.0)
            xi = max(xi, (1.0 - start) / 2.0 * math.cos(math.pi * s) + (1.0 + start) / 2.0)
        out[i] = xi
        prev = ti
    return out


def render(
    plant: str,
    params: dict[str, float],
    u: Array,
    dt_s: float,
    form: str,
    q: dict[str, float],
    load: Array,
    temperature: Array,
    base: Array,
) -> Array:
    """Noise-free stroke reading [mm] of ``plant`` (its contraction ``base`` for the set pressure
    ``u`` [bar]) with the effect ``form`` (``"none"``: switched off), through the rig
    (:func:`~bench.plants.blind10_rig.stroke_reading`).

    The load and temperature forms act through their column's change since the record's start
    (the plant as identified then): with the columns held at their first value they are the
    effect-free plant."""
    x = base
    if form in INSIDE_FORMS:
        drive = BLIND10_DRIVES[plant]
        v = normalised_pressure(u, dt_s, params)
        if form == "bladder_self_heating":
            soft = 1.0 / (1.0 + q["softening_per_heat"] * heat_state(base, dt_s, q))
            x = drive(v, dt_s, params, {"rubber": soft})
        elif form == "supply_dead_time":
            x = drive(variable_delay(v, np.full_like(v, q["dead_time_s"] / dt_s)), dt_s, params, {})
        else:  # nitinol_bias_spring
            warm = lowpass(temperature, dt_s, q["spring_tau_s"])
            xi = martensite_share(warm - warm[0], q)
            g = q["austenite_stiffening"]
            x = drive(v, dt_s, params, {"spring": (1.0 + g * (1.0 - xi)) / (1.0 + g * (1.0 - xi[0]))})
    elif form == "linear_dashpot":
        v = normalised_pressure(u, dt_s, params)
        stiff = stiffness_n_mm(v, x, params)
        top = float(stiffness_n_mm(np.array([1.0]), np.array([params["stroke_mm"]]), params)[0])
        x = first_order(x, dt_s, q["tau_top_s"] * top / stiff)
    elif form == "first_order_pressure_creep":
        v = normalised_pressure(u, dt_s, params)
        x = x - q["creep_share"] * params["stroke_mm"] * (v - lowpass(v, dt_s, q["creep_tau_s"]))
    elif form == "struik_ageing_creep":
        v = normalised_pressure(u, dt_s, params)
        x = x - q["ageing_share"] * params["stroke_mm"] * (v - ageing_lag(v, dt_s, q))
    elif form == "linear_compliance":
        x = x - q["sag_mm_per_kg"] * (load - load[0])
    elif form == "rope_bedding_in":
        x = x - bedding_sag(load, dt_s, q)
    elif form == "linear_gain_tempco":
        warm = lowpass(temperature, dt_s, q["wall_tau_s"])
        x = x * (1.0 + q["gain_per_k"] * (warm - warm[0]))
    reading = stroke_reading(x, dt_s, params)
    if form == "plc_scan_workload":
        reading = plc_reading(reading, u, dt_s, params["peak"], q)
    return reading
