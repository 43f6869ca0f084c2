"""Four hysteresis cores for the fifth (blind3) plant family, structurally unlike the other sixteen.

Every core maps a commanded pressure ``u`` [bar gauge, 0..peak] to a stroke ``y`` [mm],
``core(u, dt_s, params) -> y``, with the rig's own dynamics included: a valve lag with a slow
thermal pressure tail (:func:`valve_line`) and a mechanical resonance, because a real rig has
them even when no hidden effect is present. Effects (:mod:`bench.plants.blind3_effects`) act on
the pressure before the core or on the stroke after it; :func:`position_sensor` is the stroke
transducer every record is read through (its nonlinearity and mains hum are confounds).

* :func:`bistable_bellows`: an origami bellows actuator whose wall is a series chain of 30-50
  bistable folds (each snaps open above its own force and closes below a lower one), pushed by
  ``p A`` against a return spring. The spring makes the loading *mixed*: every snap lowers the
  wall force, so folds open one by one in avalanches (Puglisi-Truskinovsky chain), then ring.
* :func:`af_braid`: a muscle with an empirical power-law force map ``F = F0 (p / peak)
  (1 - e / e_max)^gamma`` against a payload and a return spring; the braid's inter-fibre
  friction is elasto-plastic with Armstrong-Frederick nonlinear kinematic hardening (yield
  surface ``|F - alpha| <= F_y``, back force ``d alpha = C d e_p - g alpha |d e_p|``).
* :func:`sleeve_dahl`: a bladder in a woven textile sleeve with a two-stage stroke: slack (the
  bladder inflates radially, little stroke) until the contact pressure ``p_c``, then taut (the
  weave contracts and jams, saturating); the sleeve-bladder friction is a Dahl element whose
  Coulomb level grows with the contact pressure ``p - p_c`` (zero while slack).
* :func:`karnopp_stickslip`: the muscle's end cap (mass ``m``) on a linear guide with Karnopp
  friction (static level above the kinetic one, a velocity window for sticking), a linear force
  model ``F = p (F_a - K_a x)`` (Reynolds et al.) and a return spring: second-order mechanics
  with 0.5 ms sub-steps; slow moves stick and slip.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass, resonance

Array = NDArray[np.float64]
Core = Callable[[Array, float, dict[str, float]], Array]
G_MS2 = 9.81


def valve_line(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Muscle pressure [bar] behind the proportional valve: two cascaded lags (spool
    ``tau_spool_s`` 10-30 ms, filling ``tau_fill_s`` 30-90 ms) and a share ``tail_share`` that
    settles with the air's heat exchange to the wall, ``tail_tau_s`` (1.5-4 s)."""
    fast = lowpass(lowpass(u, dt_s, p["tau_spool_s"]), dt_s, p["tau_fill_s"])
    return (1.0 - p["tail_share"]) * fast + p["tail_share"] * lowpass(fast, dt_s, p["tail_tau_s"])


def stiffness_n_mm(u: Array, params: dict[str, float]) -> Array:
    """Tangent axial stiffness [N/mm] the actuator opposes to an external force at pressure
    ``u`` [bar]: it grows with pressure (a stiffer inflated wall)."""
    return np.asarray(params["k0_n_mm"] + params["k1_n_mm"] * np.clip(u, 0.0, None) / params["peak"])


SENSOR_FULL_SCALE_MM = 60.0


def position_sensor(x: Array, dt_s: float, p: dict[str, float]) -> Array:
    """What the stroke transducer reports for a true stroke ``x`` [mm]: its integral
    nonlinearity (a bow of ``inl_bow_mm`` over the 60 mm full scale plus a ripple of
    ``inl_wave_mm`` with ``inl_cycles`` periods, zero at 0 mm) and mains hum picked up by the
    unshielded cable (``hum_mm`` at 50 or 60 Hz, sampled, so aliased by low sample rates, its
    amplitude breathing by +-30 % over 17 s)."""
    s = x / SENSOR_FULL_SCALE_MM
    wave = np.sin(2.0 * np.pi * p["inl_cycles"] * s + p["inl_phase"]) - math.sin(p["inl_phase"])
    inl = p["inl_bow_mm"] * 4.0 * s * (1.0 - s) + p["inl_wave_mm"] * wave
    t = np.arange(x.size, dtype=np.float64) * dt_s
    hum = (
        p["hum_mm"]
        * (1.0 + 0.3 * np.sin(2.0 * np.pi * t / 17.0))
        * np.sin(2.0 * np.pi * p["hum_hz"] * t + p["hum_phase"])
    )
    return np.asarray(x + inl + hum, dtype=np.float64)


# ---- a chain of bistable bellows folds ---------------------------------------------------------


def fold_thresholds(p: dict[str, float]) -> tuple[Array, Array, Array]:
    """Opening force ``f_up`` [N], closing force ``f_dn`` [N] and extra length ``delta`` [mm] of
    each fold: thresholds spread over ``[f_lo, f_hi]`` with disorder, gaps drawn per fold."""
    n = int(p["n_folds"])
    rng = np.random.default_rng(int(p["fold_seed"]))
    base = np.linspace(p["f_lo_n"], p["f_hi_n"], n)
    f_up = base + p["disorder"] * (p["f_hi_n"] - p["f_lo_n"]) / n * rng.standard_normal(n)
    gap = p["gap_n"] * rng.uniform(0.6, 1.4, n)
    delta = p["fold_mm"] * rng.uniform(0.7, 1.3, n)
    return f_up, f_up - gap, delta


def bistable_bellows(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Wall force ``F_w = (p A - k_r D) / (1 + k_r N / k_f)`` [N] with ``D`` the summed extra
    length [mm] of the open folds; a closed fold opens when ``F_w`` exceeds its ``f_up`` and an
    open one closes when ``F_w`` drops below its ``f_dn`` (one at a time, weakest first, until
    none is left: an avalanche). Stroke ``N F_w / k_f + D`` [mm] through the payload ringing."""
    f_up, f_dn, delta = fold_thresholds(p)
    n, area, k_r, k_f = f_up.size, p["area_n_bar"], p["k_return_n_mm"], p["k_fold_n_mm"]
    c1 = 1.0 + k_r * n / k_f
    is_open = np.zeros(n, dtype=bool)
    opened = 0.0
    inf = math.inf
    next_up, next_dn = float(f_up.min()), -inf
    out = np.empty_like(u)
    for i, pi in enumerate(valve_line(u, dt_s, p).tolist()):
        force = pi * area
        for _ in range(4 * n):  # a snap lowers (opening) or raises (closing) the wall force
            fw = (force - k_r * opened) / c1
            if fw > next_up:
                j = int(np.argmin(np.where(is_open, inf, f_up)))
                is_open[j], opened = True, opened + float(delta[j])
            elif fw < next_dn:
                j = int(np.argmax(np.where(is_open, f_dn, -inf)))
                is_open[j], opened = False, opened - float(delta[j])
            else:
                break
            next_up = float(np.min(np.where(is_open, inf, f_up)))
            next_dn = float(np.max(np.where(is_open, f_dn, -inf)))
        out[i] = n * max(fw, 0.0) / k_f + opened
    return resonance(out, dt_s, p["f_res_hz"], p["zeta"])


# ---- Armstrong-Frederick braid friction on a power-law muscle ----------------------------------


def free_contraction(v: Array, p: dict[str, float]) -> Array:
    """Frictionless contraction [mm] solving ``F0 v (1 - x / x_m)^gamma = W + k_s x`` (bisection;
    0 while the muscle cannot lift the payload ``W``)."""
    lo, hi = np.zeros_like(v), np.full_like(v, p["x_max_mm"])
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        surplus = p["f0_n"] * v * (1.0 - mid / p["x_max_mm"]) ** p["gamma"] - p["weight_n"] - p["k_spring_n_mm"] * mid
        lo, hi = np.where(surplus > 0.0, mid, lo), np.where(surplus > 0.0, hi, mid)
    return np.asarray(0.5 * (lo + hi), dtype=np.float64)


def muscle_stiffness(v: Array, x: Array, p: dict[str, float]) -> Array:
    """Tangent stiffness [N/mm] of the muscle-spring balance at ``(v, x)``."""
    slope = p["f0_n"] * v * p["gamma"] * np.clip(1.0 - x / p["x_max_mm"], 0.0, 1.0) ** (p["gamma"] - 1.0)
    return np.asarray(slope / p["x_max_mm"] + p["k_spring_n_mm"], dtype=np.float64)


def af_braid(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction ``x = x_f - N F / K_t`` [mm]: the braid friction is ``N F`` [N] with ``N = (0.05
    + 0.95 v) / 0.525`` the fibres' normal force relative to mid pressure (it grows with the
    pressure) and ``F`` the Armstrong-Frederick state at mid pressure, elastic (``dF = E dx``)
    inside ``|F - alpha| <= F_y`` and plastic on it (``dF = E H / (E + H) dx``, ``H = C - g n
    alpha``, ``d alpha = dF``), where ``dx = dx_f K_t / (K_t + N E_t)`` (the friction in series
    with the balance); sub-steps of at most 0.05 mm; then the ringing, which cannot take the
    payload below its rest stop (0 mm)."""
    v = np.clip(valve_line(u, dt_s, p) / p["peak"], 0.0, None)
    xf = free_contraction(v, p)
    kt = muscle_stiffness(v, xf, p)
    normal = (0.05 + 0.95 * v) / 0.525
    e, fy, c, g = p["e_n_mm"], p["f_yield_n"], p["c_n_mm"], p["g_per_mm"]
    force, alpha, last = 0.0, 0.0, float(xf[0])
    out = np.empty_like(xf)
    for i, (target, k, nr) in enumerate(zip(xf.tolist(), kt.tolist(), normal.tolist())):
        n_sub = 1 + int(abs(target - last) / 0.05)
        step = (target - last) / n_sub
        for _ in range(n_sub):
            trial = force + e * k / (k + nr * e) * step
            if abs(trial - alpha) <= fy:
                force = trial
            else:
                n = 1.0 if trial > alpha else -1.0
                h = max(c - g * n * alpha, 1e-9)
                tangent = e * h / (e + h)
                alpha += tangent * k / (k + nr * tangent) * step
                force = alpha + n * fy
        last = target
        out[i] = target - nr * force / k
    return np.maximum(resonance(out, dt_s, p["f_res_hz"], p["zeta"]), 0.0)  # the payload rests on its stop


# ---- textile sleeve: slack then taut, Dahl friction on contact ----------------------------------


def sleeve_stroke(v: Array, p: dict[str, float]) -> tuple[Array, Array]:
    """Frictionless stroke [mm] (slack stage: ``s1`` over ``[0, c]`` by the bladder alone; taut
    stage: ``s2 (1 - exp(-(v - c) / v_j))``, normalised, as the weave jams) and the Dahl
    Coulomb level [mm], proportional to the contact pressure ``(v - c)+``."""
    c, vj = p["contact_share"], p["jam_share"]
    slack = p["s1_mm"] * np.clip(v, 0.0, c) / c
    taut = np.clip(v - c, 0.0, None)
    stroke = slack + p["s2_mm"] * -np.expm1(-taut / vj) / -math.expm1(-(1.0 - c) / vj)
    return stroke, p["r_max_mm"] * taut / (1.0 - c)


def sleeve_dahl(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Dahl friction in stroke units: ``dz = s dx / (1 + s)``, ``s = kappa (1 - sign(dx) z / r)``
    (``kappa``: presliding over the actuator's stiffness), ``|z| <= r``; output ``x - z`` [mm]
    through the ringing."""
    x, radius = sleeve_stroke(np.clip(valve_line(u, dt_s, p) / p["peak"], 0.0, None), p)
    kappa = p["kappa"]
    z, last = 0.0, float(x[0])
    out = np.empty_like(x)
    for i, (xi, ri) in enumerate(zip(x.tolist(), radius.tolist())):
        if ri <= 1e-9:
            z = 0.0
        else:
            d = xi - last
            n_sub = 1 + int(abs(d) / (0.2 * ri + 0.01))
            step, sgn = d / n_sub, (1.0 if d >= 0.0 else -1.0)
            for _ in range(min(n_sub, 200)):
                s = kappa * max(1.0 - sgn * z / ri, 0.0)
                z += s * step / (1.0 + s)
            z = min(max(z, -ri), ri)
        last = xi
        out[i] = xi - z
    return resonance(out, dt_s, p["f_res_hz"], p["zeta"])


# ---- Karnopp stick-slip on a linear guide -------------------------------------------------------


def karnopp_stickslip(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """``m x'' = p F_a - (p K_a + k_s) x - c x' - F_f`` [N, mm, kg] (semi-implicit Euler, 1 ms
    sub-steps or finer): within ``|x'| < v_eps`` the guide sticks while the applied force stays
    within ``F_s`` (else it breaks away at ``F_s``); outside, ``F_f = F_k sign(x')``. End stop at 0."""
    pr = valve_line(u, dt_s, p)
    n_sub = max(1, int(math.ceil(dt_s / 0.001)))
    h = dt_s / n_sub
    fa, ka, ks, c = p["f_a_n_bar"], p["k_a_n_bar_mm"], p["k_spring_n_mm"], p["c_n_s_mm"]
    fs, fk, veps, acc = p["f_static_n"], p["f_kinetic_n"], p["v_eps_mm_s"], 1000.0 / p["mass_kg"]
    x, v = 0.0, 0.0
    out = np.empty_like(pr)
    for i, pi in enumerate(pr.tolist()):
        drive, stiff = pi * fa, pi * ka + ks
        for _ in range(n_sub):
            applied = drive - stiff * x - c * v
            if abs(v) < veps:
                if abs(applied) <= fs:
                    v = 0.0
                    continue
                net = applied - (fs if applied > 0.0 else -fs)
            else:
                net = applied - (fk if v > 0.0 else -fk)
            v += h * acc * net
            x += h * v
            if x < 0.0:
                x, v = 0.0, max(v, 0.0)
        out[i] = x
    return out


BLIND3_CORES: dict[str, Core] = {
    "bistable_bellows": bistable_bellows,
    "af_braid": af_braid,
    "sleeve_dahl": sleeve_dahl,
    "karnopp_stickslip": karnopp_stickslip,
}


def _rig(rng: np.random.Generator, peak: float, f_lo: float, f_hi: float, z_lo: float, z_hi: float) -> dict[str, float]:
    """What every core's rig has: a two-lag valve, the thermal pressure tail, a resonance, a
    pressure-stiffened actuator (``k0 + k1 p / peak`` [N/mm])."""
    return {
        "peak": peak,
        "tau_spool_s": rng.uniform(0.01, 0.03),
        "tau_fill_s": rng.uniform(0.03, 0.09),
        "tail_share": rng.uniform(0.02, 0.05),
        "tail_tau_s": rng.uniform(1.5, 4.0),
        "f_res_hz": rng.uniform(f_lo, f_hi),
        "zeta": rng.uniform(z_lo, z_hi),
        "k0_n_mm": rng.uniform(1.0, 2.5),
        "k1_n_mm": rng.uniform(4.0, 10.0),
        "inl_bow_mm": rng.uniform(0.08, 0.25),
        "inl_wave_mm": rng.uniform(0.03, 0.1),
        "inl_cycles": rng.uniform(2.0, 4.0),
        "inl_phase": rng.uniform(0.0, 2.0 * math.pi),
        "hum_mm": rng.uniform(0.008, 0.02),
        "hum_hz": float(rng.choice([50.0, 60.0])),
        "hum_phase": rng.uniform(0.0, 2.0 * math.pi),
    }


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar]: stroke span ~15-45 mm,
    a loop 3-20 % of the span wide."""
    if core == "bistable_bellows":
        g = {**_rig(rng, peak, 6.0, 16.0, 0.2, 0.4)}  # a polymer bellows damps its snaps
        n = int(rng.integers(30, 51))
        stroke = rng.uniform(18.0, 35.0)  # mm, all folds open
        f_lo, f_hi = rng.uniform(15.0, 30.0), rng.uniform(90.0, 160.0)  # N
        k_f = n * rng.uniform(30.0, 60.0)  # N/mm per fold: a stiff chain, 0.5-1 mm elastic per fold
        k_r = rng.uniform(0.6, 1.2) * (f_hi - f_lo) / stroke  # the return spring takes a share of the rise
        g.update(
            n_folds=float(n),
            fold_seed=float(rng.integers(1 << 30)),
            fold_mm=stroke / n,
            f_lo_n=f_lo,
            f_hi_n=f_hi,
            disorder=rng.uniform(0.5, 2.0),
            k_fold_n_mm=k_f,
            k_return_n_mm=k_r,
        )
        gap_floor = 1.5 * k_r * 1.3 * stroke / n / (1.0 + k_r * n / k_f)  # > the drop of one snap
        g["gap_n"] = max(rng.uniform(0.06, 0.14) * (f_hi - f_lo), gap_floor)
        g["area_n_bar"] = (1.2 * f_hi * (1.0 + k_r * n / k_f) + k_r * 1.3 * stroke) / peak
        return g
    if core == "af_braid":
        g = {
            **_rig(rng, peak, 4.0, 12.0, 0.1, 0.3),
            "f0_n": rng.uniform(600.0, 1200.0),
            "x_max_mm": rng.uniform(40.0, 60.0),
            "gamma": rng.uniform(1.5, 2.5),
            "weight_n": rng.uniform(0.03, 0.08),
            "k_spring_n_mm": rng.uniform(5.0, 12.0),
        }
        g["weight_n"] *= g["f0_n"]
        top = float(free_contraction(np.array([1.0]), g)[0])
        k_mid = float(muscle_stiffness(np.array([0.5]), np.array([0.5 * top]), g)[0])
        amp = rng.uniform(0.02, 0.04) * top * k_mid  # friction amplitude [N]: half the loop width
        share = rng.uniform(0.3, 0.5)
        g.update(f_yield_n=share * amp, e_n_mm=rng.uniform(5.0, 10.0) * k_mid)
        g["g_per_mm"] = 1.0 / (rng.uniform(0.04, 0.1) * top)
        g["c_n_mm"] = g["g_per_mm"] * (1.0 - share) * amp
        return g
    if core == "sleeve_dahl":
        g = {
            **_rig(rng, peak, 8.0, 20.0, 0.05, 0.2),
            "contact_share": rng.uniform(0.08, 0.18),
            "jam_share": rng.uniform(0.3, 0.6),
            "s1_mm": rng.uniform(1.0, 3.0),
            "s2_mm": rng.uniform(15.0, 35.0),
            "kappa": rng.uniform(2.0, 6.0),
        }
        g["r_max_mm"] = rng.uniform(0.05, 0.1) * (g["s1_mm"] + g["s2_mm"])
        return g
    if core == "karnopp_stickslip":
        mass, f_hz = rng.uniform(1.0, 3.0), rng.uniform(5.0, 10.0)
        k_mid = mass * (2.0 * math.pi * f_hz) ** 2 / 1000.0  # N/mm at mid pressure
        ks = rng.uniform(0.3, 0.5) * k_mid
        ka = (k_mid - ks) / (0.5 * peak)
        stroke = rng.uniform(18.0, 35.0)
        fa = stroke * (peak * ka + ks) / peak
        fk = rng.uniform(0.015, 0.03) * stroke * k_mid
        g = {
            **_rig(rng, peak, f_hz, f_hz, 0.05, 0.15),
            "mass_kg": mass,
            "f_a_n_bar": fa,
            "k_a_n_bar_mm": ka,
            "k_spring_n_mm": ks,
            "f_kinetic_n": fk,
            "f_static_n": fk * rng.uniform(1.03, 1.1),
            "v_eps_mm_s": rng.uniform(0.3, 1.0),
            "k0_n_mm": ks,
            "k1_n_mm": peak * ka,
        }
        g["c_n_s_mm"] = 2.0 * g["zeta"] * math.sqrt(k_mid * 1000.0 * mass) / 1000.0
        return g
    raise KeyError(f"unknown blind3 core {core!r}; known: {', '.join(BLIND3_CORES)}")
