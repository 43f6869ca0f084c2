"""Every effect in two forms, one plain and one unusual, and the always-moving columns (blind11).

For each effect the first form is the *plain* textbook form a lab would most likely meet, in a
parameterisation or range the other families do not use; the second is *unusual*, unlike every
other family's form. Four forms act *inside* the core (:data:`INSIDE_FORMS`: the core re-driven
with ``mods``, see :mod:`bench.plants.blind11_cores`); the rest act on the stroke or on its
reading after it.

Rate dependence: plain, the bladder as a *generalised Maxwell solid* (a two-term Prony series:
relaxation times of 10-40 ms and 80-300 ms, the second branch 1-3 x as strong as the first) held
by the balance, so a fast move is first met by the instantaneous modulus and the stroke catches
up along the two relaxations (after); unusual, a *centrifugal governor brake* on the payload (its
shoes fly out above a threshold speed and brake with ``c (v^2 - v_c^2)``: moves slower than the
threshold are untouched, faster ones are held back towards the threshold speed behind the
balance's stiffness; after). Creep: plain, *Boltzmann superposition over the stroke's history with
a three-term Prony retardation spectrum* (Kelvin units at 1-3 s, 10-30 s and 100-300 s, equal
shares: a flat, log-time spectrum; after); unusual, *permeation into a sealed cover*: air diffuses
through the bladder into the gap under an airtight protective cover (the membrane's time lag of
2-6 s, then the gap's pressure settling in 8-30 s, fill and the cover's leak together, at 4-12 %
of the muscle's), and the gap's pressure, pushing back on the braid, takes away from the
muscle's: after a rise the stroke comes back down slowly (*reverse* creep), after a fall it
undershoots and creeps back up (inside). Transport delay: plain, a *FIFO of whole samples* (the
stroke channel 2-12 frames behind the pressure channel: a delay counted in samples, so its length
in seconds depends on the rate; after); unusual, an *adaptive jitter buffer* on the stroke's
network link (a playout delay that jumps up after late packets and creeps back down as the link's
transit times settle, over bursts of congestion; after). Load dependence: plain, the load's change
since the start hung on the payload directly or through a *block and tackle* rigged to multiply
the stroke 2:1-3:1 (so the muscle carries 1-3 x its weight: 9.8-30 N of pull per kg, in the
muscle's force balance; inside); unusual, the frame's slender *column* carrying the load bows more
as the load nears its Euler load (an *imperfect column*, sized so that the record's heaviest load
takes it to 70-85 % of its Euler load: bow ``a0 / (1 - P / P_cr)``, end shortening ``pi^2 (a^2 -
a0^2) / 4 l``, 0.01-0.06 mm at no load), lowering the muscle's anchor against the floor-mounted
stroke sensor (after). Temperature drift: plain, a *linear temperature coefficient of the lift-off
pressure* (a pre-stretched filled-rubber bladder whose modulus falls with the temperature: 4-12
mbar/K more to reach the braid, through the 1.5 mm wall's 3-10 s thermal lag; inside); unusual,
the nylon braid passing its *wet glass transition*, which its moisture puts where the rig's
temperatures pass (within a kelvin of the median of the braid's temperature over the record): the
fibres' compliance rises sigmoidally by 100-300 % (wet nylon 6 loses 2-4 x its modulus) across a
2-5 K wide transition, so they stretch more under the pressure (an effect that grows with the
pressure and only near the transition; through the thin fibres' 1.5-5 s lag; inside).

Load [kg] and temperature [degC] columns always move; when they are not the effect they are
decoys. Load: an *unbalanced rotor* (a vibration motor) on the payload's pan, its speed stepped
between set points (the load cell reads its weight plus the centrifugal force's vertical part, 4-7
Hz), or a payload hung from a pretensioned steel *guy wire* whose tension drops as the wire warms
(a decoy following the temperature column), re-tensioned by a turnbuckle now and then.
Temperature: a heater's *plume wandering* over the probe (an Ornstein-Uhlenbeck position, the
excess a Gaussian of the distance), or a glue dispenser laying beads beside the rig every 12-25 s
that cure *exothermically* (autocatalytic Kamal-Sourour kinetics with an Arrhenius rate: each bead
a slow rise that runs away, then cools).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import cont2discrete, lfilter

from bench.plants.blind11_cores import BLIND11_DRIVES, balance_stiffness, normalised_pressure
from bench.plants.blind11_rig import stroke_reading
from bench.plants.filters import lowpass, variable_delay

Array = NDArray[np.float64]
BLIND11_FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("prony_maxwell_bladder", "centrifugal_brake"),
    "creep": ("prony_kelvin_spectrum", "sealed_cover_permeation"),
    "transport_delay": ("fifo_frames", "adaptive_jitter_buffer"),
    "load_dependence": ("block_and_tackle", "imperfect_column"),
    "temperature_drift": ("lift_off_tempco", "nylon_glass_transition"),
}
PLAIN_FORMS: tuple[str, ...] = tuple(forms[0] for e, forms in BLIND11_FORMS.items() if e != "none")
INTENSITY_KEY: dict[str, str] = {  # the parameter that scales each form's size
    "prony_maxwell_bladder": "prony_share",
    "centrifugal_brake": "brake_gain",
    "prony_kelvin_spectrum": "kelvin_share",
    "sealed_cover_permeation": "cover_share",
    "fifo_frames": "fifo_samples",
    "adaptive_jitter_buffer": "latency_scale",
    "block_and_tackle": "pull_n_per_kg",
    "imperfect_column": "shortening_mm",
    "lift_off_tempco": "lift_mbar_per_k",
    "nylon_glass_transition": "compliance_rise",
}
INSIDE_FORMS: tuple[str, ...] = (
    "sealed_cover_permeation",
    "block_and_tackle",
    "lift_off_tempco",
    "nylon_glass_transition",
)
G_MS2 = 9.81


# ---- the load [kg] and temperature [degC] columns ---------------------------------------------------


def load_unbalanced_rotor(t: Array, rng: np.random.Generator) -> Array:
    """A 2.5-5 kg pan and motor with an unbalance ``m e`` of 3-6 kg mm: the load cell reads the
    weight plus ``m e w^2 sin(phase) / g`` [kg] (0.2-1.2 kg: the pan stays down); the speed steps
    (ramping over 0.5-1.5 s) between set points of 4-7 Hz every 4-12 s (the first within 1 s), the
    phase integrating the speed."""
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    mass, unbalance = float(rng.uniform(2.5, 5.0)), float(rng.uniform(3.0, 6.0)) * 1e-3  # kg, kg m
    knots_t, knots_f = [0.0], [float(rng.uniform(4.0, 7.0))]
    now = float(rng.uniform(0.2, 1.0))
    while now < t[-1] + 10.0:
        ramp = float(rng.uniform(0.5, 1.5))
        knots_t += [now, now + ramp]
        knots_f += [knots_f[-1], float(rng.uniform(4.0, 7.0))]
        now += ramp + float(rng.uniform(4.0, 12.0))
    f = np.interp(t, knots_t, knots_f)
    phase = 2.0 * np.pi * np.cumsum(f) * dt + float(rng.uniform(0.0, 6.3))
    omega = 2.0 * np.pi * f
    return np.asarray(mass + unbalance * omega**2 * np.sin(phase) / G_MS2, dtype=np.float64)


def load_thermal_guy_wire(t: Array, rng: np.random.Generator, temperature: Array) -> Array:
    """A 2-5 kg payload steadied by a pretensioned steel guy wire (1-2 mm^2, 1-3 kg of pretension
    pulling down on the pan): the wire's tension falls by ``E A alpha dT`` (E 200 GPa, alpha 12e-6
    /K) as it warms with the temperature through its 20-60 s lag; a turnbuckle re-tensions it to
    its pretension by 0.4-1.2 kg either way (kept in 0.5-4 kg) every 8-25 s (over 1-2 s; the first
    within 3 s)."""
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    payload, area = float(rng.uniform(2.0, 5.0)), float(rng.uniform(1.0, 2.0)) * 1e-6  # kg, m^2
    per_k = 200e9 * area * 12e-6 / G_MS2  # kg per K
    warm = lowpass(temperature, dt, float(rng.uniform(20.0, 60.0)))
    knots_t, knots_p = [0.0], [float(rng.uniform(1.0, 3.0))]
    now = float(rng.uniform(0.5, 3.0))
    while now < t[-1] + 10.0:
        turn = float(rng.uniform(1.0, 2.0))
        knots_t += [now, now + turn]
        step = float(rng.choice([-1.0, 1.0])) * float(rng.uniform(0.4, 1.2))
        knots_p += [knots_p[-1], float(np.clip(knots_p[-1] + step, 0.5, 4.0))]
        now += turn + float(rng.uniform(8.0, 25.0))
    pretension = np.interp(t, knots_t, knots_p)
    return np.asarray(payload + pretension - per_k * (warm - warm[0]), dtype=np.float64)


def temp_wandering_plume(t: Array, rng: np.random.Generator) -> Array:
    """A 19-25 degC room; a heater's plume, 8-18 K warmer at its axis and 20-50 mm wide, whose axis
    wanders about the probe as an Ornstein-Uhlenbeck process (RMS 25-60 mm, correlation 1-4 s),
    the probe's air warming by the Gaussian of its distance to the axis."""
    dt = float(t[1] - t[0]) if t.size > 1 else 1.0
    room, excess = float(rng.uniform(19.0, 25.0)), float(rng.uniform(8.0, 18.0))
    width, spread, corr = float(rng.uniform(20.0, 50.0)), float(rng.uniform(25.0, 60.0)), float(rng.uniform(1.0, 4.0))
    keep = math.exp(-dt / corr)
    kick = spread * math.sqrt(1.0 - keep * keep)
    start = float(rng.normal(0.0, spread))
    pos = lfilter([kick], [1.0, -keep], rng.standard_normal(t.size), zi=[keep * start])[0]
    return np.asarray(room + excess * np.exp(-0.5 * (pos / width) ** 2), dtype=np.float64)


def temp_exotherm_beads(t: Array, rng: np.random.Generator) -> Array:
    """A 20-26 degC room; a dispenser lays a glue bead beside the rig every 12-25 s (one already
    curing since 0-15 s before the start, the next within 0-6 s): each cures by Kamal-Sourour
    kinetics ``da/dt = (k1 + k2 a^m)(1 - a)^n`` (m 0.5-1, n 1.5-2), its rates Arrhenius in the bead's
    temperature (an activation of 6000-9000 K), heating it by 40-70 K of adiabatic rise and losing
    the heat in 3-8 s; the probe beside the bead line reads 30-50 % of the beads' excess through 2 s
    of air (simulated
    every 50 ms, read linearly between)."""
    room = float(rng.uniform(20.0, 26.0))
    share, rise = float(rng.uniform(0.3, 0.5)), float(rng.uniform(40.0, 70.0))
    m, n, act = float(rng.uniform(0.5, 1.0)), float(rng.uniform(1.5, 2.0)), float(rng.uniform(6000.0, 9000.0))
    k1, k2, lose = float(rng.uniform(0.01, 0.03)), float(rng.uniform(0.1, 0.3)), float(rng.uniform(3.0, 8.0))
    kinetics = (room, rise, m, n, act, k1, k2, lose)
    h = 0.05
    end = float(t[-1]) if t.size else 0.0
    laid = [-float(rng.uniform(0.0, 15.0)), float(rng.uniform(0.0, 6.0))]
    while laid[-1] < end:
        laid.append(laid[-1] + float(rng.uniform(12.0, 25.0)))
    grid = np.arange(laid[0], end + 2.0 * h, h)
    beads: list[list[float]] = []
    nxt = 0
    excess = np.empty(grid.size)
    for i, gi in enumerate(grid.tolist()):
        while nxt < len(laid) and laid[nxt] <= gi + 1e-9:
            beads.append([0.0, 0.0])
            nxt += 1
        beads = [_cure_step(b, h, kinetics) for b in beads]
        excess[i] = sum(b[1] for b in beads)
    probe = room + share * lowpass(excess, h, 2.0)
    return np.asarray(np.interp(t, grid, probe), dtype=np.float64)


def _cure_step(bead: list[float], h: float, kinetics: tuple[float, ...]) -> list[float]:
    """One explicit step ``h`` [s] of a bead's cure ``a`` and excess temperature [K]; ``kinetics`` =
    (room [degC], adiabatic rise [K], m, n, activation [K], k1, k2 [1/s at 25 degC], heat loss [s])."""
    room, rise, m, n, act, k1, k2, lose = kinetics
    a, excess = bead
    boost = math.exp(act * (1.0 / 298.15 - 1.0 / (273.15 + room + excess)))
    rate = (k1 + k2 * a**m) * (1.0 - a) ** n * boost
    a = min(a + h * rate, 1.0)
    excess += h * (rise * rate - excess / lose)
    return [a, excess]


LOAD_PATTERNS = ("unbalanced_rotor", "thermal_guy_wire")
TEMPERATURE_PATTERNS = ("wandering_plume", "exotherm_beads")


def columns(t: Array, rng: np.random.Generator) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] for a record, and their pattern names (independent of the
    effect; the guy wire's load follows the temperature)."""
    load_name = LOAD_PATTERNS[int(rng.integers(0, len(LOAD_PATTERNS)))]
    temp_name = TEMPERATURE_PATTERNS[int(rng.integers(0, len(TEMPERATURE_PATTERNS)))]
    temperature = temp_wandering_plume(t, rng) if temp_name == "wandering_plume" else temp_exotherm_beads(t, rng)
    if load_name == "unbalanced_rotor":
        load = load_unbalanced_rotor(t, rng)
    else:
        load = load_thermal_guy_wire(t, rng, temperature)
    return load, temperature, load_name, temp_name


# ---- effects ---------------------------------------------------------------------------------------


def draw_effect_params(effect: str, form: str, rng: np.random.Generator) -> dict[str, float]:
    """The drawn constants of ``effect`` in ``form`` (units in the key names or below)."""
    if form == "prony_maxwell_bladder":  # total relaxing share of the balance's stiffness; times [s]; split
        return {
            "prony_share": rng.uniform(0.1, 0.4),
            "tau1_s": rng.uniform(0.01, 0.04),
            "tau2_s": rng.uniform(0.08, 0.3),
            "second_over_first": rng.uniform(1.0, 3.0),
        }
    if form == "centrifugal_brake":  # brake gain [s^2/mm: N s^2/mm^2 per N/mm of stiffness]; threshold percentile
        return {"brake_gain": rng.uniform(2e-4, 2e-3), "threshold_pct": rng.uniform(55.0, 85.0)}
    if form == "prony_kelvin_spectrum":  # the delayed share of the stroke; the three retardation times [s]
        return {
            "kelvin_share": rng.uniform(0.03, 0.09),
            "tau_a_s": rng.uniform(1.0, 3.0),
            "tau_b_s": rng.uniform(10.0, 30.0),
            "tau_c_s": rng.uniform(100.0, 300.0),
        }
    if form == "sealed_cover_permeation":  # the gap's settled share of the pressure; lags [s]
        return {
            "cover_share": rng.uniform(0.04, 0.12),
            "membrane_s": rng.uniform(2.0, 6.0),
            "gap_s": rng.uniform(8.0, 30.0),
        }
    if form == "fifo_frames":
        return {"fifo_samples": rng.uniform(2.0, 12.0)}
    if form == "adaptive_jitter_buffer":  # transit scale [s]; burst spacing [s]; burst length [s]
        return {
            "latency_scale": rng.uniform(0.005, 0.02),
            "burst_every_s": rng.uniform(3.0, 10.0),
            "burst_s": rng.uniform(0.5, 2.0),
            "jitter_seed": float(rng.integers(0, 2**31)),
        }
    if form == "block_and_tackle":  # pull [N] per kg of load change (1-3 x g)
        return {"pull_n_per_kg": G_MS2 * rng.uniform(1.0, 3.0)}
    if form == "imperfect_column":  # shortening scale pi^2 a0^2 / 4l [mm]; heaviest P / P_cr; frame [kg]
        return {
            "shortening_mm": rng.uniform(0.01, 0.06),
            "heaviest_share": rng.uniform(0.7, 0.85),
            "frame_kg": rng.uniform(2.0, 5.0),
        }
    if form == "lift_off_tempco":  # [mbar/K]; the bladder's thermal lag [s]
        return {"lift_mbar_per_k": rng.uniform(4.0, 12.0), "bladder_tau_s": rng.uniform(3.0, 10.0)}
    if form == "nylon_glass_transition":  # compliance rise; transition above the median [K], width [K]; lag [s]
        return {
            "compliance_rise": rng.uniform(1.0, 3.0),
            "tg_above_median_k": rng.uniform(-1.0, 1.0),
            "tg_width_k": rng.uniform(2.0, 5.0),
            "braid_tau_s": rng.uniform(1.5, 5.0),
        }
    if effect == "none":
        return {}
    raise KeyError(f"unknown form {effect}:{form}; known: {BLIND11_FORMS}")


def prony_maxwell(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The stroke [mm] held back by a two-branch Maxwell solid in parallel with the balance: ``K (x_e -
    x) = K sum_i g_i (x - h_i)``, ``tau_i h_i' = x - h_i``, i.e. ``X / X_e = 1 / (1 + sum_i g_i s tau_i /
    (1 + s tau_i))`` (``g_1 + g_2 = prony_share``, ``g_2 / g_1 = second_over_first``); exact for ``x_e``
    held over a sample, from rest on ``x_e[0]``."""
    g1 = q["prony_share"] / (1.0 + q["second_over_first"])
    g2 = q["prony_share"] - g1
    t1, t2 = q["tau1_s"], q["tau2_s"]
    num = np.polymul([t1, 1.0], [t2, 1.0])
    den = np.polyadd(num, np.polyadd(g1 * np.polymul([t1, 0.0], [t2, 1.0]), g2 * np.polymul([t2, 0.0], [t1, 1.0])))
    b, a, _ = cont2discrete((num, den), dt_s, method="zoh")
    b, a = np.asarray(b, dtype=np.float64).ravel(), np.asarray(a, dtype=np.float64)
    return np.asarray(lfilter(b, a, x - x[0]) + x[0], dtype=np.float64)


def governed_stroke(x: Array, v: Array, dt_s: float, p: dict[str, float], q: dict[str, float]) -> Array:
    """The stroke [mm] behind a centrifugal brake: it follows ``x`` while that needs at most the
    threshold speed ``v_c`` (the ``threshold_pct`` percentile of the record's own stroke speed);
    otherwise it moves at the speed where the brake's ``c (u^2 - v_c^2)`` equals the balance's pull
    back ``K (x - y)`` (``c = brake_gain K``, ``K`` the balance's stiffness [N/mm]; implicit per
    sample: ``u^2 + c' u dt - (v_c^2 + K |x - y| / c) = 0``). From rest on ``x[0]``."""
    speed = np.abs(np.gradient(x, dt_s)) if x.size > 1 else np.zeros_like(x)
    v_c = max(float(np.percentile(speed, q["threshold_pct"])), 1e-6)
    stiff = balance_stiffness(v, x, p)
    out = np.empty(x.size)
    y = float(x[0])
    for i, (xi, ki) in enumerate(zip(x.tolist(), stiff.tolist())):
        gap = xi - y
        need = abs(gap) / dt_s
        if need > v_c:
            c = q["brake_gain"] * ki
            half = 0.5 * ki * dt_s / c
            u = -half + math.sqrt(half * half + v_c * v_c + ki * abs(gap) / c)
            y += math.copysign(min(u * dt_s, abs(gap)), gap)
        else:
            y = xi
        out[i] = y
    return out


def kelvin_spectrum(x: Array, dt_s: float, q: dict[str, float]) -> Array:
    """``x - c sum_i (x - lag_i(x)) / 3``: a third of the delayed share ``c = kelvin_share`` through
    each of the three Kelvin units (retardation times ``tau_a``, ``tau_b``, ``tau_c``), i.e. the
    stroke's history superposed with a flat, three-term retardation spectrum."""
    delayed = sum(x - lowpass(x, dt_s, q[key]) for key in ("tau_a_s", "tau_b_s", "tau_c_s"))
    return np.asarray(x - q["kelvin_share"] * delayed / 3.0, dtype=np.float64)


def cover_gap_pressure(v: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The gap's pressure [share of peak] under the sealed cover: the flow through the bladder (the
    membrane's lag ``membrane_s`` on the muscle's pressure) fills the gap, which the cover leaks to
    atmosphere, so the gap settles at ``cover_share`` of the muscle's pressure in ``gap_s`` (exact
    per sample); from an empty gap."""
    flow = np.clip(v, 0.0, None) - np.clip(v[:1], 0.0, None)  # from an empty gap at the start
    seen = lowpass(flow, dt_s, q["membrane_s"])
    return np.asarray(q["cover_share"] * lowpass(seen, dt_s, q["gap_s"]), dtype=np.float64)


def jitter_delay_s(n: int, dt_s: float, q: dict[str, float]) -> Array:
    """The adaptive jitter buffer's playout delay [s] per sample: packets' transit times are
    ``latency_scale (1 + E)`` (E exponential) and in congestion bursts (every ``burst_every_s`` on
    average, ``burst_s`` long) 3-8 x longer; the buffer's delay is the transit's running mean plus 4
    x its running deviation (NetEQ-like, forgetting over 0.5 s), and it grows at once when a packet
    would be late but falls at most 10 % of the sample time per sample (time-stretching)."""
    rng = np.random.default_rng(int(q["jitter_seed"]))
    scale = q["latency_scale"]
    t = np.arange(n, dtype=np.float64) * dt_s
    congested = np.zeros(n, dtype=bool)
    now = float(rng.exponential(q["burst_every_s"]))
    while now < (t[-1] if n else 0.0):
        length = q["burst_s"] * float(rng.uniform(0.5, 1.5))
        congested |= (t >= now) & (t < now + length)
        now += length + float(rng.exponential(q["burst_every_s"]))
    factor = np.where(congested, rng.uniform(3.0, 8.0), 1.0)
    transit = (scale * (1.0 + rng.exponential(1.0, n)) * factor).tolist()
    keep = math.exp(-dt_s / 0.5)
    mean, var, delay = 2.0 * scale, scale * scale, 3.0 * scale
    out = np.empty(n)
    for i, tr in enumerate(transit):
        mean = keep * mean + (1.0 - keep) * tr
        var = keep * var + (1.0 - keep) * (tr - mean) ** 2
        target = mean + 4.0 * math.sqrt(var)
        delay = max(target, tr, delay - 0.1 * dt_s)
        out[i] = delay
    return out


def column_shortening(load: Array, q: dict[str, float]) -> Array:
    """The column's end shortening [mm] under the frame's and the load's weight ``P`` [kg]:
    ``s ((1 - P / P_cr)^-2 - 1)`` with ``s = pi^2 a0^2 / 4 l`` (``shortening_mm``), the bow amplified
    from ``a0`` to ``a0 / (1 - P / P_cr)``; ``P_cr`` such that the record's heaviest ``P`` is
    ``heaviest_share`` of it."""
    weight = q["frame_kg"] + np.clip(load, 0.0, None)
    ratio = weight / (float(np.max(weight)) / q["heaviest_share"])
    return np.asarray(q["shortening_mm"] * ((1.0 - ratio) ** -2 - 1.0), dtype=np.float64)


def fibre_compliance(temperature: Array, dt_s: float, q: dict[str, float]) -> Array:
    """The braid fibres' compliance relative to the start's: ``(1 + r G(T)) / (1 + r G(T_0))``, ``G``
    the logistic glassy-to-rubbery share of the braid's lagged temperature ``T`` about ``T_g`` (its
    median over the record plus ``tg_above_median_k``; 10-90 % over ~``tg_width_k``), ``r`` the
    compliance's rise across the transition."""
    warm = lowpass(temperature, dt_s, q["braid_tau_s"])
    tg = float(np.median(warm)) + q["tg_above_median_k"]
    rubbery = 1.0 / (1.0 + np.exp(-np.clip((warm - tg) / (0.25 * q["tg_width_k"]), -60.0, 60.0)))
    compliance = 1.0 + q["compliance_rise"] * rubbery
    return np.asarray(compliance / compliance[0], dtype=np.float64)


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
    """Noise-free stroke reading [mm] of ``plant`` (its stroke ``base`` for the set pressure ``u``
    [bar]) with the effect ``form`` (``"none"``: switched off), through the rig
    (:func:`~bench.plants.blind11_rig.stroke_reading`).

    The load and temperature forms act through their column's change since the record's start
    (the plant as identified then): with the columns held at their first value they are the
    effect-free plant."""
    x = base
    if form in INSIDE_FORMS:
        v = normalised_pressure(u, dt_s, params)
        if form == "sealed_cover_permeation":
            mods = {"dv": -cover_gap_pressure(v, dt_s, q)}
        elif form == "block_and_tackle":
            mods = {"f_ext": q["pull_n_per_kg"] * (load - load[0])}
        elif form == "lift_off_tempco":
            warm = lowpass(temperature, dt_s, q["bladder_tau_s"])
            mods = {"lift": q["lift_mbar_per_k"] * 1e-3 * (warm - warm[0]) / params["peak"]}
        else:  # nylon_glass_transition
            mods = {"fibre": fibre_compliance(temperature, dt_s, q)}
        neutral = {"dv": 0.0, "lift": 0.0, "f_ext": 0.0, "fibre": 1.0}
        if any(np.any(m != neutral[k]) for k, m in mods.items()):  # else it is the core's own run, ``base``
            x = BLIND11_DRIVES[plant](v, dt_s, params, mods)
    elif form == "prony_maxwell_bladder":
        x = prony_maxwell(x, dt_s, q)
    elif form == "centrifugal_brake":
        x = governed_stroke(x, normalised_pressure(u, dt_s, params), dt_s, params, q)
    elif form == "prony_kelvin_spectrum":
        x = kelvin_spectrum(x, dt_s, q)
    elif form == "imperfect_column":
        short = column_shortening(load, q)
        x = x - (short - short[0])
    reading = stroke_reading(x, dt_s, params)
    if form == "fifo_frames":
        k = max(int(round(q["fifo_samples"])), 1)
        reading = np.concatenate([np.full(k, reading[0]), reading[:-k]])[: reading.size]
    elif form == "adaptive_jitter_buffer":
        reading = variable_delay(reading, jitter_delay_s(reading.size, dt_s, q) / dt_s)
    return np.asarray(reading, dtype=np.float64)
