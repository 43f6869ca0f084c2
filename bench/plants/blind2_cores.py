"""Four hysteresis cores for the fourth (blind2) plant family, structurally unlike the other ten.

Every core maps a pressure ``p`` [bar gauge, 0..peak] that reaches the muscle to a contraction
``y`` [mm], ``core(p, dt_s, params) -> y``, with the rig's own dynamics included (valve lag
with a slow thermal tail, a mechanical resonance), because a real rig has them even when no
hidden effect is present. Effects (:mod:`bench.plants.blind2_effects`) act on ``p`` before the
core or on ``y`` after it through the pressure-dependent stiffness :func:`stiffness_n_mm`.

* :func:`ja_duhem`: a Jiles-Atherton-type Duhem model (saturating tanh anhysteretic curve,
  mean-field feedback, pinning width ``k``, reversible share ``c``) of the braid/bladder state.
* :func:`antagonistic_joint`: two Chou-Hannaford muscles on a pulley, one at ``p``, one at a
  fixed bias; the joint bearing's elasto-plastic friction is loaded by the sum of the cable
  tensions (presliding, then slip); output = joint angle x pulley radius [mm].
* :func:`braid_deadband`: a proportional valve with a dead band integrating into the chamber
  (pressure hysteresis), then a Chou-Hannaford balance with three braid strands whose Coulomb
  friction grows with the pressure (loop width grows with ``p``).
* :func:`capstan_exo`: a muscle pulling a pretensioned exo joint spring through a Bowden
  sheath: capstan friction bounds the transmitted tension between ``T e^{-mu phi}`` and
  ``T e^{+mu phi}`` (multiplicative hysteresis), and the cable is slack below a threshold.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass, resonance

Array = NDArray[np.float64]
Core = Callable[[Array, float, dict[str, float]], Array]


def valve_line(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Pressure [bar] behind a proportional valve: a lag ``tau_valve_s`` plus a share
    ``tail_share`` that settles with the chamber's thermal time ``tail_tau_s`` (1.5-4 s)."""
    fast = lowpass(u, dt_s, p["tau_valve_s"])
    return (1.0 - p["tail_share"]) * fast + p["tail_share"] * lowpass(fast, dt_s, p["tail_tau_s"])


def stiffness_n_mm(p_bar: Array, params: dict[str, float]) -> Array:
    """Tangent stiffness [N/mm] the muscle opposes to an external force: it grows with pressure."""
    return np.asarray(params["k0_n_mm"] + params["k1_n_mm"] * np.clip(p_bar, 0.0, None) / params["peak"])


def _ch_terms(theta0: float) -> tuple[float, float]:
    """Chou-Hannaford ``a = 3 / tan^2 theta0``, ``b = 1 / sin^2 theta0``."""
    return 3.0 / math.tan(theta0) ** 2, 1.0 / math.sin(theta0) ** 2


# ---- Jiles-Atherton / Duhem --------------------------------------------------------------------


def ja_duhem(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """``dM/dh = (1 - c) (Man - M) / (d k - alpha (Man - M)) + c dMan/dh``, ``d = sign(dh)``,
    the irreversible part zero when it would run against the input; ``Man = tanh((h + alpha M -
    h0) / a)``; ``h`` the valve pressure over peak. ``y = stroke (M - M0) / (M1 - M0)`` [mm]
    through the payload resonance."""
    h = np.clip(valve_line(u, dt_s, p) / p["peak"], 0.0, 1.2)
    a, k, c, alpha, h0 = p["a"], p["k"], p["c"], p["alpha"], p["h0"]
    m = math.tanh(-h0 / a)
    m0 = m
    out = np.empty_like(h)
    last = 0.0
    for i, hi in enumerate(h.tolist()):
        dh = hi - last
        n = 1 + int(abs(dh) / 0.004)
        step = dh / n
        d = 1.0 if step >= 0.0 else -1.0
        hh = last
        for _ in range(n):
            hh += step
            man = math.tanh((hh + alpha * m - h0) / a)
            diff = man - m
            irr = (1.0 - c) * diff / (d * k - alpha * diff) if d * diff > 0.0 else 0.0
            rev = c * (1.0 - man * man) / a
            m += (irr + rev) * step
        last = hi
        out[i] = m
    m1 = math.tanh((1.0 + alpha - h0) / a)
    x = p["stroke_mm"] * (out - m0) / (m1 - m0)
    return resonance(x, dt_s, p["f_res_hz"], p["zeta"])


# ---- antagonistic pair on a joint ----------------------------------------------------------------


def joint_equilibrium(pa: Array, p: dict[str, float]) -> tuple[Array, Array, Array]:
    """Frictionless joint angle [rad], tangent stiffness and bearing-friction limit (both in
    torque / (r A0 bar) per rad and per unit) for muscle A at ``pa`` [bar], B at ``bias_bar``.

    Torque ``r A0 (pa (a (w - s th)^2 - b) - pb (a (w + s th)^2 - b)) - kj th = 0`` with
    ``w = 1 - eps0``, ``s = r / L0``: a quadratic in ``th``, solved in its stable form.
    """
    a, b = _ch_terms(p["theta0"])
    pb, w, s, kj = p["bias_bar"], 1.0 - p["eps0"], p["s"], p["kj"]
    pa = np.clip(pa, 0.0, None)
    a2 = a * s * s * (pa - pb)
    a1 = -2.0 * a * w * s * (pa + pb) - kj
    a0 = (pa - pb) * (a * w * w - b)
    th = 2.0 * a0 / (-a1 + np.sqrt(a1 * a1 - 4.0 * a2 * a0))
    stiff = -(2.0 * a2 * th + a1)
    tension = pa * np.maximum(a * (w - s * th) ** 2 - b, 0.0) + pb * (a * (w + s * th) ** 2 - b)
    return th, stiff, p["mu_rb"] * tension


def antagonistic_joint(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Elasto-plastic bearing friction around :func:`joint_equilibrium`: sticking with presliding
    stiffness ``kf``, slipping at the tension-loaded limit; then the joint's inertia resonance.
    Output ``r (th - th_vented)`` [mm]."""
    th0, stiff, limit = joint_equilibrium(valve_line(u, dt_s, p), p)
    kf = p["kf"]
    anchor = float(th0[0])
    out = np.empty_like(th0)
    for i, (t0, kk, tc) in enumerate(zip(th0.tolist(), stiff.tolist(), limit.tolist())):
        th = (kk * t0 + kf * anchor) / (kk + kf)
        force = kf * (th - anchor)
        if force > tc:
            th = t0 - tc / kk
            anchor = th - tc / kf
        elif force < -tc:
            th = t0 + tc / kk
            anchor = th + tc / kf
        out[i] = th
    vented = float(joint_equilibrium(np.zeros(1), p)[0][0])
    x = 1000.0 * p["r_m"] * (out - vented)
    return resonance(x, dt_s, p["f_res_hz"], p["zeta"])


# ---- dead-band valve and pressure-scaled braid friction ------------------------------------------


def deadband_chamber(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Chamber pressure [bar]: ``p' = (e - sign(e) db) / tau`` when ``|e| > db`` (``e = u - p``),
    else the valve is shut and the pressure holds; plus the thermal tail of :func:`valve_line`."""
    db, rate = p["deadband_bar"], 1.0 - math.exp(-dt_s / p["tau_valve_s"])
    out = np.empty_like(u)
    pr = 0.0
    for i, ui in enumerate(u.tolist()):
        e = ui - pr
        if e > db:
            pr += rate * (e - db)
        elif e < -db:
            pr += rate * (e + db)
        out[i] = pr
    return (1.0 - p["tail_share"]) * out + p["tail_share"] * lowpass(out, dt_s, p["tail_tau_s"])


def ch_contraction(pr: Array, p: dict[str, float]) -> Array:
    """Contraction [m] solving ``pr A0 (a (1 - e)^2 - b) = W + k L0 e`` (payload ``W``, spring ``k``)."""
    a, b = _ch_terms(p["theta0"])
    q = np.maximum(pr, 1e-6) * 1e5 * math.pi * p["r0_m"] ** 2
    kk = p["k_spring"] * p["l0_m"]
    s = (-kk + np.sqrt(kk * kk + 4.0 * q * a * (q * b + p["weight_n"] + kk))) / (2.0 * q * a)  # s = 1 - e
    return np.asarray(np.maximum(1.0 - s, 0.0) * p["l0_m"], dtype=np.float64)


def braid_deadband(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Three braid strands, each a play around the frictionless contraction whose half width is
    its Coulomb force ``mu_k pr A0`` over the balance's stiffness (width grows with pressure);
    output [mm] through a lightly damped payload resonance."""
    pr = deadband_chamber(u, dt_s, p)
    x0 = 1000.0 * ch_contraction(pr, p)
    radius = p["width_mm_per_bar"] * np.clip(pr, 0.0, None) / (1.0 + 0.5 * pr / p["peak"])
    shares = (0.5, 1.0, 1.5)
    states = [float(x0[0])] * 3
    out = np.empty_like(x0)
    for i, (xi, ri) in enumerate(zip(x0.tolist(), radius.tolist())):
        acc = 0.0
        for k in range(3):
            rk = shares[k] * ri
            sk = states[k]
            sk = xi - rk if sk < xi - rk else xi + rk if sk > xi + rk else sk
            states[k] = sk
            acc += sk
        out[i] = acc / 3.0
    return resonance(out, dt_s, p["f_res_hz"], p["zeta"])


# ---- Bowden cable with capstan friction to an exo joint ----------------------------------------


def capstan_bounds(pr: Array, p: dict[str, float]) -> tuple[Array, Array]:
    """Joint displacement [mm] while the tension rises (``c = e^{-mu phi}``) and while it falls
    (``c = e^{+mu phi}``): ``x = (c pr F0 alpha - T0) / (c pr F0 beta + kj)``, 0 while slack."""
    out = []
    for c in (math.exp(-p["mu_phi"]), math.exp(p["mu_phi"])):
        q = c * np.clip(pr, 0.0, None) * p["f0_n_bar"]
        out.append(np.maximum((q * p["alpha"] - p["t_pre_n"]) / (q * p["beta_per_mm"] + p["kj_n_mm"]), 0.0))
    return out[0], out[1]


def capstan_exo(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The joint stays put while the sheath's capstan friction holds it between
    :func:`capstan_bounds`; a soft end stop; the exo joint's inertia resonance, which cannot
    ring below the joint's rest stop [mm]."""
    up, down = capstan_bounds(valve_line(u, dt_s, p), p)
    out = np.empty_like(up)
    x = 0.0
    for i, (lo, hi) in enumerate(zip(up.tolist(), down.tolist())):
        x = lo if x < lo else hi if x > hi else x
        out[i] = x
    stop = p["stop_mm"]
    ringing = resonance(stop * np.tanh(out / stop), dt_s, p["f_res_hz"], p["zeta"])
    return np.maximum(ringing, 0.0)  # the joint rests on its stop when the cable goes slack


BLIND2_CORES: dict[str, Core] = {
    "ja_duhem": ja_duhem,
    "antagonistic_joint": antagonistic_joint,
    "braid_deadband": braid_deadband,
    "capstan_exo": capstan_exo,
}


def _rig(rng: np.random.Generator, peak: float, f_lo: float, f_hi: float, z_lo: float, z_hi: float) -> dict[str, float]:
    """What every core's rig has: valve lag, thermal tail, resonance, pressure-stiffened muscle."""
    return {
        "peak": peak,
        "tau_valve_s": rng.uniform(0.04, 0.12),
        "tail_share": rng.uniform(0.02, 0.05),
        "tail_tau_s": rng.uniform(1.5, 4.0),
        "f_res_hz": rng.uniform(f_lo, f_hi),
        "zeta": rng.uniform(z_lo, z_hi),
        "k0_n_mm": rng.uniform(1.5, 3.0),
        "k1_n_mm": rng.uniform(5.0, 12.0),
    }


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar]: output span ~15-45 mm,
    a loop 3-20 % of the span wide."""
    if core == "ja_duhem":
        return {
            **_rig(rng, peak, 4.0, 12.0, 0.15, 0.4),
            "a": rng.uniform(0.3, 0.5),
            "k": rng.uniform(0.018, 0.038),
            "c": rng.uniform(0.1, 0.3),
            "alpha": rng.uniform(0.0, 0.03),
            "h0": rng.uniform(0.2, 0.35),
            "stroke_mm": rng.uniform(18.0, 40.0),
        }
    if core == "antagonistic_joint":
        g = {
            **_rig(rng, peak, 3.0, 8.0, 0.1, 0.3),
            "theta0": math.radians(rng.uniform(20.0, 26.0)),
            "eps0": rng.uniform(0.04, 0.08),
            "bias_bar": rng.uniform(0.3, 0.5) * peak,
            "r_m": rng.uniform(0.015, 0.025),
            "mu_rb": 0.0,
            "kf": 1.0,
        }
        g["s"] = g["r_m"] / rng.uniform(0.2, 0.3)
        a, _ = _ch_terms(g["theta0"])
        g["kj"] = rng.uniform(1.0, 2.0) * a * g["s"] * peak
        th, stiff, tension = joint_equilibrium(np.array([0.0, 0.5 * peak, peak]), {**g, "mu_rb": 1.0})
        share = rng.uniform(0.05, 0.12)  # loop width over span at mid pressure
        g["mu_rb"] = share * float(th[2] - th[0]) * float(stiff[1]) / (2.0 * float(tension[1]))
        g["kf"] = rng.uniform(4.0, 8.0) * float(stiff[1])
        return g
    if core == "braid_deadband":
        g = {
            **_rig(rng, peak, 8.0, 20.0, 0.05, 0.15),
            "theta0": math.radians(rng.uniform(20.0, 26.0)),
            "r0_m": rng.uniform(0.006, 0.010),
            "l0_m": rng.uniform(0.2, 0.3),
            "weight_n": rng.uniform(1.0, 3.0) * 9.81,
            "deadband_bar": rng.uniform(0.012, 0.03) * peak,
            "k_spring": 1.0,
        }
        a, b = _ch_terms(g["theta0"])
        e = rng.uniform(18.0, 36.0) / 1000.0 / g["l0_m"]
        force = peak * 1e5 * math.pi * g["r0_m"] ** 2 * (a * (1.0 - e) ** 2 - b)
        g["k_spring"] = (force - g["weight_n"]) / (g["l0_m"] * e)  # N/m
        span = float(ch_contraction(np.array([peak]), g)[0] - ch_contraction(np.array([0.0]), g)[0]) * 1000.0
        g["width_mm_per_bar"] = rng.uniform(0.03, 0.07) * span / (0.8 * peak)
        return g
    if core == "capstan_exo":
        g = {
            **_rig(rng, peak, 5.0, 15.0, 0.1, 0.3),
            "f0_n_bar": rng.uniform(150.0, 300.0),
            "alpha": 1.0,
            "beta_per_mm": 1.0 / rng.uniform(45.0, 70.0),
            "t_pre_n": rng.uniform(20.0, 60.0),
            "mu_phi": rng.uniform(0.05, 0.12),
        }
        q, x_top = peak * g["f0_n_bar"], rng.uniform(18.0, 35.0)
        g["kj_n_mm"] = (q - g["t_pre_n"]) / x_top - q * g["beta_per_mm"]
        g["stop_mm"] = x_top * rng.uniform(1.3, 1.6)
        return g
    raise KeyError(f"unknown blind2 core {core!r}; known: {', '.join(BLIND2_CORES)}")
