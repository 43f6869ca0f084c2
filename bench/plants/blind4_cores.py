"""Four hysteresis cores for the sixth (blind4) plant family, structurally unlike the other twenty.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params, width=None) -> y``, through the valve's lag
(:func:`bench.plants.blind4_rig.valve`); ``width`` is a per-sample factor on the braid's
friction (1: as drawn), through which the lubricant's temperature acts.
The rest of the rig (supply droop, linkage play, mounting plate, transducer errors) is added by
:mod:`bench.plants.blind4_rig`; effects (:mod:`bench.plants.blind4_effects`) act on the pressure
before the core or on the contraction after it.

* :func:`masing_tondu`: the braid's friction as an *extended Masing* hysteresis in pressure
  (a tanh backbone, every branch the backbone doubled about its reversal point, a stack of
  reversal points so that a closed minor loop is forgotten), taking a share of the pressure
  (friction grows with the braid's normal force, so none is left vented) from a Tondu-Lopez
  muscle (braid angle 20-28 deg, end-effect ``k``) against a payload and a spring.
* :func:`tellinen_sleeve`: a sleeve muscle described by its two limiting branches (an
  exponential envelope plus and minus a skewed half-width) and the *Tellinen* rule inside them:
  a branch's slope is the limiting branch's slope times the share of the way still left to it.
* :func:`bliman_sorine`: a Tondu-Lopez muscle whose braid friction is a *Bliman-Sorine*
  second-order friction in path length (rate-independent: after a reversal the friction
  overshoots to a break-away peak, then settles to its Coulomb level) in series with the
  muscle's pressure-dependent stiffness.
* :func:`stoner_crimps`: the braid's crimped cords as an ensemble of *Stoner-Wohlfarth*
  two-well elements (12 easy-axis angles x 4 switching scales): each follows a reversible branch
  of its energy minimum and snaps to the other well at the astroid field, so the stroke steps
  (small Barkhausen-like jumps) on top of a reversible exponential envelope.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind4_rig import draw_rig, valve

Array = NDArray[np.float64]


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array: ...


def _width(width: Array | None, like: Array) -> Array:
    return np.ones_like(like) if width is None else np.asarray(width, dtype=np.float64)


# ---- Tondu-Lopez statics -------------------------------------------------------------------------


def tondu_force(pressure: Array, x: Array, p: dict[str, float]) -> Array:
    """Muscle force [N] at ``pressure`` [bar] and contraction ``x`` [mm] (Tondu-Lopez):
    ``F0 p (a (1 - k x / L0)^2 - b) / (a - b)``, ``a = 3 / tan^2(alpha0)``, ``b = 1 / sin^2(alpha0)``."""
    alpha = math.radians(p["braid_deg"])
    a, b = 3.0 / math.tan(alpha) ** 2, 1.0 / math.sin(alpha) ** 2
    return np.asarray(p["f0_n_bar"] * pressure * (a * (1.0 - p["k_end"] * x / p["l0_mm"]) ** 2 - b) / (a - b))


def tondu_contraction(pressure: Array, p: dict[str, float]) -> Array:
    """Contraction [mm] balancing the muscle force against the payload and the return spring,
    ``F(p, x) = W + k_s x`` (bisection; 0 while the muscle cannot lift the payload)."""
    pr = np.clip(pressure, 0.0, None)
    alpha = math.radians(p["braid_deg"])
    x_max = p["l0_mm"] * (1.0 - math.sqrt((1.0 / math.sin(alpha) ** 2) / (3.0 / math.tan(alpha) ** 2))) / p["k_end"]
    lo, hi = np.zeros_like(pr), np.full_like(pr, x_max)
    for _ in range(36):
        mid = 0.5 * (lo + hi)
        surplus = tondu_force(pr, mid, p) - p["weight_n"] - p["k_spring_n_mm"] * mid
        lo, hi = np.where(surplus > 0.0, mid, lo), np.where(surplus > 0.0, hi, mid)
    return np.asarray(0.5 * (lo + hi), dtype=np.float64)


def _tondu_params(rng: np.random.Generator, peak: float, stroke_mm: float) -> dict[str, float]:
    """A Tondu-Lopez muscle whose spring is chosen so that full pressure contracts it ``stroke_mm``."""
    g = {
        "braid_deg": rng.uniform(20.0, 28.0),
        "k_end": rng.uniform(1.1, 1.4),
        "l0_mm": rng.uniform(180.0, 280.0),
        "f0_n_bar": rng.uniform(180.0, 400.0),
        "weight_n": rng.uniform(20.0, 60.0),
    }
    force_top = float(tondu_force(np.array([peak]), np.array([stroke_mm]), g)[0])
    g["k_spring_n_mm"] = max(force_top - g["weight_n"], 1.0) / stroke_mm
    return g


def _tangent_stiffness(g: dict[str, float], peak: float) -> tuple[float, float]:
    """``k0, k1`` [N/mm] of a linear fit ``k0 + k1 p / peak`` to the balance's stiffness."""
    ks = []
    for share in (0.2, 1.0):
        pr = np.array([share * peak])
        x = tondu_contraction(pr, g)
        slope = (tondu_force(pr, x - 0.1, g) - tondu_force(pr, x + 0.1, g)) / 0.2
        ks.append(float(slope[0]) + g["k_spring_n_mm"])
    k1 = (ks[1] - ks[0]) / 0.8
    return max(ks[0] - 0.2 * k1, 1.0), max(k1, 0.5)


# ---- extended Masing rules -----------------------------------------------------------------------


def masing(pressure: Array, half_width: float, knee: float) -> Array:
    """Friction loss [bar] of the extended Masing model with backbone ``h = a tanh(p / s)``:
    the branch from a reversal ``(p_r, h_r)`` is ``h_r + d 2 a tanh(|p - p_r| / 2 s)``; when a
    branch passes the reversal before its own, that minor loop is closed and removed (the
    branch continues as the older one). Starts on the lower outer branch (vented)."""
    a, s2 = half_width, 2.0 * knee
    rev_p, rev_h = [math.inf], [a]  # a virtual reversal above the range: the outer descending branch
    d, last, h = -1.0, float(pressure[0]), -a
    out = np.empty_like(pressure)
    for i, pi in enumerate(pressure.tolist()):
        if pi != last:
            nd = 1.0 if pi > last else -1.0
            if nd != d:
                rev_p.append(last)
                rev_h.append(h)
                d = nd
            while len(rev_p) >= 3 and (pi - rev_p[-2]) * d >= 0.0:
                del rev_p[-2:], rev_h[-2:]
            h = rev_h[-1] + d * 2.0 * a * math.tanh(abs(pi - rev_p[-1]) / s2) if rev_p[-1] != math.inf else d * a
            last = pi
        out[i] = h
    return out


def masing_tondu(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Contraction [mm] of a Tondu-Lopez muscle at the effective pressure ``p (1 - w h)`` [bar],
    ``h`` the Masing friction share (half-width ``masing_share``, knee ``knee_bar``)."""
    pr = valve(u, dt_s, p)
    h = masing(pr, p["masing_share"], p["knee_bar"])
    return tondu_contraction(pr * (1.0 - _width(width, pr) * h), p)


# ---- Tellinen rule between limiting branches -----------------------------------------------------


def _branches(v: Array, p: dict[str, float]) -> tuple[Array, Array]:
    """Centre and half-width [share of stroke] of the limiting branches at ``v = p / peak``
    (ascending: centre - half, descending: centre + half)."""
    vs = p["envelope_share"]
    centre = -np.expm1(-np.clip(v, 0.0, 1.2) / vs) / -math.expm1(-1.0 / vs)
    s = np.clip(v, 0.0, 1.0)
    half = p["half_width"] * np.sin(np.pi * s) ** 0.7 * (1.0 + p["skew"] * (s - 0.5))
    return centre, half


def tellinen_sleeve(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Stroke [mm] ``stroke_mm y``: rising, ``dy = dL_a (L_d - y) / (L_d - L_a)``; falling,
    ``dy = dL_d (y - L_a) / (L_d - L_a)`` (sub-steps of at most 0.004 in ``v``); ``width``
    scales the state's distance from the centre curve (the loop, minor loops too)."""
    v = np.clip(valve(u, dt_s, p) / p["peak"], 0.0, None)
    grid = np.linspace(0.0, 1.2, 1201)
    c_tab, h_tab = _branches(grid, p)
    out = np.empty_like(v)
    last = float(v[0])
    c0, h0 = _branches(np.array([last]), p)
    y = float(c0[0] - h0[0])
    for i, vi in enumerate(v.tolist()):
        n_sub = 1 + int(abs(vi - last) / 0.004)
        step = (vi - last) / n_sub
        for k in range(n_sub):
            a, b = last + k * step, last + (k + 1) * step
            ja, jb = min(int(a * 1000.0), 1199), min(int(b * 1000.0), 1199)
            fa, fb = a * 1000.0 - ja, b * 1000.0 - jb
            ca, ha = c_tab[ja] + fa * (c_tab[ja + 1] - c_tab[ja]), h_tab[ja] + fa * (h_tab[ja + 1] - h_tab[ja])
            cb, hb = c_tab[jb] + fb * (c_tab[jb + 1] - c_tab[jb]), h_tab[jb] + fb * (h_tab[jb + 1] - h_tab[jb])
            la, da, lb, db = ca - ha, ca + ha, cb - hb, cb + hb
            gap = max(da - la, 1e-6)
            y += (lb - la) * (da - y) / gap if step > 0.0 else (db - da) * (y - la) / gap
            y = min(max(y, lb), db)
        last = vi
        out[i] = y
    centre, _ = _branches(v, p)
    return np.asarray(p["stroke_mm"] * (centre + _width(width, v) * (out - centre)), dtype=np.float64)


# ---- Bliman-Sorine friction ----------------------------------------------------------------------


def bliman_sorine(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Contraction ``x_f - w F / K(p)`` [mm]: ``x_f`` the frictionless Tondu-Lopez balance, ``F``
    [N] the Bliman-Sorine friction ``z1 - z2`` with ``dz1/ds = (f1 sgn - z1) / (eta eps)``,
    ``dz2/ds = (f2 sgn - z2) / eps`` in the path length ``s`` [mm] of ``x_f`` (exact per
    sample, starting relaxed), ``K`` the balance's stiffness ``k0 + k1 p / peak``."""
    pr = valve(u, dt_s, p)
    xf = tondu_contraction(pr, p)
    stiff = p["k0_n_mm"] + p["k1_n_mm"] * np.clip(pr, 0.0, None) / p["peak"]
    f1, f2, l1, l2 = p["f1_n"], p["f2_n"], p["eta"] * p["eps_mm"], p["eps_mm"]
    z1, z2, last, sgn = 0.0, 0.0, float(xf[0]), -1.0  # relaxed after the vented rest
    out = np.empty_like(xf)
    for i, (xi, ki, wi) in enumerate(zip(xf.tolist(), stiff.tolist(), _width(width, xf).tolist())):
        ds = xi - last
        if ds != 0.0:
            sgn = 1.0 if ds > 0.0 else -1.0
            e1, e2 = math.exp(-abs(ds) / l1), math.exp(-abs(ds) / l2)
            z1 = sgn * f1 + (z1 - sgn * f1) * e1
            z2 = sgn * f2 + (z2 - sgn * f2) * e2
            last = xi
        out[i] = xi - wi * (z1 - z2) / ki
    return out


# ---- Stoner-Wohlfarth crimps ---------------------------------------------------------------------

SW_ANGLES_DEG = np.linspace(6.0, 84.0, 12)
SW_GRID = np.linspace(-3.0, 3.0, 601)


def switching_field(theta_deg: Array) -> Array:
    """The astroid: the reduced field at which a well at ``theta`` to the field vanishes."""
    th = np.radians(theta_deg)
    return np.asarray((np.cos(th) ** (2.0 / 3.0) + np.sin(th) ** (2.0 / 3.0)) ** -1.5, dtype=np.float64)


@cache
def sw_branches() -> tuple[Array, Array]:
    """``cos(phi)`` along the upper well (``phi`` near 0) and the lower one (near pi) for every
    angle in :data:`SW_ANGLES_DEG` on :data:`SW_GRID`: minima of ``sin^2(phi - theta) / 2 - h
    cos(phi)``, followed by continuation from a strong field (the lost well is filled with the
    other's value, never read)."""
    th = np.radians(SW_ANGLES_DEG)
    hsw = switching_field(SW_ANGLES_DEG)
    upper = np.empty((th.size, SW_GRID.size))
    phi = np.zeros_like(th)
    for j in range(SW_GRID.size - 1, -1, -1):
        h = SW_GRID[j]
        for _ in range(12):
            grad = 0.5 * np.sin(2.0 * (phi - th)) + h * np.sin(phi)
            curv = np.cos(2.0 * (phi - th)) + h * np.cos(phi)
            phi = phi - grad / np.where(np.abs(curv) > 1e-3, curv, 1e-3)
        upper[:, j] = np.where(h > -hsw, np.cos(phi), np.nan)
    lower = -upper[:, ::-1]  # the well near pi is the mirror image in the field
    upper_filled = np.where(np.isnan(upper), lower, upper)
    lower_filled = np.where(np.isnan(lower), upper, lower)
    return upper_filled, lower_filled


def stoner_crimps(u: Array, dt_s: float, p: dict[str, float], width: Array | None = None) -> Array:
    """Stroke [mm] ``rev_mm S(v) + hyst_mm (mean m + 1) / 2``: ``S`` an exponential envelope,
    ``m`` the elements' projections; element ``(angle, scale)`` sees the reduced field ``(p -
    centre) / H``, ``H = h_scale peak`` times 0.75, 0.9, 1.1, 1.3, and is in the upper well
    after it last passed ``+w h_sw`` and in the lower one after it last passed ``-w h_sw``
    (``w``: ``width``, the cords' friction scaling their switching fields)."""
    pr = valve(u, dt_s, p)
    v = np.clip(pr / p["peak"], 0.0, None)
    upper, lower = sw_branches()
    hsw = switching_field(SW_ANGLES_DEG)
    idx, w = np.arange(v.size), _width(width, v)
    total = np.zeros_like(v)
    n = 0
    for scale in (0.75, 0.9, 1.1, 1.3):
        h = (v - p["centre_share"]) / (p["h_scale"] * scale)
        for k in range(SW_ANGLES_DEG.size):
            ev = np.where(h >= w * hsw[k], 1, np.where(h <= -w * hsw[k], -1, 0))
            last = np.maximum.accumulate(np.where(ev != 0, idx, 0))
            state = np.where(ev[last] != 0, ev[last], -1)
            total += np.where(state > 0, np.interp(h, SW_GRID, upper[k]), np.interp(h, SW_GRID, lower[k]))
            n += 1
    vs = p["envelope_share"]
    envelope = -np.expm1(-v / vs) / -math.expm1(-1.0 / vs)
    return np.asarray(p["rev_mm"] * envelope + p["hyst_mm"] * (total / n + 1.0) / 2.0, dtype=np.float64)


BLIND4_CORES: dict[str, Core] = {
    "masing_tondu": masing_tondu,
    "tellinen_sleeve": tellinen_sleeve,
    "bliman_sorine": bliman_sorine,
    "stoner_crimps": stoner_crimps,
}


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~15-40 mm, a
    loop 3-20 % of the stroke wide), its rig's constants included."""
    stroke = float(rng.uniform(16.0, 38.0))
    if core in ("masing_tondu", "bliman_sorine"):
        g = _tondu_params(rng, peak, stroke)
        k0, k1 = _tangent_stiffness(g, peak)
        g.update(draw_rig(rng, peak, k0, k1))
        if core == "masing_tondu":
            g.update(masing_share=rng.uniform(0.05, 0.1), knee_bar=rng.uniform(0.04, 0.1) * peak)
        else:
            k_mid = k0 + 0.5 * k1
            coulomb = rng.uniform(0.02, 0.045) * stroke * k_mid  # N: half the loop width
            f2 = rng.uniform(0.3, 0.6) * coulomb
            g.update(f1_n=coulomb + f2, f2_n=f2, eta=rng.uniform(0.25, 0.5), eps_mm=rng.uniform(0.3, 0.8))
        return g
    k_mid = rng.uniform(3.0, 8.0)
    g = draw_rig(rng, peak, 0.6 * k_mid, 0.8 * k_mid)
    if core == "tellinen_sleeve":
        g.update(
            stroke_mm=stroke,
            envelope_share=rng.uniform(0.4, 1.0),
            half_width=rng.uniform(0.02, 0.045),
            skew=rng.uniform(-0.6, 0.6),
        )
        return g
    if core == "stoner_crimps":
        hyst = rng.uniform(0.05, 0.1) * stroke
        g.update(
            rev_mm=stroke - hyst,
            hyst_mm=hyst,
            envelope_share=rng.uniform(0.5, 1.2),
            centre_share=rng.uniform(0.42, 0.58),
            h_scale=rng.uniform(0.12, 0.22),
        )
        return g
    raise KeyError(f"unknown blind4 core {core!r}; known: {', '.join(BLIND4_CORES)}")
