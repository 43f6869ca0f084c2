"""Four hysteresis cores for the ninth (blind7) plant family, structurally unlike the other thirty-two.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params) -> y``, through the valve and the hose
(:func:`bench.plants.blind7_rig.muscle_pressure`). The rest of the rig (PWM ripple in the
recorded input, channel skew, popcorn noise) is added by :mod:`bench.plants.blind7_rig`; every
effect (:mod:`bench.plants.blind7_effects`) acts on the contraction after the core.

* :func:`ising_crossings`: the braid's fibre crossings as a *random-field Ising chain* (Sethna's
  zero-temperature RFIM on a ring of 96 crossings): each crossing is locked or released, feels
  its own random threshold (the local fibre tension) and its two neighbours along the helix (a
  locked neighbour helps it lock: ferromagnetic coupling), so crossings release in avalanches and
  the memory is the lattice's configuration (return-point memory from no-passing, not a sum of
  independent relays). Crossings lock as the pressure presses the fibres together and release
  as it falls; a share ``rho`` of the pressure acts through the crossings, so only the locked
  share of it reaches the stroke. The force map is *exponential-linear*, ``F = p A ((1 + a)
  e^(-x / x0) - a)`` (a reduced form of Sarosi's law for Festo muscles, eq. 15 of Ai et al. 2019
  in the seeds, with its ``a = c = e = 0``), against a payload and a spring, solved by bisection.
* :func:`detent_carriage`: the payload carriage runs on a *cogged* rail (a periodic detent
  potential of 0.15-0.4 mm pitch: a Prandtl-Tomlinson slider): the muscle (a cubic datasheet
  force map) and the return spring pull it through the detents, it sits in a local minimum of
  the energy and jumps to the next one when that minimum vanishes. The memory is which well it
  sits in (multistability), the loop made of stick-slip jumps.
* :func:`endochronic_sleeve`: the textile sleeve's friction as a *Valanis endochronic* element:
  a hereditary integral over the intrinsic time (the path length of the pressure) with a
  power-law kernel (a Prony series of six terms), a *fading* memory of the whole path, not of
  reversal points; on a *hyperbolic* force map ``F = p A (xm - x) / (xm + b x)`` (closed form).
* :func:`twist_bearing`: an unbalanced braid twists its end cap as it contracts; the cap turns
  in a thrust bearing whose Coulomb torque grows with the axial tension, so the cap's angle lags
  the free twist (a play in a hidden coordinate, its radius set by the stroke) and the braid's
  twist-extension coupling shortens the stroke while the cap is held; on an exponential-saturation
  stroke map (a datasheet fit ``S (1 - e^(-(v - v_th) / v0))``).
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind7_rig import draw_rig, muscle_pressure

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2
CROSSINGS = 96
PRONY_TERMS = 6
FIELD_MARGIN = 2.0


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float]) -> Array: ...


# ---- random-field Ising chain of braid crossings -------------------------------------------------


def ising_locked_share(v: Array, p: dict[str, float]) -> Array:
    """Share of locked crossings (0..1) for the normalised pressure ``v`` [0..1]: a ring of
    :data:`CROSSINGS` spins ``s_i = +-1`` with random fields ``h_i ~ N(0, 1)`` (seeded by
    ``ising_seed``), coupling ``coupling`` to both neighbours and the field ``H = G (v - 1/2)``;
    zero-temperature single-flip dynamics (every unstable spin flips until none is), all released
    at the start. Between flips nothing is computed: the field only has to leave the band where
    no spin is unstable."""
    rng = np.random.default_rng(int(p["ising_seed"]))
    h = rng.normal(0.0, 1.0, CROSSINGS)
    coupling, gain = p["coupling"], p["field_gain"]
    s = -np.ones(CROSSINGS)

    def band(spins: Array) -> tuple[float, float]:
        flip_at = -h - coupling * (np.roll(spins, 1) + np.roll(spins, -1))
        up = flip_at[spins < 0.0]
        down = flip_at[spins > 0.0]
        return (float(down.max()) if down.size else -math.inf, float(up.min()) if up.size else math.inf)

    low, high = band(s)
    share = 0.0
    out = np.empty(v.size)
    for i, field in enumerate((gain * (v - 0.5)).tolist()):
        if not low <= field < high:
            while True:
                local = h + field + coupling * (np.roll(s, 1) + np.roll(s, -1))
                flips = ((s < 0.0) & (local > 0.0)) | ((s > 0.0) & (local < 0.0))
                if not flips.any():
                    break
                s[flips] = -s[flips]
            low, high = band(s)
            share = 0.5 * (float(s.mean()) + 1.0)
        out[i] = share
    return out


def exponential_linear_contraction(pressure: Array, p: dict[str, float]) -> Array:
    """Contraction [mm] where ``p A ((1 + a) e^(-x / x0) - a) = W + k x`` (bisection; the force
    falls and the load rises with ``x``, so the root is unique); 0 below lift-off."""
    pa = BAR_N_MM2 * p["area_mm2"] * np.clip(pressure, 0.0, None)
    a, x0, w, k = p["sarosi_a"], p["x0_mm"], p["weight_n"], p["k_spring_n_mm"]
    lo = np.zeros_like(pa)
    hi = np.full_like(pa, x0 * math.log((1.0 + a) / a))
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        excess = pa * ((1.0 + a) * np.exp(-mid / x0) - a) - w - k * mid
        lo, hi = np.where(excess > 0.0, mid, lo), np.where(excess > 0.0, hi, mid)
    return np.asarray(0.5 * (lo + hi), dtype=np.float64)


def ising_crossings(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm] at the effective pressure ``peak ((1 - rho) v + rho L)``, ``L`` the
    locked share (:func:`ising_locked_share`), ``rho`` = ``locked_weight``."""
    v = np.clip(muscle_pressure(u, dt_s, p) / p["peak"], 0.0, None)
    rho = p["locked_weight"]
    effective = (1.0 - rho) * v + rho * ising_locked_share(v, p)
    return exponential_linear_contraction(p["peak"] * effective, p)


# ---- Prandtl-Tomlinson carriage on a cogged rail -------------------------------------------------


def detent_carriage(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm]: the carriage rests where ``g(y) = p A (1 - c1 s - c3 s^3) - W - k y -
    F_d sin(2 pi y / lambda) = 0`` (``s = y / xm``), in the well it sat in: from the last
    position it moves the way ``g`` pushes, in steps of ``lambda / 8``, to the first sign change
    of ``g`` (the nearest stable rest), then bisects; it stops at 0 (the carriage's stop)."""
    pressure = muscle_pressure(u, dt_s, p)
    pa_list = (BAR_N_MM2 * p["area_mm2"] * np.clip(pressure, 0.0, None)).tolist()
    xm, c1, c3, w, k = p["xmax_mm"], p["c1"], p["c3"], p["weight_n"], p["k_spring_n_mm"]
    fd, wave, pitch = p["detent_n"], 2.0 * math.pi / p["pitch_mm"], p["pitch_mm"]
    step = pitch / 8.0

    def g(y: float, pa: float) -> float:
        s = y / xm
        return pa * (1.0 - c1 * s - c3 * s * s * s) - w - k * y - fd * math.sin(wave * y)

    y = 0.0
    out = np.empty(len(pa_list))
    for i, pa in enumerate(pa_list):
        g0 = g(y, pa)
        if g0 != 0.0:
            d = 1.0 if g0 > 0.0 else -1.0
            y0 = y
            while True:
                y1 = y0 + d * step
                if y1 <= 0.0:
                    if g(0.0, pa) <= 0.0:
                        y0 = y1 = 0.0
                        break
                    y1 = 0.0
                g1 = g(y1, pa)
                if g1 * d <= 0.0:
                    break
                y0 = y1
            a, b = (y0, y1) if y0 < y1 else (y1, y0)
            if a != b:
                ga = g(a, pa)
                for _ in range(14):
                    mid = 0.5 * (a + b)
                    gm = g(mid, pa)
                    if (gm > 0.0) == (ga > 0.0):
                        a, ga = mid, gm
                    else:
                        b = mid
            y = max(0.5 * (a + b), 0.0)
        out[i] = y
    return out


# ---- Valanis endochronic sleeve ------------------------------------------------------------------


def endochronic_friction(v: Array, p: dict[str, float]) -> Array:
    """Friction [share of peak pressure]: ``sum_j sigma_j``, each ``d sigma_j = a_j sign(dv)
    |dv| / zeta_j - sigma_j |dv| / zeta_j`` over the intrinsic time ``z = int |dv|`` (exact per
    step: rate-independent), ``zeta_j`` log-spaced from 0.004 to 0.4, ``a_j ~ zeta_j^(1 -
    alpha)`` summing to ``friction_share`` (a power-law kernel ``~ z^(-alpha)``)."""
    zeta = np.geomspace(0.004, 0.4, PRONY_TERMS)
    level = zeta ** (1.0 - p["kernel_alpha"])
    level = (p["friction_share"] * level / level.sum()).tolist()
    inv = (1.0 / zeta).tolist()
    sigma = [0.0] * PRONY_TERMS
    out = np.empty(v.size)
    prev = float(v[0])
    for i, vi in enumerate(v.tolist()):
        dv = vi - prev
        if dv != 0.0:
            sign, dz = (1.0 if dv > 0.0 else -1.0), abs(dv)
            for j in range(PRONY_TERMS):
                keep = math.exp(-dz * inv[j])
                sigma[j] = sigma[j] * keep + sign * level[j] * (1.0 - keep)
        out[i] = sum(sigma)
        prev = vi
    return out


def hyperbolic_contraction(pressure: Array, p: dict[str, float]) -> Array:
    """Contraction [mm] where ``P (xm - x) / (xm + b x) = W + k x`` (``P = p A``): the stable
    root of ``k b x^2 + (k xm + W b + P) x + (W - P) xm = 0``; 0 below lift-off."""
    pa = BAR_N_MM2 * p["area_mm2"] * np.clip(pressure, 0.0, None)
    xm, b, w, k = p["xmax_mm"], p["hyper_b"], p["weight_n"], p["k_spring_n_mm"]
    qb = k * xm + w * b + pa
    qc = (w - pa) * xm
    x = 2.0 * -qc / (qb + np.sqrt(qb * qb - 4.0 * k * b * qc))
    return np.asarray(np.clip(x, 0.0, None), dtype=np.float64)


def endochronic_sleeve(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm] at the pressure less the sleeve's endochronic friction."""
    pressure = muscle_pressure(u, dt_s, p)
    v = np.clip(pressure / p["peak"], 0.0, None)
    return hyperbolic_contraction(p["peak"] * np.clip(v - endochronic_friction(v, p), 0.0, None), p)


# ---- twist-coupled braid in a thrust bearing ------------------------------------------------------


def saturating_stroke(v: Array, p: dict[str, float]) -> Array:
    """Stroke [mm] of the datasheet fit ``S (1 - e^(-(v - v_th)+ / v0)) / (1 - e^(-(1 - v_th) / v0))``."""
    v_th, v0 = p["v_threshold"], p["v_scale"]
    norm = 1.0 - math.exp(-(1.0 - v_th) / v0)
    return np.asarray(p["stroke_mm"] * (1.0 - np.exp(-np.clip(v - v_th, 0.0, None) / v0)) / norm, dtype=np.float64)


def twist_bearing(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm] ``x_s(v) - S c (v - phi)``: the cap's angle ``phi`` (in units of the free
    twist, which is ``v``) stays while ``|v - phi|`` is below the bearing's radius ``r0 (0.25 +
    0.75 x_s / S)`` and is dragged along at it otherwise; never below 0."""
    v = np.clip(muscle_pressure(u, dt_s, p) / p["peak"], 0.0, None)
    free = saturating_stroke(v, p)
    stroke, r0 = p["stroke_mm"], p["bearing_radius"]
    radius = (r0 * (0.25 + 0.75 * free / stroke)).tolist()
    phi = float(v[0])
    angle = np.empty(v.size)
    for i, (vi, r) in enumerate(zip(v.tolist(), radius)):
        phi = min(max(phi, vi - r), vi + r)
        angle[i] = phi
    return np.asarray(np.clip(free - stroke * p["twist_coupling"] * (v - angle), 0.0, None), dtype=np.float64)


BLIND7_CORES: dict[str, Core] = {
    "ising_crossings": ising_crossings,
    "detent_carriage": detent_carriage,
    "endochronic_sleeve": endochronic_sleeve,
    "twist_bearing": twist_bearing,
}


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~14-36 mm, a
    loop 3-20 % of the stroke wide), its rig's constants included; ``k_total_n_mm`` is the
    stiffness [N/mm] the payload meets at the muscle's end (for the load forms)."""
    stroke = float(rng.uniform(14.0, 36.0))
    g = draw_rig(rng, peak)
    if core == "ising_crossings":
        a, x0, area = rng.uniform(0.1, 0.3), rng.uniform(0.9, 1.5) * stroke, rng.uniform(300.0, 900.0)
        top = BAR_N_MM2 * area * peak * ((1.0 + a) * math.exp(-stroke / x0) - a)
        weight = rng.uniform(0.05, 0.15) * top
        k = (top - weight) / stroke
        coupling = rng.uniform(0.5, 0.9)
        g.update(sarosi_a=a, x0_mm=x0, area_mm2=area, weight_n=weight, k_spring_n_mm=k, k_total_n_mm=2.0 * k)
        g.update(
            coupling=coupling, field_gain=2.0 * (2.0 * coupling + FIELD_MARGIN), locked_weight=rng.uniform(0.15, 0.3)
        )
        g.update(ising_seed=float(rng.integers(0, 2**31)))
        return g
    if core == "detent_carriage":
        xm, c1, c3, area = stroke / rng.uniform(0.55, 0.75), rng.uniform(0.5, 0.9), rng.uniform(0.1, 0.4), 0.0
        area = rng.uniform(400.0, 1000.0)
        s = stroke / xm
        top = BAR_N_MM2 * area * peak * (1.0 - c1 * s - c3 * s**3)
        weight = rng.uniform(0.05, 0.15) * top
        k = (top - weight) / stroke
        g.update(xmax_mm=xm, c1=c1, c3=c3, area_mm2=area, weight_n=weight, k_spring_n_mm=k, k_total_n_mm=2.0 * k)
        g.update(detent_n=rng.uniform(0.03, 0.06) * top, pitch_mm=rng.uniform(0.15, 0.4))
        return g
    if core == "endochronic_sleeve":
        xm, b, area = stroke / rng.uniform(0.5, 0.7), rng.uniform(0.5, 2.0), rng.uniform(400.0, 1000.0)
        top = BAR_N_MM2 * area * peak * (xm - stroke) / (xm + b * stroke)
        weight = rng.uniform(0.05, 0.15) * top
        k = (top - weight) / stroke
        g.update(xmax_mm=xm, hyper_b=b, area_mm2=area, weight_n=weight, k_spring_n_mm=k, k_total_n_mm=2.0 * k)
        g.update(friction_share=rng.uniform(0.04, 0.08), kernel_alpha=rng.uniform(0.3, 0.7))
        return g
    if core == "twist_bearing":
        g.update(stroke_mm=stroke, v_threshold=rng.uniform(0.03, 0.1), v_scale=rng.uniform(0.3, 0.8))
        g.update(bearing_radius=rng.uniform(0.06, 0.12), twist_coupling=rng.uniform(0.3, 0.6))
        g.update(k_total_n_mm=rng.uniform(2.0, 7.0))
        return g
    raise KeyError(f"unknown blind7 core {core!r}; known: {', '.join(BLIND7_CORES)}")
