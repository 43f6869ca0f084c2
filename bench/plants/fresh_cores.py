"""Four held-out hysteresis cores for a pneumatic muscle rig, unlike :mod:`bench.plants.cores`.

Every core maps an input ``u`` [bar-like, 0..peak] to a contraction ``y`` [mm], increasing in
``u``, with ``core(u, dt_s, params, hooks) -> y``. :class:`Hooks` carries per-sample arrays
through which the effects of :mod:`bench.plants.fresh_effects` act *inside* the physics:

* ``width``: factor on the hysteresis width (friction level, relay spread, Duhem rate).
* ``load_kg``: hanging mass [kg] acting in the muscle's force balance (0: only the fixed preload).
* ``stiffness``: factor on the elastic stiffness that opposes contraction (load spring, bladder).
* ``relax_s``: time constant [s] of a viscous element on the hysteresis state (0: the state
  jumps at once): Duhem deviation, relay states, slip anchors (Bingham), friction band.

All of them share the quasi-static McKibben balance of :func:`mckibben_contraction`
(``F = p F0 (1 - x)^2`` against ``W + K x``), which has a physical dead zone under load.

* :func:`coleman_hodgdon`: a Duhem (Coleman-Hodgdon) model around the McKibben curve.
* :func:`kp_sum`: Krasnosel'skii-Pokrovskii relays with ramps, a skewed two-lobe density on the
  Preisach plane, driving the McKibben balance as an effective pressure (rate-independent).
* :func:`maxwell_slip_mass`: McKibben force on a moving mass held by Maxwell-slip elements, a
  load spring and viscous damping: second-order mechanics with a light resonance (~10-20 Hz).
* :func:`pneumatic_chamber`: ``u`` is the valve command; the chamber pressure fills and vents
  through a nonlinear, direction-dependent law; contraction follows the McKibben balance with a
  Coulomb friction band in force space (a force-space play).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
G_MS2 = 9.81


@dataclass(frozen=True)
class Hooks:
    """Per-sample modifiers an effect passes into a core (all ones / zeros: no effect)."""

    width: Array
    load_kg: Array
    stiffness: Array
    relax_s: float = 0.0

    @staticmethod
    def neutral(n: int) -> Hooks:
        return Hooks(np.ones(n), np.zeros(n), np.ones(n))


def _relax_share(dt_s: float, relax_s: float) -> float:
    """Share of the way a viscous state moves to its target in ``dt_s`` (1: no viscosity)."""
    return 1.0 if relax_s <= 0.0 else float(1.0 - np.exp(-dt_s / relax_s))


def mckibben_contraction(p: Array | float, load: Array | float, stiffness: Array | float) -> Array:
    """Contraction ratio ``x`` in [0, 1) of the muscle's maximum at normalised pressure ``p``.

    Solves ``p (1 - x)^2 = load + stiffness x`` (forces as fractions of the full-pressure
    force ``F0``); zero where ``p <= load`` (the muscle stays at full length under its load).
    """
    a = np.maximum(np.asarray(p, dtype=np.float64), 1e-9)
    w = np.asarray(load, dtype=np.float64)
    k = np.asarray(stiffness, dtype=np.float64)
    disc = 4.0 * a * k + k * k + 4.0 * a * w
    x = 2.0 * (a - w) / ((2.0 * a + k) + np.sqrt(disc))  # the stable root of the quadratic
    return np.maximum(x, 0.0)


def coleman_hodgdon(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """Duhem model ``dz = alpha |dv| (f(v) - z) + g(v) dv`` with ``v = u / peak``.

    ``f`` is the McKibben curve [mm] (``stroke_mm`` times :func:`mckibben_contraction`),
    ``g = gamma f'`` with ``gamma < 1``: ascending branches run below ``f``, descending above,
    loop width ~ ``2 (1 - gamma) f' / alpha``; ``alpha`` [1/unit of v] is divided by ``width``.
    With ``relax_s`` the hysteretic deviation ``z - f`` reaches the output through a lag.
    """
    v = u / p["peak"]
    load = p["preload"] + hooks.load_kg * G_MS2 / p["f0_n"]
    k = p["k"] * hooks.stiffness
    f = p["stroke_mm"] * mckibben_contraction(v, load, k)
    dv = 1e-3
    slope = p["stroke_mm"] * (mckibben_contraction(v + dv, load, k) - mckibben_contraction(v - dv, load, k)) / (2 * dv)
    g = p["gamma"] * slope
    alpha = p["alpha"] / hooks.width
    out = np.empty_like(u)
    z = float(f[0])
    prev = float(v[0])
    share = _relax_share(dt_s, hooks.relax_s)
    dev = 0.0
    sub = 4  # sub-steps keep alpha |dv| < 1 (no overshoot past f)
    for i, (vi, fi, gi, ai) in enumerate(zip(v.tolist(), f.tolist(), g.tolist(), alpha.tolist())):
        d = (vi - prev) / sub
        for _ in range(sub):
            z += ai * abs(d) * (fi - z) + gi * d
        prev = vi
        dev += share * ((z - fi) - dev)
        out[i] = fi + dev
    return out


def _kp_grid(p: dict[str, float]) -> tuple[Array, Array, Array]:
    """Relay midpoints, half-spreads (in v) and weights of the KP density (two skewed lobes)."""
    grid_mid, grid_half = np.meshgrid(np.linspace(0.05, 0.95, 14), np.geomspace(0.02, 0.3, 9))
    mids, halves = grid_mid.ravel(), grid_half.ravel()
    lobe1 = np.exp(-(((mids - p["mid1"]) / 0.18) ** 2) - np.log(halves / p["half1"]) ** 2 / 0.5)
    lobe2 = p["lobe2"] * np.exp(-(((mids - p["mid2"]) / 0.12) ** 2) - np.log(halves / p["half2"]) ** 2 / 0.3)
    w = lobe1 + lobe2
    return mids, halves, w / w.sum()


def kp_sum(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """Effective pressure ``h = (1 - s) v + s * sum w_i r_i(v)`` of KP relays with ramps, then
    the McKibben balance; rate-independent. Relay ``i`` (ramp ``a``) follows
    ``r = min(ramp(v - beta), max(ramp(v - alpha + a), r))``, ``alpha - beta = 2 half width``;
    with ``relax_s`` each relay moves to that target through a first-order lag."""
    v = u / p["peak"]
    mids, halves, w = _kp_grid(p)
    ramp = 0.015
    share = p["share"]
    move = _relax_share(dt_s, hooks.relax_s)
    r = np.zeros_like(mids)  # vented: every relay off
    h = np.empty_like(u)
    for i, (vi, wi) in enumerate(zip(v.tolist(), hooks.width.tolist())):
        half = np.maximum(halves * wi, ramp)
        up = np.clip((vi - (mids + half) + ramp) / ramp, 0.0, 1.0)
        down = np.clip((vi - (mids - half)) / ramp, 0.0, 1.0)
        r += move * (np.minimum(down, np.maximum(up, r)) - r)
        h[i] = (1.0 - share) * vi + share * float(w @ r)
    load = p["preload"] + hooks.load_kg * G_MS2 / p["f0_n"]
    return p["stroke_mm"] * mckibben_contraction(h, load, p["k"] * hooks.stiffness)


def maxwell_slip_mass(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """``m y'' = F0 v (1 - y/ym)^2 - sum F_i - k_L y - W - c y'`` [N, mm, kg], semi-implicit
    Euler at <= 0.5 ms. Element ``i`` (stiffness ``k_i``, break-away ``f_i width``) sticks
    while ``|k_i (y - s_i)| < f_i`` and slides otherwise (with ``relax_s``: its anchor creeps to
    the limit through a lag, a Bingham element); the hanging mass adds to ``m``."""
    f0, ym = p["f0_n"], p["ym_mm"]
    n_el = 4
    ks = [p["k_slip"] * s for s in (0.4, 0.3, 0.2, 0.1)]
    fs = [p["f_slip"] * s for s in (0.1, 0.2, 0.3, 0.4)]
    sub = max(1, int(np.ceil(dt_s / 0.0005)))
    h = dt_s / sub
    move = _relax_share(h, hooks.relax_s)
    y, vel = 0.0, 0.0
    anchors = [0.0] * n_el
    out = np.empty_like(u)
    prev = float(u[0])
    for i, (ui, wi, li, si) in enumerate(
        zip(u.tolist(), hooks.width.tolist(), hooks.load_kg.tolist(), hooks.stiffness.tolist())
    ):
        mass = p["mass_kg"] + li
        weight = p["preload_n"] + li * G_MS2
        k_load = p["k_load"] * si
        du = (ui - prev) / sub
        for s in range(sub):
            v = (prev + du * (s + 1)) / p["peak"]
            stretch = max(0.0, 1.0 - y / ym)
            force = f0 * v * stretch * stretch - k_load * y - weight - p["c"] * vel
            for j in range(n_el):
                limit = fs[j] * wi
                fj = ks[j] * (y - anchors[j])
                if fj > limit:
                    anchors[j] += move * (y - limit / ks[j] - anchors[j])
                    fj = ks[j] * (y - anchors[j])
                elif fj < -limit:
                    anchors[j] += move * (y + limit / ks[j] - anchors[j])
                    fj = ks[j] * (y - anchors[j])
                force -= fj
            vel += h * force / mass * 1000.0  # N/kg = m/s^2 -> mm/s^2
            y = max(0.0, y + h * vel)  # the muscle cannot lengthen past its rest length
            if y == 0.0 and vel < 0.0:
                vel = 0.0
        prev = ui
        out[i] = y
    return out


def pneumatic_chamber(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """Valve command ``u`` -> chamber pressure ``P`` -> contraction [mm].

    ``dP/dt = sign(e) |e|^0.6 rate(P)`` with ``e = u - P`` (sonic-like flow), filling at
    ``rate_fill / (1 + P/peak)`` (volume grows), venting at ``rate_vent (0.3 + P/peak)`` (little
    head to atmosphere when low); never overshoots. Contraction: Coulomb band ``+-fc width`` in
    force space, ``x = clip(x, x(P, W + fc), x(P, W - fc))`` with the McKibben balance (with
    ``relax_s``: ``x`` moves to that clip through a lag).
    """
    peak = p["peak"]
    sub = max(1, int(np.ceil(dt_s / 0.001)))
    h = dt_s / sub
    pres = float(u[0])
    pressure = np.empty_like(u)
    for i, ui in enumerate(u.tolist()):
        for _ in range(sub):
            e = ui - pres
            if e >= 0:
                rate = p["rate_fill"] / (1.0 + pres / peak)
            else:
                rate = p["rate_vent"] * (0.3 + pres / peak)
            step = h * rate * abs(e / peak) ** 0.6 * peak
            pres += min(step, abs(e)) if e >= 0 else -min(step, abs(e))
        pressure[i] = pres
    v = pressure / peak
    load = p["preload"] + hooks.load_kg * G_MS2 / p["f0_n"]
    k = p["k"] * hooks.stiffness
    fc = p["fc"] * hooks.width
    hi = mckibben_contraction(v, np.maximum(load - fc, 0.0), k)
    lo = mckibben_contraction(v, load + fc, k)
    x = np.empty_like(u)
    xi = float(lo[0])
    move = _relax_share(dt_s, hooks.relax_s)
    for i, (a, b) in enumerate(zip(lo.tolist(), hi.tolist())):
        xi += move * (min(b, max(a, xi)) - xi)
        x[i] = xi
    return p["stroke_mm"] * x


Core = Callable[[Array, float, dict[str, float], Hooks], Array]
FRESH_CORES: dict[str, Core] = {
    "coleman_hodgdon": coleman_hodgdon,
    "kp_sum": kp_sum,
    "maxwell_slip_mass": maxwell_slip_mass,
    "pneumatic_chamber": pneumatic_chamber,
}
RATE_INDEPENDENT = ("coleman_hodgdon", "kp_sum")


def _muscle(rng: np.random.Generator, peak: float) -> dict[str, float]:
    """The force-balance parameters the Duhem, relay and chamber cores share (drawn in this order)."""
    return {
        "peak": peak,
        "stroke_mm": rng.uniform(35.0, 55.0),
        "preload": rng.uniform(0.02, 0.06),
        "f0_n": rng.uniform(500.0, 900.0),
        "k": rng.uniform(0.4, 1.0),
    }


def draw_fresh_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` (stroke 30-60 mm of a ~200 mm muscle, output span ~12-40 mm)."""
    if core == "coleman_hodgdon":
        return {
            **_muscle(rng, peak),
            "alpha": rng.uniform(2.5, 5.0),
            "gamma": rng.uniform(0.5, 0.7),
        }
    if core == "kp_sum":
        return {
            **_muscle(rng, peak),
            "share": rng.uniform(0.35, 0.6),
            "mid1": rng.uniform(0.3, 0.5),
            "half1": rng.uniform(0.05, 0.12),
            "mid2": rng.uniform(0.65, 0.85),
            "half2": rng.uniform(0.03, 0.06),
            "lobe2": rng.uniform(0.3, 0.8),
        }
    if core == "maxwell_slip_mass":
        return {
            "peak": peak,
            "f0_n": rng.uniform(500.0, 800.0),
            "ym_mm": rng.uniform(45.0, 60.0),
            "k_load": rng.uniform(3.0, 6.0),  # N/mm
            "preload_n": rng.uniform(15.0, 30.0),
            "mass_kg": rng.uniform(1.0, 3.0),
            "k_slip": rng.uniform(20.0, 40.0),  # N/mm, all elements stuck
            "f_slip": rng.uniform(30.0, 60.0),  # N, total break-away
            "c": rng.uniform(0.05, 0.15),  # N s/mm: damping ratio ~0.1-0.3
        }
    if core == "pneumatic_chamber":
        return {
            **_muscle(rng, peak),
            "rate_fill": rng.uniform(8.0, 16.0),  # 1/s at full error
            "rate_vent": rng.uniform(6.0, 12.0),
            "fc": rng.uniform(0.03, 0.06),
        }
    raise KeyError(f"unknown fresh core {core!r}; known: {', '.join(FRESH_CORES)}")
