"""Four hysteresis cores for the twelfth (blind10) plant family, unlike the other forty-four.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params) -> y``, through the I/P converter and the volume booster
(:func:`bench.plants.blind10_rig.muscle_pressure`). Each is a *drive* ``drive(v, dt_s, params,
mods) -> y`` of the muscle's normalised pressure ``v`` [share of peak] in which some effects act
(:mod:`bench.plants.blind10_effects`): ``mods`` may hold ``"rubber"`` (a factor on the bladder's
Gent modulus) and ``"spring"`` (a factor on the return spring's stiffness).

The muscle (:func:`solve_strain`) is a Chou-Hannaford braid around a *Gent* bladder (a
limiting-chain-extensibility rubber: its hoop resistance stiffens sharply as the hoop stretch
nears the chains' limit), with a lift-off pressure spent inflating the bladder onto the braid,
pulling a weight and a return spring. The force balance is solved for the strain by bisection
(vectorised over the record). The hysteresis:

* :func:`bristle_bladder`: the bladder-braid contact as *Haessig-Friedland bristles*: 16-32
  bonds, each an elastic bristle that snaps when its deflection passes a limit and re-bonds at
  once where it snapped with a random small deflection; the normal force (so the force of every bond) grows with
  the pressure. A friction with presliding and a saw-toothed sliding level, not a sum of
  Masing elements: the loops never repeat exactly. The force is put back into the force balance.
* :func:`avalanche_crossings`: the braid's crossings as an *Olami-Feder-Christensen* lattice (a
  ring of 10-18 crossings, each loaded by the braid's travel, slipping when its force reaches its
  own threshold, dropping to a residual and passing a share ``alpha`` of the drop to both
  neighbours, which may slip in turn: avalanches of all sizes, non-conservative). The crossings'
  total force is put back into the force balance.
* :func:`check_valve_twin`: *two muscles in parallel* on one payload, the second (thinner, another
  braid angle) fed from the first's line through a pair of opposed *check valves* with cracking
  pressures of 4-10 % of the peak (filling) and 3-8 % (venting): the second muscle's pressure is
  an asymmetric play of the first's, and it keeps the venting valve's cracking pressure when the
  line is vented. Hysteresis from the pneumatic circuit, not from friction.
* :func:`overcentre_latch`: a *snap-action over-centre spring* (a preloaded compression spring on a
  pivoting strut, anchored beside the carriage's path: it pushes the carriage away from the
  point of closest approach and loses contact once it reaches its free length) on a carriage with a
  small Coulomb friction. The stroke follows its local equilibrium (tracked on a fine grid) and
  snaps across the unstable stretch: one macroscopic jump up and one at a lower pressure down.
"""

from __future__ import annotations

import bisect
import math
from operator import add, sub
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind10_rig import draw_rig, muscle_pressure

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2
BISECTION_STEPS = 26
BLADDER_TABLE = 2048
LATCH_GRID = 1500
LATCH_WINDOW = 24  # grid cells searched per numpy call while the latch carriage moves


class Drive(Protocol):
    def __call__(self, v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array: ...


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float]) -> Array: ...


# ---- the muscle: Chou-Hannaford braid, Gent bladder ------------------------------------------------


def braid_g(e: Array | float, a: float, b: float) -> Array:
    """Chou-Hannaford's ``a (1 - e)^2 - b`` (the force per unit pressure and area) at strain ``e``."""
    return np.asarray(a * (1.0 - np.asarray(e)) ** 2 - b, dtype=np.float64)


def gent_shape(e: Array | float, p: dict[str, float], braid: str = "") -> Array:
    """The Gent bladder's axial resistance at strain ``e`` per unit of its modulus: ``W'(lam)
    dlam/de`` with the hoop stretch ``lam = sin(theta) / sin(theta0)``, ``cos(theta) = (1 - e)
    cos(theta0)``, ``W'(lam) ~ (lam - lam^-3) / (1 - (lam^2 + lam^-2 - 2) / J_m)`` (clipped short
    of the chains' limit)."""
    theta0 = p[f"braid_angle{braid}_rad"]
    c0, s0 = math.cos(theta0), math.sin(theta0)
    e = np.asarray(e, dtype=np.float64)
    inner = np.sqrt(np.clip(1.0 - (1.0 - e) ** 2 * c0 * c0, 1e-12, None))
    lam = inner / s0
    dlam = (1.0 - e) * c0 * c0 / (s0 * inner)
    i1 = lam * lam + 1.0 / (lam * lam) - 2.0
    lock = np.clip(1.0 - i1 / p["gent_jm"], 0.05, None)
    return np.asarray((lam - lam**-3) / lock * dlam, dtype=np.float64)


_BLADDER_TABLES: dict[tuple[float, ...], tuple[Array, Array]] = {}


def bladder_n(e: Array | float, p: dict[str, float]) -> Array:
    """The bladder's resistance [N] at strain ``e``: ``bladder_top_n`` at the top strain
    (:func:`gent_shape` tabulated at :data:`BLADDER_TABLE` points up to ``strain_max``, read linearly)."""
    key = (p["braid_angle_rad"], p["gent_jm"], p["gent_top_shape"], p["bladder_top_n"], p["strain_max"])
    if key not in _BLADDER_TABLES:
        if len(_BLADDER_TABLES) > 512:
            _BLADDER_TABLES.clear()
        grid = np.linspace(0.0, p["strain_max"] * 1.05, BLADDER_TABLE)
        _BLADDER_TABLES[key] = grid, p["bladder_top_n"] * gent_shape(grid, p) / p["gent_top_shape"]
    grid, table = _BLADDER_TABLES[key]
    return np.asarray(np.interp(e, grid, table), dtype=np.float64)


def residual_n(
    e: Array, v: Array, p: dict[str, float], rubber: Array, spring: Array, f_ext: Array, v2: Array | None = None
) -> Array:
    """The force balance's surplus [N] at strain ``e``: the muscle's pull at the pressure share
    ``v`` beyond lift-off (``lift_share`` x ``rubber``; a second muscle's at ``v2`` if given) minus
    the weight, ``f_ext``, the spring (x ``spring``) and the bladder (x ``rubber``)."""
    q = BAR_N_MM2 * p["area_mm2"] * p["peak"]
    pull = q * np.clip(v - rubber * p["lift_share"], 0.0, None) * braid_g(e, p["braid_a"], p["braid_b"])
    if v2 is not None:
        q2 = BAR_N_MM2 * p["area2_mm2"] * p["peak"]
        pull = pull + q2 * np.clip(v2 - rubber * p["lift2_share"], 0.0, None) * np.clip(
            braid_g(e, p["braid2_a"], p["braid2_b"]), 0.0, None
        )
    hold = p["weight_n"] + f_ext + spring * p["k_spring_n_mm"] * p["length_mm"] * e + rubber * bladder_n(e, p)
    return np.asarray(pull - hold, dtype=np.float64)


def _mod(v: Array, mods: dict[str, Array], key: str) -> Array:
    m = mods.get(key)
    return np.ones_like(v) if m is None else np.asarray(m, dtype=np.float64)


def solve_strain(
    v: Array, p: dict[str, float], mods: dict[str, Array], f_ext: Array | None = None, v2: Array | None = None
) -> Array:
    """The strain where :func:`residual_n` is zero (it falls with the strain): 0 below lift-off,
    at most ``strain_max``; bisection, :data:`BISECTION_STEPS` halvings."""
    rubber, spring = _mod(v, mods, "rubber"), _mod(v, mods, "spring")
    f = np.zeros_like(v) if f_ext is None else f_ext
    lo, hi = np.zeros_like(v), np.full_like(v, p["strain_max"])
    for _ in range(BISECTION_STEPS):
        mid = 0.5 * (lo + hi)
        up = residual_n(mid, v, p, rubber, spring, f, v2) > 0.0
        lo = np.where(up, mid, lo)
        hi = np.where(up, hi, mid)
    at_rest = residual_n(np.zeros_like(v), v, p, rubber, spring, f, v2) <= 0.0
    return np.asarray(np.where(at_rest, 0.0, 0.5 * (lo + hi)), dtype=np.float64)


def static_stroke(v: Array, p: dict[str, float], mods: dict[str, Array], f_ext: Array | None = None) -> Array:
    """The frictionless contraction [mm] at pressure share ``v`` (the force ``f_ext`` [N] added to
    what the muscle pulls against)."""
    return np.asarray(solve_strain(v, p, mods, f_ext) * p["length_mm"], dtype=np.float64)


def stiffness_n_mm(v: Array, x: Array, p: dict[str, float], mods: dict[str, Array] | None = None) -> Array:
    """The balance's stiffness [N/mm] at ``(v, x)``: how much the surplus falls per mm of stroke
    (central difference of :func:`residual_n` over +-0.05 mm; at least 1e-6)."""
    m = mods or {}
    rubber, spring, zero = _mod(v, m, "rubber"), _mod(v, m, "spring"), np.zeros_like(v)
    h = 0.05 / p["length_mm"]
    e = x / p["length_mm"]
    lo = residual_n(np.clip(e - h, 0.0, None), v, p, rubber, spring, zero)
    hi = residual_n(e + h, v, p, rubber, spring, zero)
    return np.asarray(np.clip((lo - hi) / 0.1, 1e-6, None), dtype=np.float64)


# ---- Haessig-Friedland bristles between bladder and braid -------------------------------------------


def bristle_force(x0: Array, v: Array, stiff: Array, p: dict[str, float]) -> Array:
    """The bristles' friction force [N] (opposing the contraction when positive) for the
    frictionless stroke ``x0`` [mm]: ``F = N(v) k sum (x - a_j)`` at the stroke ``x = x0 - F / K``
    (``K`` = ``stiff`` [N/mm], the balance's stiffness: the bristles and the muscle in series, solved
    each sample); bond ``j`` anchored at ``a_j`` snaps when ``|x - a_j|`` passes ``bristle_reach_mm``
    and re-bonds where it snapped with a deflection ``U(-1, 1) x rebond_share x reach`` (so the
    state depends on the path, not on the sampling); the normal-force factor
    ``N(v) = n0 + (1 - n0) v`` (``v`` clipped to 0..1.2); from rest (every bond unloaded at
    ``x0[0]``), the re-bond draws seeded by ``bristle_seed``."""
    n = int(p["bristles"])
    reach, k = p["bristle_reach_mm"], p["bristle_k_n_mm"]
    n0 = p["normal_floor"]
    rng = np.random.default_rng(int(p["bristle_seed"]))
    draws = (rng.uniform(-1.0, 1.0, 4096) * p["rebond_share"] * reach).tolist()
    used = 0
    anchors = [float(x0[0])] * n  # kept sorted
    total = float(x0[0]) * n
    out = np.empty(x0.size)
    for i, (xi, vi, ki) in enumerate(zip(x0.tolist(), v.tolist(), stiff.tolist())):
        c = (n0 + (1.0 - n0) * min(max(vi, 0.0), 1.2)) * k
        while True:
            x = max((xi + c * total / ki) / (1.0 + c * n / ki), 0.0)
            if x - anchors[0] > reach:
                old = anchors.pop(0)
                snapped = old + reach  # where it snapped: the same on any sampling
            elif anchors[-1] - x > reach:
                old = anchors.pop()
                snapped = old - reach
            else:
                break
            new = snapped - draws[used % len(draws)]
            used += 1
            bisect.insort(anchors, new)
            total += new - old
        out[i] = c * (n * x - total)
    return out


def bristle_bladder(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] with the bristles' force put back into the force balance."""
    x0 = static_stroke(v, p, mods)
    return static_stroke(v, p, mods, bristle_force(x0, v, stiffness_n_mm(v, x0, p, mods), p))


# ---- Olami-Feder-Christensen crossings ------------------------------------------------------------


def _topple(s: list[float], offset: float, thl: list[float], edge: list[float], r: float, alpha: float) -> None:
    """Relax the ring in place (crossing ``j``'s force is ``s[j] + offset``): every crossing at or
    past its threshold (``edge``: the thresholds less a rounding margin) drops to ``r`` x it and
    passes ``alpha`` x the drop to each neighbour, which are checked in turn, until all are below."""
    n = len(s)
    todo = [j for j in range(n) if abs(s[j] + offset) >= edge[j]]
    while todo:
        j = todo.pop()
        f = s[j] + offset
        if abs(f) < edge[j]:
            continue
        rest = r * thl[j] if f > 0.0 else -r * thl[j]
        share = alpha * (f - rest)
        s[j] = rest - offset
        left, right = j - 1 if j else n - 1, j + 1 if j + 1 < n else 0
        s[left] += share
        s[right] += share
        todo += [left, right]


def ofc_force(x0: Array, stiff: Array, p: dict[str, float]) -> Array:
    """The crossings' total force [N] for the frictionless stroke ``x0`` [mm], at the stroke ``x =
    x0 - F / K`` (``K`` = ``stiff`` [N/mm]: the lattice and the muscle in series, solved each
    sample): every crossing's force grows by ``k dx``; one at or past its threshold ``th_j`` drops
    to ``r th_j`` (same sign) and passes ``alpha`` x the drop to each neighbour on the ring, until
    none is past its threshold (an avalanche, started at the loading where the first crossing
    reaches its threshold; the stroke it frees loads the ring again); from rest.
    Thresholds spread ``U(1 - s, 1 + s)`` about ``crossing_n``, seeded by ``ofc_seed``."""
    n = int(p["crossings"])
    rng = np.random.default_rng(int(p["ofc_seed"]))
    thl = (p["crossing_n"] * rng.uniform(1.0 - p["threshold_spread"], 1.0 + p["threshold_spread"], n)).tolist()
    edge = [t * (1.0 - 1e-9) for t in thl]  # at the threshold despite rounding
    k, r, alpha = p["crossing_k_n_mm"], p["residual_share"], p["ofc_alpha"]
    nk, x_ref = n * k, float(x0[0])
    s = [0.0] * n  # each crossing's force less the common loading k (x - x_ref)
    up, down, total = min(thl), min(thl), 0.0
    out = np.empty(x0.size)
    for i, (xi, ki) in enumerate(zip(x0.tolist(), stiff.tolist())):
        for _ in range(100):
            x = max((xi - (total - nk * x_ref) / ki) / (1.0 + nk / ki), 0.0)
            offset = k * (x - x_ref)
            if -down < offset < up:
                break
            # topple at the crossing itself (the loading that reaches the first threshold), so the
            # avalanche is the same on any sampling; the rest of the step is taken on the next pass
            _topple(s, up if offset >= up else -down, thl, edge, r, alpha)
            up, down = min(map(sub, thl, s)), min(map(add, thl, s))
            total = sum(s)
        out[i] = total + nk * (x - x_ref)
    return out


def avalanche_crossings(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] with the crossings' force put back into the force balance."""
    x0 = static_stroke(v, p, mods)
    return static_stroke(v, p, mods, ofc_force(x0, stiffness_n_mm(v, x0, p, mods), p))


# ---- twin muscles joined by check valves ----------------------------------------------------------


def check_valve_pressure(v: Array, p: dict[str, float]) -> Array:
    """The second muscle's pressure [share of peak] behind the opposed check valves: it rises to
    ``v - fill_crack`` when the line exceeds it by the filling valve's cracking pressure, falls to
    ``v + vent_crack`` when the line is below it by the venting valve's; otherwise it is held
    (never below 0; from 0)."""
    fill, vent = p["fill_crack_share"], p["vent_crack_share"]
    out = np.empty(v.size)
    q = 0.0
    for i, vi in enumerate(v.tolist()):
        if vi - q > fill:
            q = vi - fill
        elif q - vi > vent:
            q = max(vi + vent, 0.0)
        out[i] = q
    return out


def check_valve_twin(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] of the two muscles pulling together, the second at the check valves' pressure."""
    return np.asarray(solve_strain(v, p, mods, v2=check_valve_pressure(v, p)) * p["length_mm"], dtype=np.float64)


# ---- over-centre latch -----------------------------------------------------------------------------


def overcentre_push_n(x: Array | float, p: dict[str, float]) -> Array:
    """The over-centre spring's push [N] along the carriage's path at stroke ``x`` [mm]: a
    compression spring of ``latch_k_n_mm`` and free length ``latch_l0_mm`` on a strut anchored
    ``latch_offset_mm`` beside the path at ``latch_x_mm``; ``k (l0 - l) (x - x_c) / l`` while
    ``l < l0`` (pushing away from ``x_c``), 0 once the strut's spring is at its free length."""
    dx = np.asarray(x, dtype=np.float64) - p["latch_x_mm"]
    length = np.sqrt(p["latch_offset_mm"] ** 2 + dx * dx)
    return np.asarray(p["latch_k_n_mm"] * np.clip(p["latch_l0_mm"] - length, 0.0, None) * dx / length)


def latch_tables(p: dict[str, float]) -> tuple[Array, Array, Array]:
    """The grid [mm] and, at each point, the pressure shares at which the carriage starts moving
    up and down there: ``h(x) +- F_c / (Q G(e))``, ``h`` the share that holds ``x`` (the latch's
    push helping the muscle)."""
    x = np.linspace(0.0, p["strain_max"] * p["length_mm"], LATCH_GRID)
    e = x / p["length_mm"]
    q = BAR_N_MM2 * p["area_mm2"] * p["peak"]
    g = braid_g(e, p["braid_a"], p["braid_b"])
    hold = p["weight_n"] + p["k_spring_n_mm"] * x + bladder_n(e, p) - overcentre_push_n(x, p)
    h = p["lift_share"] + hold / (q * g)
    band = p["latch_friction_n"] / (q * g)
    return x, h + band, h - band


def track_latch(w: Array, p: dict[str, float]) -> Array:
    """The carriage's stroke [mm] for the pressure-share history ``w``: it stays while ``w`` lies
    between the shares that move it down and up at its place; beyond, it moves to the nearest
    place (in that direction) where ``w`` no longer moves it, crossing any unstable stretch in one
    jump; from 0 (on the bottom stop)."""
    x, up, down = latch_tables(p)
    upl, downl, xl = up.tolist(), down.tolist(), x.tolist()
    last = x.size - 1
    out = np.empty(w.size)
    j, frac = 0, 0.0  # position: x[j] + frac (x[j+1] - x[j])
    for i, wi in enumerate(w.tolist()):
        jn = min(j + 1, last)
        up_here = upl[j] + frac * (upl[jn] - upl[j])
        down_here = downl[j] + frac * (downl[jn] - downl[j])
        if wi > up_here and j < last:
            k = j + 1
            while k <= last and k < j + 4 and upl[k] < wi:  # most moves end within a few cells
                k += 1
            while k <= last and upl[k] < wi:
                stop = min(k + LATCH_WINDOW, last + 1)
                hits = np.flatnonzero(up[k:stop] >= wi)
                if hits.size:
                    k += int(hits[0])
                    break
                k = stop
            if k > last:
                j, frac = last, 0.0
            else:
                lo_up = up_here if k == j + 1 else upl[k - 1]
                lo_frac = frac if k == j + 1 else 0.0
                t = (wi - lo_up) / (upl[k] - lo_up) if upl[k] > lo_up else 1.0
                pos = (k - 1 + lo_frac) + t * (1.0 - lo_frac)
                j, frac = min(int(pos), last), pos - min(int(pos), last)
        elif wi < down_here and (j > 0 or frac > 0.0):
            k = j if frac > 0.0 else j - 1
            while k >= 0 and k > j - 4 and downl[k] > wi:
                k -= 1
            while k >= 0 and downl[k] > wi:
                start = max(k - LATCH_WINDOW + 1, 0)
                hits = np.flatnonzero(down[start : k + 1] <= wi)
                if hits.size:
                    k = start + int(hits[-1])
                    break
                k = start - 1
            if k < 0:
                j, frac = 0, 0.0
            else:
                hi_down = down_here if k == j else downl[k + 1]
                hi_pos = j + frac if k == j else k + 1.0
                t = (downl[k] - wi) / (downl[k] - hi_down) if downl[k] > hi_down else 0.0
                pos = k + t * (hi_pos - k)
                j, frac = min(int(pos), last), pos - min(int(pos), last)
        out[i] = xl[j] + frac * (xl[min(j + 1, last)] - xl[j])
    return out


def overcentre_latch(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] of the latched carriage. ``mods`` act as the pressure share they are
    worth at the frictionless, latch-free stroke (the tables are the unmodified plant's)."""
    w = np.asarray(v, dtype=np.float64)
    if mods:
        e = solve_strain(v, p, mods)
        rubber, spring = _mod(v, mods, "rubber"), _mod(v, mods, "spring")
        q = BAR_N_MM2 * p["area_mm2"] * p["peak"]
        extra = (spring - 1.0) * p["k_spring_n_mm"] * p["length_mm"] * e + (rubber - 1.0) * bladder_n(e, p)
        w = w - extra / (q * braid_g(e, p["braid_a"], p["braid_b"])) - (rubber - 1.0) * p["lift_share"]
    return track_latch(w, p)


BLIND10_DRIVES: dict[str, Drive] = {
    "bristle_bladder": bristle_bladder,
    "avalanche_crossings": avalanche_crossings,
    "check_valve_twin": check_valve_twin,
    "overcentre_latch": overcentre_latch,
}


def normalised_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The muscle's pressure [share of peak] for the set pressure ``u`` [bar]."""
    return np.asarray(muscle_pressure(u, dt_s, p) / p["peak"], dtype=np.float64)


def _core(name: str) -> Core:
    drive = BLIND10_DRIVES[name]

    def core(u: Array, dt_s: float, p: dict[str, float]) -> Array:
        return drive(normalised_pressure(u, dt_s, p), dt_s, p, {})

    core.__name__ = name
    core.__doc__ = f"Contraction [mm] of the {name} core for the set pressure ``u`` [bar] (no effect)."
    return core


BLIND10_CORES: dict[str, Core] = {name: _core(name) for name in BLIND10_DRIVES}


# ---- parameters ------------------------------------------------------------------------------------


def _braid(rng: np.random.Generator, g: dict[str, float], suffix: str = "") -> None:
    angle = math.radians(float(rng.uniform(18.0, 26.0)))
    g[f"braid_angle{suffix}_rad"] = angle
    g[f"braid{suffix}_a"] = 3.0 / math.tan(angle) ** 2
    g[f"braid{suffix}_b"] = 1.0 / math.sin(angle) ** 2


def _draw_muscle(rng: np.random.Generator, g: dict[str, float], stroke: float, twin: bool) -> None:
    """A Chou-Hannaford braid (18-26 deg, 10-18 mm, 120-300 mm) on a Gent bladder (limit at 1.4-3
    x its top stretch invariant) taking 3-8 % of the peak to lift off and 8-18 % of the top force;
    a weight of 5-12 % of the rest and a spring set so that the frictionless stroke at the peak is
    ``stroke`` (at most 60 % of the braid's free contraction). A twin adds a second muscle of
    45-75 % of the first's area (its own braid angle), counted at the peak less its cracking
    pressure."""
    _braid(rng, g)
    d0, length = float(rng.uniform(10.0, 18.0)), float(rng.uniform(120.0, 300.0))
    a, b = g["braid_a"], g["braid_b"]
    free = 1.0 - math.sqrt(b / a)
    e_top = min(stroke / length, 0.6 * free)
    area = math.pi * d0 * d0 / 4.0
    lift = float(rng.uniform(0.03, 0.08))
    g.update(diameter_mm=d0, length_mm=length, area_mm2=area, lift_share=lift, top_strain=e_top)
    g.update(stroke_mm=e_top * length, strain_max=0.97 * free)
    theta0 = g["braid_angle_rad"]
    lam_top = math.sqrt(1.0 - (1.0 - e_top) ** 2 * math.cos(theta0) ** 2) / math.sin(theta0)
    i1_top = lam_top**2 + lam_top**-2 - 2.0
    g["gent_jm"] = i1_top * float(rng.uniform(1.4, 3.0))
    g["gent_top_shape"] = float(gent_shape(e_top, g))
    top = BAR_N_MM2 * area * g["peak"] * (1.0 - lift) * (a * (1.0 - e_top) ** 2 - b)
    if twin:
        _braid(rng, g, "2")
        g["area2_mm2"] = area * float(rng.uniform(0.45, 0.75))
        g["lift2_share"] = float(rng.uniform(0.03, 0.08))
        g["fill_crack_share"] = float(rng.uniform(0.04, 0.1))
        g["vent_crack_share"] = float(rng.uniform(0.03, 0.08))
        g2 = max(g["braid2_a"] * (1.0 - e_top) ** 2 - g["braid2_b"], 0.0)
        top += BAR_N_MM2 * g["area2_mm2"] * g["peak"] * (1.0 - g["fill_crack_share"] - g["lift2_share"]) * g2
    bladder = float(rng.uniform(0.08, 0.18)) * top
    weight = float(rng.uniform(0.05, 0.12)) * (top - bladder)
    g.update(bladder_top_n=bladder, weight_n=weight, top_force_n=top)
    g["k_spring_n_mm"] = (top - bladder - weight) / (e_top * length)


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~12-34 mm), its
    rig's constants included."""
    if core not in BLIND10_DRIVES:
        raise KeyError(f"unknown blind10 core {core!r}; known: {', '.join(BLIND10_DRIVES)}")
    stroke = float(rng.uniform(12.0, 34.0))
    g = draw_rig(rng, peak)
    _draw_muscle(rng, g, stroke, twin=core == "check_valve_twin")
    g["bow_span_mm"] = 1.2 * g["stroke_mm"]
    top, stroke_mm = g["top_force_n"], g["stroke_mm"]
    if core == "bristle_bladder":
        n = int(rng.integers(16, 33))
        reach = float(rng.uniform(0.025, 0.06)) * stroke_mm
        level = float(rng.uniform(0.04, 0.075)) * top  # the sliding level at full normal force
        g.update(bristles=float(n), bristle_reach_mm=reach, bristle_k_n_mm=2.0 * level / (n * reach))
        g.update(rebond_share=rng.uniform(0.1, 0.5), normal_floor=rng.uniform(0.2, 0.4))
        g["bristle_seed"] = float(rng.integers(0, 2**31))
        return g
    if core == "avalanche_crossings":
        n = int(rng.integers(10, 19))
        r = float(rng.uniform(0.05, 0.3))
        level = float(rng.uniform(0.04, 0.075)) * top
        per = level / (n * (1.0 + r) / 2.0)
        reach = float(rng.uniform(0.04, 0.08)) * stroke_mm
        g.update(crossings=float(n), residual_share=r, crossing_n=per, crossing_k_n_mm=per / reach)
        g.update(ofc_alpha=rng.uniform(0.12, 0.22), threshold_spread=rng.uniform(0.2, 0.45))
        g["ofc_seed"] = float(rng.integers(0, 2**31))
        return g
    if core == "check_valve_twin":
        return g
    # overcentre_latch: the strut's negative stiffness 1.3-2 x the balance's stiffness at x_c
    x_c = float(rng.uniform(0.35, 0.6)) * stroke_mm
    half = float(rng.uniform(0.05, 0.1)) * stroke_mm  # the push's reach either side of x_c
    offset = float(rng.uniform(20.0, 40.0))
    l0 = math.hypot(offset, half)
    v_c = np.array([0.5])
    for _ in range(40):  # the pressure share holding x_c without the latch
        x_here = static_stroke(v_c, g, {})[0]
        v_c = v_c + 0.5 * (x_c - x_here) / stroke_mm
    k_c = float(stiffness_n_mm(v_c, np.array([x_c]), g)[0])
    k_latch = float(rng.uniform(1.3, 2.0)) * k_c * offset / (l0 - offset)
    g.update(latch_x_mm=x_c, latch_offset_mm=offset, latch_l0_mm=l0, latch_k_n_mm=k_latch)
    g["latch_friction_n"] = float(rng.uniform(0.02, 0.04)) * top
    return g
