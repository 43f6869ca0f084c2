"""Four hysteresis cores for the seventh (blind5) plant family, structurally unlike the other twenty-four.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params, width=None) -> y``, through the supply regulator
(:func:`bench.plants.blind5_rig.regulator`: a lag and the diaphragm's small play); ``width`` is a
per-sample factor on the element that makes the loop (1: as drawn), through which the
lubricant's thixotropy acts. The rest of the rig (the mount's settling, mains hum, the pressure
transducer's error, dropped frames) is added by :mod:`bench.plants.blind5_rig`; effects
(:mod:`bench.plants.blind5_effects`) act on the set pressure before the core or on the
contraction after it.

* :func:`vector_fibre_play`: the fibres of the two braid layers slide over each other in the
  plane of the sleeve, so their Coulomb friction is *isotropic in two dimensions*: a crossing is a
  vector play (a circular stick region) driven along the braid's curved kinematic path in
  (axial, hoop) displacement. Four radii and a reversible share; the muscle's statics are the
  Chou-Hannaford balance (solved in closed form) against a payload and a spring.
* :func:`rolling_lobe_peel`: a rolling-lobe (air-spring-like) actuator whose membrane rolls over
  a tapered piston; the rolling front advances only when the pressure force beats the peel
  force and recedes only when it falls below the re-adhesion force (two different thresholds,
  scaled by the lobe's circumference, which grows with the stroke), plus the membrane's own
  elastic bulge.
* :func:`drawwire_stickslip`: a frictionless Chou-Hannaford muscle read through a draw-wire
  sensor whose drum bearing has static above kinetic friction, both in proportion to the wire
  tension (the drum's spring); the elastic wire stretches until the drum breaks away and
  slips (quasi-static stick-slip with an overshoot), so the reading lags in a sawtooth.
* :func:`moving_play_assist`: a Prandtl-Ishlinskii braid (four plays in pressure and a
  reversible share) with a negative-stiffness assist spring that feeds the contraction back
  into the effective pressure (a Della Torre *moving* model), then the braid's lock-up as a
  tanh saturation of the stroke.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_rig import draw_rig, regulator

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array: ...


def _width(width: Array | None, like: Array) -> list[float]:
    return (np.ones_like(like) if width is None else np.asarray(width, dtype=np.float64)).tolist()


# ---- Chou-Hannaford statics ----------------------------------------------------------------------


def chou_hannaford_contraction(pressure: Array, p: dict[str, float]) -> Array:
    """Contraction [mm] of a McKibben muscle (Chou-Hannaford: ``F = A p (3 cos^2(theta0) (1 -
    e)^2 - 1)``, ``A = pi D0^2 / (4 sin^2 theta0)``) balancing a payload ``W`` and a spring
    ``k``: with ``s = 1 - e`` the balance ``3 A p c^2 s^2 + k L0 s - (A p + W + k L0) = 0`` is
    solved in closed form (the rationalised root, stable at ``p = 0``); never negative."""
    theta = math.radians(p["braid_deg"])
    area = BAR_N_MM2 * math.pi * p["d0_mm"] ** 2 / (4.0 * math.sin(theta) ** 2)  # N/bar
    c2 = math.cos(theta) ** 2
    ap = area * np.clip(pressure, 0.0, None)
    kl = p["k_spring_n_mm"] * p["l0_mm"]
    rhs = ap + p["weight_n"] + kl
    s = 2.0 * rhs / (kl + np.sqrt(kl * kl + 12.0 * ap * c2 * rhs))
    return np.asarray(np.clip(p["l0_mm"] * (1.0 - s), 0.0, None), dtype=np.float64)


def _chou_hannaford_params(rng: np.random.Generator, peak: float, stroke_mm: float) -> dict[str, float]:
    """A muscle (bore 10-20 mm, braid 18-26 deg, 150-300 mm long) whose spring makes full
    pressure contract it ``stroke_mm``; the payload is 5-15 % of its vented force at ``peak``."""
    g = {
        "d0_mm": rng.uniform(10.0, 20.0),
        "braid_deg": rng.uniform(18.0, 26.0),
        "l0_mm": rng.uniform(150.0, 300.0),
    }
    theta = math.radians(g["braid_deg"])
    area = BAR_N_MM2 * math.pi * g["d0_mm"] ** 2 / (4.0 * math.sin(theta) ** 2)
    c2 = math.cos(theta) ** 2
    g["weight_n"] = rng.uniform(0.05, 0.15) * area * peak * (3.0 * c2 - 1.0)
    e_top = stroke_mm / g["l0_mm"]
    top = area * peak * (3.0 * c2 * (1.0 - e_top) ** 2 - 1.0) - g["weight_n"]
    g["k_spring_n_mm"] = max(top, 1.0) / stroke_mm
    return g


# ---- vector play of crossed fibres ---------------------------------------------------------------

VECTOR_RADII = (0.4, 0.8, 1.2, 1.6)  # times radius_mm


def braid_path(pressure: Array, p: dict[str, float]) -> tuple[Array, Array]:
    """Axial and hoop displacement [mm] of a fibre crossing at ``pressure``: the contraction, and
    ``hoop_gain D0 (D / D0 - 1)`` with ``D / D0 = sqrt(1 - (1 - e)^2 cos^2 theta0) / sin theta0``."""
    axial = chou_hannaford_contraction(pressure, p)
    theta = math.radians(p["braid_deg"])
    s = 1.0 - axial / p["l0_mm"]
    ratio = np.sqrt(np.clip(1.0 - s * s * math.cos(theta) ** 2, 0.0, None)) / math.sin(theta)
    return axial, np.asarray(p["hoop_gain"] * p["d0_mm"] * (ratio - 1.0), dtype=np.float64)


def vector_fibre_play(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Contraction [mm] ``w0 a + sum_j w_j Z_j,a``: ``Z_j`` the crossings' positions, each a
    vector play of radius ``r_j`` around the path point ``X = (a, h)`` (``Z`` moves only when
    ``|X - Z| > r_j``, then onto the circle, towards ``X``), starting on the path."""
    axial, hoop = braid_path(regulator(u, dt_s, p), p)
    radii = [p["radius_mm"] * k for k in VECTOR_RADII]
    weights = [p[f"w{j}"] for j in range(1, 5)]
    za, zh = [float(axial[0])] * 4, [float(hoop[0])] * 4
    out = np.empty_like(axial)
    for i, (a, h, w) in enumerate(zip(axial.tolist(), hoop.tolist(), _width(width, axial))):
        total = p["w0"] * a
        for j in range(4):
            da, dh = a - za[j], h - zh[j]
            dist, r = math.hypot(da, dh), radii[j] * w
            if dist > r:
                shrink = r / dist
                za[j], zh[j] = a - da * shrink, h - dh * shrink
            total += weights[j] * za[j]
        out[i] = total
    return out


# ---- rolling lobe with peel and re-adhesion ------------------------------------------------------


def lobe_fronts(pressure: Array, p: dict[str, float], w: Array) -> tuple[Array, Array]:
    """Positions [mm] where the rolling front would advance (``F(p, s) = k s + W + f_a c(s)``)
    and recede (``= k s + W - f_r c(s)``): ``F = A0 (1 + a s / S) p``, ``c(s) = 1 + a s / 2 S``
    (both linear in ``s``: closed form), clipped into 0..1.2 S."""
    a0p = BAR_N_MM2 * p["piston_mm2"] * np.clip(pressure, 0.0, None)
    taper, stroke, k, load = p["taper"], p["stroke_mm"], p["k_spring_n_mm"], p["weight_n"]
    fa, fr = p["peel_n"] * w, p["readhere_n"] * w
    adv = (a0p - load - fa) / (k - a0p * taper / stroke + fa * taper / (2.0 * stroke))
    rec = (a0p - load + fr) / (k - a0p * taper / stroke - fr * taper / (2.0 * stroke))
    return np.clip(adv, 0.0, 1.2 * stroke), np.clip(rec, 0.0, 1.2 * stroke)


def rolling_lobe_peel(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Stroke [mm]: the rolling front ``s`` stays put between its advance and recede positions
    and is pushed by them, plus the membrane's bulge ``bulge_share S p / peak``."""
    pressure = regulator(u, dt_s, p)
    w = np.asarray(_width(width, pressure))
    adv, rec = lobe_fronts(pressure, p, w)
    out = np.empty_like(pressure)
    s = float(adv[0])
    for i, (lo, hi) in enumerate(zip(adv.tolist(), rec.tolist())):
        s = min(max(s, lo), hi)
        out[i] = s
    return np.asarray(out + p["bulge_share"] * p["stroke_mm"] * pressure / p["peak"], dtype=np.float64)


# ---- draw-wire sensor with stick-slip ------------------------------------------------------------


def drawwire_stickslip(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Reading [mm] of the drum ``d`` of a draw-wire sensor on a frictionless muscle ``x``: the
    wire (``k_w``) pulls against the drum spring ``T = T0 + k_d d``; the drum sticks while
    ``|k_w (x - d) - T| <= mu_s w T`` and, when it breaks away, slips to where the imbalance is
    ``mu' w T``, ``mu' = mu_k - overshoot (mu_s - mu_k)`` (closed form). Zeroed at vented rest."""
    x = chou_hannaford_contraction(regulator(u, dt_s, p), p)
    kw, t0, kd = p["k_wire_n_mm"], p["t0_n"], p["k_drum_n_mm"]
    mu_s, mu_slip = p["mu_static"], p["mu_kinetic"] - p["overshoot"] * (p["mu_static"] - p["mu_kinetic"])
    d0 = -t0 / (kw + kd)  # frictionless drum at x = 0
    d = d0
    out = np.empty_like(x)
    for i, (xi, wi) in enumerate(zip(x.tolist(), _width(width, x))):
        tension = t0 + kd * d
        pull = kw * (xi - d) - tension
        if pull > mu_s * wi * tension:
            m = 1.0 + mu_slip * wi
            d = (kw * xi - m * t0) / (kw + m * kd)
        elif pull < -mu_s * wi * tension:
            m = 1.0 - mu_slip * wi
            d = (kw * xi - m * t0) / (kw + m * kd)
        out[i] = d - d0
    return out


# ---- moving Prandtl-Ishlinskii with an assist spring ---------------------------------------------

PLAY_RADII = (0.25, 0.6, 1.0, 1.5)  # times radius_share * peak


def moving_play_assist(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Stroke [mm] ``S tanh(kappa z) / tanh(kappa)``, ``z = (w0 v + sum_j w_j play_j(v)) / peak``
    (never below 0: the muscle cannot lengthen past its rest), the plays seeing the effective
    pressure ``v = p + beta peak y / S`` with ``y`` the stroke one sample before (the assist
    spring's feedback; the loop gain stays below 1, so this settles within a few samples)."""
    pressure = regulator(u, dt_s, p)
    peak, stroke, beta, kappa = p["peak"], p["stroke_mm"], p["assist_beta"], p["kappa"]
    radii = [p["radius_share"] * peak * k for k in PLAY_RADII]
    weights = [p[f"w{j}"] for j in range(1, 5)]
    norm = math.tanh(kappa)
    y = 0.0
    plays = [float(pressure[0]) - r for r in radii]
    out = np.empty_like(pressure)
    for i, (pi, w) in enumerate(zip(pressure.tolist(), _width(width, pressure))):
        v = pi + beta * peak * y / stroke
        z = p["w0"] * v
        for j in range(4):
            r = radii[j] * w
            plays[j] = min(max(plays[j], v - r), v + r)
            z += weights[j] * plays[j]
        y = stroke * math.tanh(kappa * max(z, 0.0) / peak) / norm
        out[i] = y
    return out


BLIND5_CORES: dict[str, Core] = {
    "vector_fibre_play": vector_fibre_play,
    "rolling_lobe_peel": rolling_lobe_peel,
    "drawwire_stickslip": drawwire_stickslip,
    "moving_play_assist": moving_play_assist,
}


def _weights(rng: np.random.Generator, reversible: float) -> dict[str, float]:
    w = rng.dirichlet(np.full(4, 2.0)) * (1.0 - reversible)
    return {"w0": reversible, **{f"w{j + 1}": float(w[j]) for j in range(4)}}


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~15-38 mm, a
    loop 3-20 % of the stroke wide), its rig's constants included; ``k_load_n_mm`` is the
    stiffness [N/mm] the payload meets at the muscle's end."""
    stroke = float(rng.uniform(15.0, 38.0))
    g = draw_rig(rng, peak)
    if core in ("vector_fibre_play", "drawwire_stickslip"):
        g.update(_chou_hannaford_params(rng, peak, stroke))
        g["k_load_n_mm"] = g["k_spring_n_mm"]
        if core == "vector_fibre_play":
            g.update(hoop_gain=rng.uniform(0.5, 1.5), radius_mm=rng.uniform(0.02, 0.045) * stroke)
            g.update(_weights(rng, float(rng.uniform(0.2, 0.4))))
            return g
        kw, t0, kd = rng.uniform(1.5, 4.0), rng.uniform(3.0, 8.0), rng.uniform(0.05, 0.15)
        mu_s = min(rng.uniform(0.02, 0.045) * stroke * kw / (t0 + 0.5 * kd * stroke), 0.6)
        g.update(k_wire_n_mm=kw, t0_n=t0, k_drum_n_mm=kd, mu_static=mu_s)
        g.update(mu_kinetic=rng.uniform(0.75, 0.9) * mu_s, overshoot=rng.uniform(0.1, 0.4))
        return g
    if core == "rolling_lobe_peel":
        a0, taper = rng.uniform(800.0, 1500.0), rng.uniform(0.1, 0.3)
        a0p = BAR_N_MM2 * a0 * peak
        load = rng.uniform(0.1, 0.2) * a0p
        k = (a0p * (1.0 + taper) - load) / stroke
        k_mid = k - 0.5 * a0p * taper / stroke
        thresholds = rng.uniform(0.035, 0.08) * stroke * k_mid
        share = rng.uniform(0.3, 0.7)
        g.update(piston_mm2=a0, taper=taper, stroke_mm=stroke, k_spring_n_mm=k, weight_n=load, k_load_n_mm=k_mid)
        g.update(peel_n=share * thresholds, readhere_n=min((1.0 - share) * thresholds, 0.6 * load))
        g.update(bulge_share=rng.uniform(0.03, 0.08))
        return g
    if core == "moving_play_assist":
        g.update(stroke_mm=stroke, assist_beta=rng.uniform(0.1, 0.25), kappa=rng.uniform(0.8, 1.6))
        g.update(radius_share=rng.uniform(0.02, 0.04), k_load_n_mm=rng.uniform(3.0, 8.0))
        g.update(_weights(rng, float(rng.uniform(0.25, 0.45))))
        return g
    raise KeyError(f"unknown blind5 core {core!r}; known: {', '.join(BLIND5_CORES)}")
