"""Four hysteresis cores for the tenth (blind8) plant family, structurally unlike the other thirty-six.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params) -> y``, through the valve (:func:`bench.plants.blind8_rig.muscle_pressure`).
The rest of the rig (flow noise at the transducer's port, the SAR converter's bit errors,
auto-zero steps, anti-alias filters) is added by :mod:`bench.plants.blind8_rig`; every effect
(:mod:`bench.plants.blind8_effects`) acts on the contraction after the core.

* :func:`crystallising_bladder`: a natural-rubber bladder that *crystallises under strain*: as
  its hoop stretch grows the stretched chains crystallise (above an onset), and the crystallites
  melt again only at a lower stretch; the crystallised share relieves the bladder's elastic
  resistance. The crystallinity follows *Ivshin-Pence* phase kinetics (two boundary curves, the
  state scaled between them from the last reversal: a one-reversal memory, not return-point
  memory). The bladder's resistance is the inflation pressure of its Mooney-Rivlin bulges
  between the fibres; the braid is Chou-Hannaford's (closed form).
* :func:`bounding_surface_braid`: the braid's inter-fibre friction as *Dafalias-Popov
  bounding-surface plasticity* in pressure: after every reversal the friction moves elastically
  at first and bends towards a bound (which grows with the normal force, i.e. the pressure)
  with a plastic modulus ``h delta / (delta_in - delta)`` set by the distance to the bound at the
  reversal. The force map is a manufacturer's *datasheet chart* (force against contraction at
  six pressures, read off with a digitising error) interpolated monotonically (PCHIP in the
  contraction, linear in the pressure).
* :func:`mindlin_crossings`: the braid's fibre crossings as Hertzian contacts in *Cattaneo-Mindlin
  partial slip*: an Iwan set of Jenkins elements whose slip thresholds reproduce Mindlin's
  ``1 - (1 - delta / delta*)^(3/2)`` backbone; the normal force grows with the pressure, so the
  slip force grows as ``N`` and the slip distance as ``N^(2/3)`` (elements slip when the pressure
  falls while they are loaded). On a *thick-walled* Chou-Hannaford map (Tsagarakis-Caldwell).
* :func:`fancher_leaf_spring`: the return spring is a *multi-leaf* spring whose interleaf
  friction is a share of the spring's force (Fancher's envelope model: after a reversal the
  force moves from one envelope, ``K x (1 - c)``, to the other, ``K x (1 + c)``, exponentially in
  the distance travelled), on an *arctangent* datasheet stroke map.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import PchipInterpolator

from bench.plants.blind8_rig import draw_rig, muscle_pressure

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2
TABLE_POINTS = 1201
IWAN_ELEMENTS = 10
CHART_PRESSURES = 6


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float]) -> Array: ...


def braid_contraction(pa: Array, p: dict[str, float], deduct_mm2: float = 0.0) -> Array:
    """Contraction [mm] of a Chou-Hannaford braid, ``pressure (A0 (a (1 - e)^2 - b) - A_t) = W + k
    L0 e`` (``pa`` = pressure x A0 [N], ``A_t`` = ``deduct_mm2``, the thick wall's loss): the
    smaller root of the quadratic in ``e``; 0 below lift-off."""
    a, b, w, kl = p["braid_a"], p["braid_b"], p["weight_n"], p["k_spring_n_mm"] * p["length_mm"]
    pa = np.clip(pa, 1e-9, None)
    loss = pa * (b + deduct_mm2 / p["area_mm2"])
    qa, qb, qc = pa * a, 2.0 * pa * a + kl, pa * a - loss - w
    e = (qb - np.sqrt(np.clip(qb * qb - 4.0 * qa * qc, 0.0, None))) / (2.0 * qa)
    return np.asarray(np.clip(e, 0.0, None) * p["length_mm"], dtype=np.float64)


def _braid_force(pressure: float, e: float, p: dict[str, float], deduct_mm2: float = 0.0) -> float:
    return BAR_N_MM2 * pressure * (p["area_mm2"] * (p["braid_a"] * (1.0 - e) ** 2 - p["braid_b"]) - deduct_mm2)


def _tabulated(stroke_at: Array, v: Array) -> Array:
    """``stroke_at`` (on :data:`TABLE_POINTS` effective pressures 0..1.2 peak) read at ``v``."""
    grid = np.linspace(0.0, 1.2, TABLE_POINTS)
    return np.asarray(np.interp(v, grid, stroke_at), dtype=np.float64)


# ---- strain-crystallising natural-rubber bladder (Ivshin-Pence kinetics) -------------------------


def mooney_rivlin_resistance(v: Array, p: dict[str, float]) -> Array:
    """The bladder's resistance [share of peak]: the inflation pressure of its bulges between
    the braid's fibres (spherical caps of a Mooney-Rivlin membrane, ``(1 / l - 1 / l^7)(1 +
    beta l^2)``) at the stretch ``l = 1 + s v``, as a share of its value at ``v = 1``, times
    ``bladder_share``."""
    s, beta = p["hoop_stretch"], p["mr_beta"]

    def mr(lam: Array) -> Array:
        return np.asarray((1.0 / lam - lam**-7) * (1.0 + beta * lam * lam), dtype=np.float64)

    top = mr(np.array([1.0 + s]))[0]
    return np.asarray(p["bladder_share"] * mr(1.0 + s * np.clip(v, 0.0, None)) / top, dtype=np.float64)


def ivshin_pence_crystallinity(v: Array, p: dict[str, float]) -> Array:
    """Crystallised share (0..1) of the bladder at the normalised pressure ``v``: crystallising
    boundary ``C(v) = logistic((v - v_c) / w)``, melting boundary ``M(v) = logistic((v - v_m) /
    w)`` (``v_m < v_c``); rising from a reversal ``(v_r, X_r)``: ``X = 1 - (1 - X_r)(1 - C(v)) /
    (1 - C(v_r))``; falling: ``X = X_r M(v) / M(v_r)``. Amorphous at the start."""
    vc, vm, w = p["crystal_onset"], p["melt_onset"], p["crystal_width"]

    def c(x: float) -> float:
        return 1.0 / (1.0 + math.exp(-(x - vc) / w))

    def m(x: float) -> float:
        return 1.0 / (1.0 + math.exp(-(x - vm) / w))

    out = np.empty(v.size)
    prev = float(v[0])
    rising = True
    xr, vr = 0.0, prev
    x = 0.0
    for i, vi in enumerate(v.tolist()):
        if vi != prev:
            up = vi > prev
            if up != rising:
                rising, xr, vr = up, x, prev
            if rising:
                x = 1.0 - (1.0 - xr) * (1.0 - c(vi)) / max(1.0 - c(vr), 1e-12)
            else:
                x = xr * m(vi) / max(m(vr), 1e-12)
            x = min(max(x, 0.0), 1.0)
        out[i] = x
        prev = vi
    return out


def crystallising_bladder(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm] at the effective pressure ``peak (v - R(v) (1 - r X))``: the bladder's
    Mooney-Rivlin resistance ``R`` relieved by the crystallised share ``X`` (``r`` =
    ``crystal_relief``)."""
    v = np.clip(muscle_pressure(u, dt_s, p) / p["peak"], 0.0, None)
    relief = 1.0 - p["crystal_relief"] * ivshin_pence_crystallinity(v, p)
    effective = np.clip(v - mooney_rivlin_resistance(v, p) * relief, 0.0, None)
    return braid_contraction(BAR_N_MM2 * p["area_mm2"] * p["peak"] * effective, p)


# ---- Dafalias-Popov bounding-surface braid on a datasheet chart ----------------------------------


def dafalias_popov_friction(v: Array, p: dict[str, float]) -> Array:
    """Friction [share of peak] ``s_b (0.15 + 0.85 v) z``: the bound grows with the normal force
    (the pressure) and ``z`` (-1..1) follows ``d z = E_t d v``, ``E_t = E H / (E + H)``, ``H = h
    delta / (delta_in - delta)``, ``delta = 1 - sign(dv) z`` the distance to the bound in the
    direction of travel (``delta_in`` at the last reversal: elastic just after it, bending
    towards the bound as ``delta`` shrinks); sub-stepped so that no step moves ``z`` by more
    than 0.05."""
    e_mod, h, s0 = p["dp_elastic"], p["dp_hardening"], p["dp_bound"]
    out = np.empty(v.size)
    z, prev, direction, delta_in = 0.0, float(v[0]), 0.0, 1.0
    for i, vi in enumerate(v.tolist()):
        dv = vi - prev
        if dv != 0.0:
            d = 1.0 if dv > 0.0 else -1.0
            if d != direction:
                direction, delta_in = d, 1.0 - d * z
            n = max(1, int(math.ceil(abs(dv) * e_mod / 0.05)))
            step = dv / n
            for _ in range(n):
                delta = max(1.0 - d * z, 0.0)
                hh = h * delta / max(delta_in - delta, 1e-12)
                z = min(max(z + e_mod * hh / (e_mod + hh) * step, -1.0), 1.0)
        out[i] = s0 * (0.15 + 0.85 * max(vi, 0.0)) * z
        prev = vi
    return out


def chart_stroke_table(p: dict[str, float]) -> Array:
    """Stroke [mm] against the effective pressure (0..1.2 peak, :data:`TABLE_POINTS` points)
    from the datasheet chart: at the chart's pressures ``F = P A (1 - x / xm)^g - B x / xm``
    read with a digitising error (``chart_seed``) and made monotone, interpolated by PCHIP in
    ``x`` and linearly in the pressure, against ``W + k x`` (bisection)."""
    rng = np.random.default_rng(int(p["chart_seed"]))
    xm, g, area, b = p["xmax_mm"], p["chart_power"], p["area_mm2"], p["chart_bladder_n"]
    xs = np.linspace(0.0, xm, 9)
    levels = np.linspace(0.0, 1.2, CHART_PRESSURES)
    rows = []
    for lv in levels:
        f = BAR_N_MM2 * lv * p["peak"] * area * (1.0 - xs / xm) ** g - b * xs / xm
        f = f * (1.0 + rng.normal(0.0, 0.015, xs.size))
        rows.append(PchipInterpolator(xs, np.minimum.accumulate(f)))
    grid = np.linspace(0.0, 1.2, TABLE_POINTS)
    pos = np.clip(grid / levels[1], 0.0, CHART_PRESSURES - 1.001)
    low, frac = pos.astype(int), pos - pos.astype(int)
    lo, hi = np.zeros_like(grid), np.full_like(grid, xm)
    w, k = p["weight_n"], p["k_spring_n_mm"]
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        vals = np.stack([row(mid) for row in rows])
        force = vals[low, np.arange(grid.size)] * (1.0 - frac) + vals[low + 1, np.arange(grid.size)] * frac
        excess = force - w - k * mid
        lo, hi = np.where(excess > 0.0, mid, lo), np.where(excess > 0.0, hi, mid)
    return np.asarray(0.5 * (lo + hi), dtype=np.float64)


def bounding_surface_braid(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm] at the pressure less the braid's bounding-surface friction."""
    v = np.clip(muscle_pressure(u, dt_s, p) / p["peak"], 0.0, None)
    effective = np.clip(v - dafalias_popov_friction(v, p), 0.0, None)
    return _tabulated(chart_stroke_table(p), effective)


# ---- Cattaneo-Mindlin partial slip at the crossings, thick-walled braid ---------------------------


def thick_wall_deduction_mm2(p: dict[str, float]) -> float:
    """The thick wall's loss of area [mm^2]: ``pi (D0 t (1 / sin t0 - 2 sin t0) + t^2)``."""
    s0 = math.sin(p["braid_angle_rad"])
    return math.pi * (p["diameter_mm"] * p["wall_mm"] * (1.0 / s0 - 2.0 * s0) + p["wall_mm"] ** 2)


def mindlin_friction(x0: Array, v: Array, p: dict[str, float]) -> Array:
    """Slip force [mm of stroke] of the Iwan set driven by the frictionless stroke ``x0``: element
    ``i`` slips at ``delta* q_i`` (``q_i = 1 - (1 - u_i)^2``, ``u_i`` the mid-quantiles), all of
    stiffness ``1.5 F / (M delta*)``; ``F = c N`` and ``delta* = d N^(2/3)``, ``N = n0 + v``."""
    q = [1.0 - (1.0 - (j + 0.5) / IWAN_ELEMENTS) ** 2 for j in range(IWAN_ELEMENTS)]
    c, d, n0 = p["slip_force_mm"], p["slip_distance_mm"], p["normal_floor"]
    f = [0.0] * IWAN_ELEMENTS
    out = np.empty(x0.size)
    prev = float(x0[0])
    for i, (xi, vi) in enumerate(zip(x0.tolist(), v.tolist())):
        normal = n0 + max(vi, 0.0)
        force = c * normal
        k = 1.5 * force / (IWAN_ELEMENTS * d * normal ** (2.0 / 3.0))
        dx = xi - prev
        total = 0.0
        for j in range(IWAN_ELEMENTS):
            limit = 1.5 * force * q[j] / IWAN_ELEMENTS
            fj = min(max(f[j] + k * dx, -limit), limit)
            f[j] = fj
            total += fj
        out[i] = total
        prev = xi
    return out


def mindlin_crossings(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm]: the thick-walled braid's stroke less the crossings' slip force."""
    v = np.clip(muscle_pressure(u, dt_s, p) / p["peak"], 0.0, None)
    pa = BAR_N_MM2 * p["area_mm2"] * p["peak"] * np.linspace(0.0, 1.2, TABLE_POINTS)
    x0 = _tabulated(braid_contraction(pa, p, thick_wall_deduction_mm2(p)), v)
    return np.asarray(np.clip(x0 - mindlin_friction(x0, v, p), 0.0, None), dtype=np.float64)


# ---- Fancher multi-leaf return spring on an arctangent stroke map ---------------------------------


def arctan_stroke(v: Array, p: dict[str, float]) -> Array:
    """Stroke [mm] of the datasheet fit ``S atan((v - v_th)+ / v0) / atan((1 - v_th) / v0)``."""
    v_th, v0 = p["v_threshold"], p["v_scale"]
    norm = math.atan((1.0 - v_th) / v0)
    return np.asarray(p["stroke_mm"] * np.arctan(np.clip(v - v_th, 0.0, None) / v0) / norm, dtype=np.float64)


def fancher_envelope_state(x0: Array, beta_mm: float) -> Array:
    """Fancher's state (-1..1): after each move ``dx`` it approaches ``sign(dx)`` by the factor
    ``exp(-|dx| / beta)`` (rate-independent: path length only); 0 at the start."""
    out = np.empty(x0.size)
    state, prev = 0.0, float(x0[0])
    for i, xi in enumerate(x0.tolist()):
        dx = xi - prev
        if dx != 0.0:
            target = 1.0 if dx > 0.0 else -1.0
            state = target + (state - target) * math.exp(-abs(dx) / beta_mm)
        out[i] = state
        prev = xi
    return out


def fancher_leaf_spring(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Contraction [mm] ``x0 - c (x_pre + x0) phi``: the interleaf friction, a share ``c`` of the
    leaf spring's force (preloaded by ``x_pre``), in the direction of travel; never below 0."""
    v = np.clip(muscle_pressure(u, dt_s, p) / p["peak"], 0.0, None)
    x0 = arctan_stroke(v, p)
    phi = fancher_envelope_state(x0, p["fancher_beta_mm"])
    friction = p["leaf_friction"] * (p["leaf_preload_mm"] + x0) * phi
    return np.asarray(np.clip(x0 - friction, 0.0, None), dtype=np.float64)


BLIND8_CORES: dict[str, Core] = {
    "crystallising_bladder": crystallising_bladder,
    "bounding_surface_braid": bounding_surface_braid,
    "mindlin_crossings": mindlin_crossings,
    "fancher_leaf_spring": fancher_leaf_spring,
}


def _draw_braid(rng: np.random.Generator, g: dict[str, float], stroke: float, deduct: bool) -> None:
    """A Chou-Hannaford braid (angle 20-28 deg, 10-16 mm, 150-350 mm) whose spring is set so
    that the stroke at the peak (less the bladder's share ``share``) is ``stroke``."""
    angle = math.radians(float(rng.uniform(20.0, 28.0)))
    d0, length = float(rng.uniform(10.0, 16.0)), float(rng.uniform(150.0, 350.0))
    g.update(braid_angle_rad=angle, diameter_mm=d0, length_mm=length, wall_mm=rng.uniform(0.8, 1.5))
    g.update(braid_a=3.0 / math.tan(angle) ** 2, braid_b=1.0 / math.sin(angle) ** 2, area_mm2=math.pi * d0 * d0 / 4.0)
    e = min(stroke / length, 0.6 * (1.0 - math.sqrt(g["braid_b"] / g["braid_a"])))
    stroke = e * length
    loss = thick_wall_deduction_mm2(g) if deduct else 0.0
    top = _braid_force(g["peak"] * (1.0 - g.get("bladder_share", 0.0)), e, g, loss)
    weight = float(rng.uniform(0.05, 0.15)) * top
    k = (top - weight) / stroke
    g.update(weight_n=weight, k_spring_n_mm=k, k_total_n_mm=2.0 * k)


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~14-36 mm, a
    loop 3-20 % of the stroke wide), its rig's constants included; ``k_total_n_mm`` is the
    stiffness [N/mm] the payload meets at the muscle's end (for the load forms)."""
    stroke = float(rng.uniform(14.0, 36.0))
    g = draw_rig(rng, peak)
    if core == "crystallising_bladder":
        g.update(
            bladder_share=rng.uniform(0.16, 0.26), hoop_stretch=rng.uniform(0.15, 0.3), mr_beta=rng.uniform(0.05, 0.2)
        )
        onset = float(rng.uniform(0.42, 0.58))
        g.update(crystal_onset=onset, melt_onset=onset - rng.uniform(0.18, 0.28), crystal_width=rng.uniform(0.05, 0.09))
        g.update(crystal_relief=rng.uniform(0.5, 0.75))
        _draw_braid(rng, g, stroke, deduct=False)
        return g
    if core == "bounding_surface_braid":
        xm, area = stroke / rng.uniform(0.45, 0.65), rng.uniform(300.0, 800.0)
        g.update(xmax_mm=xm, area_mm2=area, chart_power=rng.uniform(1.2, 2.2), chart_seed=float(rng.integers(0, 2**31)))
        top = BAR_N_MM2 * peak * area * (1.0 - stroke / xm) ** g["chart_power"]
        g.update(chart_bladder_n=rng.uniform(0.05, 0.15) * top)
        top -= g["chart_bladder_n"] * stroke / xm
        weight = float(rng.uniform(0.05, 0.15)) * top
        k = (top - weight) / stroke
        g.update(weight_n=weight, k_spring_n_mm=k, k_total_n_mm=2.0 * k)
        g.update(
            dp_bound=rng.uniform(0.06, 0.09), dp_elastic=rng.uniform(15.0, 40.0), dp_hardening=rng.uniform(2.0, 8.0)
        )
        return g
    if core == "mindlin_crossings":
        _draw_braid(rng, g, stroke, deduct=True)
        g.update(slip_force_mm=rng.uniform(0.025, 0.05) * stroke, slip_distance_mm=rng.uniform(0.04, 0.12) * stroke)
        g.update(normal_floor=rng.uniform(0.05, 0.12))
        return g
    if core == "fancher_leaf_spring":
        g.update(stroke_mm=stroke, v_threshold=rng.uniform(0.04, 0.1), v_scale=rng.uniform(0.3, 0.9))
        g.update(leaf_friction=rng.uniform(0.03, 0.07), leaf_preload_mm=rng.uniform(0.1, 0.3) * stroke)
        g.update(fancher_beta_mm=rng.uniform(0.02, 0.06) * stroke, k_total_n_mm=rng.uniform(2.0, 7.0))
        return g
    raise KeyError(f"unknown blind8 core {core!r}; known: {', '.join(BLIND8_CORES)}")
