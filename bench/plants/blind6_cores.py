"""Four hysteresis cores for the eighth (blind6) plant family, structurally unlike the other twenty-eight.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params, width=None) -> y``, through the spool valve
(:func:`bench.plants.blind6_rig.spool_valve`); ``width`` is a per-sample factor on the element
that makes the loop (1: as drawn), through which the liner's temperature acts. The rest of the
rig (compressor vibration, crosstalk, the snubbed pressure port, sampling jitter) is added by
:mod:`bench.plants.blind6_rig`; effects (:mod:`bench.plants.blind6_effects`) act on the set
pressure before the core or on the contraction after it.

* :func:`pleated_berg`: a pleated muscle (Daerden's PPAM: a force that is very large at small
  contraction and falls hyperbolically, ``F = p A (c0 / (e + c1) - 1)``) against a payload and a
  spring, closed form; the bladder's filled-rubber friction follows *Berg's* model in pressure
  (after a reversal the friction approaches its limit along a hyperbola, half way within a
  distance ``x2``).
* :func:`rayleigh_lambert`: the braid's inter-fibre slip as a *Rayleigh law* in pressure
  (every branch quadratic in the distance from its reversal, a stack of reversals wiped out when
  a branch passes the one before: closed minor loops), driving a muscle with an *exponential*
  force law ``F = p A e^(-x / x0)`` against a payload and a spring, solved with the Lambert W.
* :func:`wedge_damper`: a muscle with a quadratic (datasheet) force map whose payload carriage
  runs in a *friction wedge* (Friedman type): the wedge's control spring is compressed by the
  stroke, so the Coulomb limit grows with the stroke (a loop that widens towards the top), with
  presliding stiffness before the wedge slips.
* :func:`pinched_sliplock`: a braid with *slip-lock pinching* (three generalised plays whose
  radius grows with the normal force, i.e. the pressure, but collapses in a band where the
  bladder's folds unfold and the fibres lose contact), read through a logistic stroke map.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.special import lambertw

from bench.plants.blind6_rig import draw_rig, spool_valve

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array: ...


def _width(width: Array | None, like: Array) -> list[float]:
    return (np.ones_like(like) if width is None else np.asarray(width, dtype=np.float64)).tolist()


# ---- pleated muscle with Berg friction -----------------------------------------------------------


def berg_friction(pressure: Array, p: dict[str, float], width: Array | None = None) -> Array:
    """Friction [bar] of Berg's model driven by ``pressure``: from the last reversal ``(x_s,
    f_s)`` it goes as ``f_s + d (f_max - f_s) / (x2 (1 - a) + d)`` (``a = f_s / f_max``, ``d``
    the distance travelled since, mirrored on the way down), ``f_max`` scaled by ``width``."""
    fmax0, x2 = p["berg_fmax_bar"], p["berg_x2_bar"]
    out = np.empty_like(pressure)
    xs, fs, direction, prev = float(pressure[0]), 0.0, 1.0, float(pressure[0])
    for i, (x, w) in enumerate(zip(pressure.tolist(), _width(width, pressure))):
        fmax = fmax0 * w
        step = x - prev
        if step * direction < 0.0:  # a reversal: the branch starts again from here
            xs, fs, direction = prev, out[i - 1], -direction
        d = abs(x - xs)
        a = min(max(fs / fmax, -1.0), 1.0)
        if direction > 0.0:
            f = fs + d * (fmax - fs) / (x2 * (1.0 - a) + d + 1e-12)
        else:
            f = fs - d * (fmax + fs) / (x2 * (1.0 + a) + d + 1e-12)
        out[i] = f
        prev = x
    return out


def pleated_contraction(pressure: Array, p: dict[str, float]) -> Array:
    """Contraction [mm]: ``p A (c0 / (e + c1) - 1) = W + k L0 e`` is a quadratic in ``e`` (closed
    form, the stable root); 0 where the muscle cannot lift the payload."""
    pa = BAR_N_MM2 * p["area_mm2"] * np.clip(pressure, 0.0, None)
    kl, w, c0, c1 = p["k_spring_n_mm"] * p["l0_mm"], p["weight_n"], p["c0"], p["c1"]
    b = w + pa + kl * c1
    c = (w + pa) * c1 - pa * c0
    e = 2.0 * -c / (b + np.sqrt(b * b - 4.0 * kl * c))
    return np.asarray(np.clip(p["l0_mm"] * e, 0.0, None), dtype=np.float64)


def pleated_berg(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Contraction [mm] of the pleated muscle at the pressure less Berg's friction, which fades
    in with the pressure (``v / (v + 0.15)``: the rubber is not pressed onto the braid vented)."""
    pressure = spool_valve(u, dt_s, p)
    v = np.clip(pressure / p["peak"], 0.0, None)
    return pleated_contraction(pressure - berg_friction(pressure, p, width) * v / (v + 0.15), p)


# ---- Rayleigh-law braid on an exponential muscle -------------------------------------------------


def rayleigh_pressure(pressure: Array, p: dict[str, float], width: Array | None = None) -> Array:
    """Effective pressure [bar] of a Rayleigh law in ``pressure``: each branch ``y_r +- (a d + b
    d^2 / 2)`` from its reversal ``(x_r, y_r)`` (``d`` the distance from it, ``b`` scaled by
    ``width``, ``a + b / 2 = 1`` per peak), reversals kept on a stack and wiped out in pairs."""
    peak = p["peak"]
    v = (np.clip(pressure, 0.0, None) / peak).tolist()
    b0 = p["rayleigh_b"]
    stack: list[tuple[float, float]] = [(v[0], v[0])]
    direction, prev, y = 1.0, v[0], v[0]
    out = np.empty(len(v))
    for i, (x, w) in enumerate(zip(v, _width(width, pressure))):
        b = b0 * w
        a = 1.0 - 0.5 * b
        step = x - prev
        if step * direction < 0.0:
            stack.append((prev, y))
            direction = -direction
        while len(stack) >= 3 and (x - stack[-2][0]) * direction >= 0.0:
            del stack[-2:]
        xr, yr = stack[-1]
        d = abs(x - xr)
        y = yr + direction * (a * d + 0.5 * b * d * d)
        out[i] = y
        prev = x
    return np.asarray(peak * out, dtype=np.float64)


def exponential_contraction(pressure: Array, p: dict[str, float]) -> Array:
    """Contraction [mm]: ``p A e^(-x / x0) = W + k x`` gives ``x = x0 W0(z) - W / k`` with ``z =
    p A e^(W / (k x0)) / (k x0)`` (Lambert W, principal branch); 0 while it cannot lift ``W``."""
    pa = BAR_N_MM2 * p["area_mm2"] * np.clip(pressure, 0.0, None)
    k, x0, w = p["k_spring_n_mm"], p["x0_mm"], p["weight_n"]
    z = pa * math.exp(w / (k * x0)) / (k * x0)
    x = x0 * np.real(lambertw(z)) - w / k
    return np.asarray(np.clip(x, 0.0, None), dtype=np.float64)


def rayleigh_lambert(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Contraction [mm] of the exponential muscle at the Rayleigh law's effective pressure."""
    return exponential_contraction(rayleigh_pressure(spool_valve(u, dt_s, p), p, width), p)


# ---- quadratic muscle in a friction wedge --------------------------------------------------------


def quadratic_statics(pressure: float, friction_n: float, p: dict[str, float]) -> float:
    """Contraction [mm] where ``p A (1 - (1 + beta) x / xm + beta x^2 / xm^2) = W + k x + f``
    (the stable root, in the form that holds at ``p = 0`` too); 0 below lift-off."""
    pa = BAR_N_MM2 * p["area_mm2"] * max(pressure, 0.0)
    xm, beta = p["xmax_mm"], p["beta"]
    qa = pa * beta / (xm * xm)
    qb = pa * (1.0 + beta) / xm + p["k_spring_n_mm"]
    qc = pa - p["weight_n"] - friction_n
    if qc <= 0.0:
        return 0.0
    return 2.0 * qc / (qb + math.sqrt(max(qb * qb - 4.0 * qa * qc, 0.0)))


def wedge_damper(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Contraction [mm]: the wedge's friction force ``f`` [N] sticks with presliding stiffness
    ``k_pre`` and slips at ``+-mu (F_pre + k_w x)`` (times ``width``); per sample the stick step
    is solved linearised (the muscle's stiffness at the last state), the slip step exactly."""
    pressure = spool_valve(u, dt_s, p).tolist()
    mu, f_pre, k_w, k_pre = p["wedge_mu"], p["wedge_preload_n"], p["wedge_k_n_mm"], p["k_pre_n_mm"]
    xm, beta, pa_per_bar = p["xmax_mm"], p["beta"], BAR_N_MM2 * p["area_mm2"]
    f, x = 0.0, quadratic_statics(pressure[0], 0.0, p)
    out = np.empty(len(pressure))
    for i, (pr, w) in enumerate(zip(pressure, _width(width, np.asarray(pressure)))):
        stiff = pa_per_bar * max(pr, 0.0) * ((1.0 + beta) / xm - 2.0 * beta * x / (xm * xm)) + p["k_spring_n_mm"]
        free = quadratic_statics(pr, f, p)
        x_new = (stiff * free + k_pre * x) / (stiff + k_pre) if free > 0.0 else 0.0
        f_new = f + k_pre * (x_new - x)
        limit = w * mu * (f_pre + k_w * x)
        if abs(f_new) > limit:
            f_new = math.copysign(limit, f_new)
            x_new = quadratic_statics(pr, f_new, p)
        f, x = f_new, x_new
        out[i] = x
    return out


# ---- pinched slip-lock braid ---------------------------------------------------------------------

PINCH_RADII = (0.5, 1.0, 1.6)  # times radius_share


def pinch_radius(v: Array, p: dict[str, float]) -> Array:
    """Play radius [share of peak]: growing with the normal force ``v / (v + v_c)``, collapsing
    by ``pinch`` in a Gaussian band around ``v_pinch``."""
    grow = v / (v + p["v_contact"])
    band = 1.0 - p["pinch"] * np.exp(-(((v - p["v_pinch"]) / p["pinch_band"]) ** 2))
    return np.asarray(p["radius_share"] * grow * band, dtype=np.float64)


def pinched_sliplock(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Stroke [mm] ``S (g(z) - g(0)) / (g(1) - g(0))``, ``g`` the logistic ``1 / (1 + e^(-(z -
    z_m) / s))``, ``z = w0 v + sum_j w_j play_j(v)`` with generalised plays of radius
    ``k_j r(v)`` (:func:`pinch_radius`, times ``width``)."""
    v = np.clip(spool_valve(u, dt_s, p) / p["peak"], 0.0, None)
    radius = pinch_radius(v, p).tolist()
    weights = [p[f"w{j}"] for j in range(1, 4)]
    plays = [float(v[0])] * 3
    z = np.empty_like(v)
    for i, (vi, r, w) in enumerate(zip(v.tolist(), radius, _width(width, v))):
        total = p["w0"] * vi
        for j in range(3):
            rj = PINCH_RADII[j] * r * w
            plays[j] = min(max(plays[j], vi - rj), vi + rj)
            total += weights[j] * plays[j]
        z[i] = total
    zm, s = p["z_mid"], p["z_scale"]

    def g(x: Array | float) -> Array:
        return np.asarray(1.0 / (1.0 + np.exp(-(np.asarray(x) - zm) / s)), dtype=np.float64)

    return np.asarray(p["stroke_mm"] * (g(z) - g(0.0)) / (g(1.0) - g(0.0)), dtype=np.float64)


BLIND6_CORES: dict[str, Core] = {
    "pleated_berg": pleated_berg,
    "rayleigh_lambert": rayleigh_lambert,
    "wedge_damper": wedge_damper,
    "pinched_sliplock": pinched_sliplock,
}


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~14-36 mm, a
    loop 3-20 % of the stroke wide), its rig's constants included; ``k_load_n_mm`` is the
    stiffness [N/mm] the payload meets at the muscle's end."""
    stroke = float(rng.uniform(14.0, 36.0))
    g = draw_rig(rng, peak)
    if core == "pleated_berg":
        l0, c1, emax = rng.uniform(90.0, 160.0), rng.uniform(0.05, 0.1), rng.uniform(0.3, 0.42)
        stroke = min(stroke, 0.75 * emax * l0)
        c0, area = emax + c1, rng.uniform(400.0, 1200.0)
        top = BAR_N_MM2 * area * peak * (c0 / (stroke / l0 + c1) - 1.0)
        weight = rng.uniform(0.05, 0.15) * top
        k = (top - weight) / stroke
        g.update(l0_mm=l0, c0=c0, c1=c1, area_mm2=area, weight_n=weight, k_spring_n_mm=k, k_load_n_mm=k)
        g.update(berg_fmax_bar=rng.uniform(0.03, 0.06) * peak, berg_x2_bar=rng.uniform(0.04, 0.12) * peak)
        return g
    if core == "rayleigh_lambert":
        x0, area = rng.uniform(0.8, 1.6) * stroke, rng.uniform(300.0, 900.0)
        top = BAR_N_MM2 * area * peak * math.exp(-stroke / x0)
        weight = rng.uniform(0.05, 0.2) * top
        k = (top - weight) / stroke
        g.update(x0_mm=x0, area_mm2=area, weight_n=weight, k_spring_n_mm=k, k_load_n_mm=k)
        g.update(rayleigh_b=rng.uniform(0.2, 0.5))
        return g
    if core == "wedge_damper":
        xm, beta, area = stroke / rng.uniform(0.55, 0.75), rng.uniform(0.2, 0.5), rng.uniform(400.0, 1000.0)
        s = stroke / xm
        top = BAR_N_MM2 * area * peak * (1.0 - (1.0 + beta) * s + beta * s * s)
        weight = rng.uniform(0.05, 0.15) * top
        k = (top - weight) / stroke
        force_top = weight + k * stroke
        mu = rng.uniform(0.15, 0.3)
        k_w = rng.uniform(0.04, 0.1) * force_top / (mu * stroke)
        g.update(xmax_mm=xm, beta=beta, area_mm2=area, weight_n=weight, k_spring_n_mm=k, k_load_n_mm=k)
        g.update(wedge_mu=mu, wedge_k_n_mm=k_w, wedge_preload_n=rng.uniform(0.005, 0.02) * force_top / mu)
        g.update(k_pre_n_mm=rng.uniform(2.0, 5.0) * k)
        return g
    if core == "pinched_sliplock":
        w = rng.dirichlet(np.full(3, 2.0)) * (1.0 - rng.uniform(0.25, 0.45))
        g.update(w0=1.0 - float(w.sum()), **{f"w{j + 1}": float(w[j]) for j in range(3)})
        g.update(stroke_mm=stroke, radius_share=rng.uniform(0.06, 0.11), v_contact=rng.uniform(0.1, 0.3))
        g.update(pinch=rng.uniform(0.5, 0.8), v_pinch=rng.uniform(0.35, 0.6), pinch_band=rng.uniform(0.08, 0.15))
        g.update(z_mid=rng.uniform(0.3, 0.5), z_scale=rng.uniform(0.2, 0.35), k_load_n_mm=rng.uniform(2.0, 7.0))
        return g
    raise KeyError(f"unknown blind6 core {core!r}; known: {', '.join(BLIND6_CORES)}")
