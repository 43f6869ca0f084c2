"""Four hysteresis cores for the eleventh (blind9) plant family, unlike the other forty.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm],
``core(u, dt_s, params) -> y``, through the PWM valves (:func:`bench.plants.blind9_rig.muscle_pressure`).
Each is a *drive* ``drive(v, dt_s, params, mods) -> y`` of the muscle's normalised pressure ``v``
[share of peak] in which some effects act (:mod:`bench.plants.blind9_effects`): ``mods`` may hold
``"dv"`` (an effective pressure added [share of peak]), ``"f_ext"`` (a force [N] added to what the
muscle pulls against) and ``"rubber"`` (a factor on the bladder's elastic resistance).

The muscle (:func:`static_stroke`) is a Chou-Hannaford braid with a rubber bladder whose hoop
resistance stiffens with the strain, pulling a weight and a return spring: the force balance is a
quadratic in the strain, solved in closed form. The hysteresis is a force [N] computed along the
frictionless stroke ``x0`` and put back into the force balance (so its width in stroke depends
on the muscle's stiffness at each pressure):

* :func:`nitinol_flag_return`: a superelastic NiTi wire beside the return spring, by the
  *Graesser-Cozzarelli* model (Ozdemir's rate-independent plasticity with a back stress, plus the
  superelastic recovery term on unloading, switched continuously: a flag-shaped loop). A
  differential model whose rate depends on its own output, not a play sum.
* :func:`jamming_sleeve`: a sleeve of granular fill around the muscle, confined by the bladder's
  pressure: an elastic-plastic element whose shear stiffness grows as ``N^(1/3)`` (Hertz-Mindlin),
  whose yield force is Mohr-Coulomb ``mu N`` with a friction ``mu`` set by the fill's packing,
  and the packing relaxes with plastic slip towards its *critical state* at the confinement (a
  state-dependent dilatancy memory; minor loops not congruent).
* :func:`mullins_bladder`: the bladder's rubber *stress-softens* (Mullins effect, the
  Ogden-Roxburgh damage function of the strain energy below its running maximum: a max-memory)
  on a braid whose crossings slide with Coulomb friction that grows with the pressure (a
  Jenkins element).
* :func:`breakaway_crossings`: an Iwan set of Jenkins elements at the braid's crossings with
  *static friction above kinetic* (each element sticks until its breakaway force, then slides at
  a lower kinetic force until the motion reverses): a loop with a breakaway bump after each
  reversal (a non-convex envelope), rate-independent.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind9_rig import draw_rig, muscle_pressure

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2
IWAN_ELEMENTS = 8
GC_STEP = 0.01  # largest strain step [Y/E] of one Graesser-Cozzarelli sub-step


class Drive(Protocol):
    def __call__(self, v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array: ...


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float]) -> Array: ...


def static_stroke(v: Array, p: dict[str, float], f_ext: Array | None = None, rubber: Array | None = None) -> Array:
    """Contraction [mm] where ``P A0 (a (1 - e)^2 - b) - g B (e / e_t)(1 + c e / e_t) / (1 + c) = W
    + F + k L0 e`` (``P = (v - g v_c) peak``: the pressure beyond what the bladder takes to inflate
    onto the braid, ``v_c`` = ``contact_share``; ``B`` the bladder's resistance at the top strain
    ``e_t``; ``g`` = ``rubber``, the bladder's modulus factor; ``F`` = ``f_ext`` [N]): the smaller root
    of the quadratic in ``e``; 0 below lift-off, the braid's free contraction at most."""
    g = np.ones_like(v) if rubber is None else rubber
    pa = BAR_N_MM2 * p["area_mm2"] * p["peak"] * np.clip(v - g * p["contact_share"], 0.0, None)
    a, b, length = p["braid_a"], p["braid_b"], p["length_mm"]
    f = np.zeros_like(pa) if f_ext is None else f_ext
    et, c = p["top_strain"], p["bladder_stiffening"]
    rb = g * p["bladder_n"] / (1.0 + c)
    qa = pa * a - rb * c / (et * et)
    qb = -2.0 * pa * a - rb / et - p["k_spring_n_mm"] * length
    qc = pa * (a - b) - p["weight_n"] - f
    disc = np.sqrt(np.clip(qb * qb - 4.0 * qa * qc, 0.0, None))
    e = 2.0 * qc / (-qb + disc)
    e_free = 1.0 - math.sqrt(b / a)
    return np.asarray(np.clip(e, 0.0, e_free) * length, dtype=np.float64)


def stiffness_n_mm(v: Array, x: Array, p: dict[str, float]) -> Array:
    """The slope [N/mm] of the force balance at ``(v, x)``: how hard a force must push to move the
    stroke (the muscle's and the return spring's stiffness together)."""
    pa = BAR_N_MM2 * p["area_mm2"] * p["peak"] * np.clip(v - p["contact_share"], 0.0, None)
    e, et, c, length = x / p["length_mm"], p["top_strain"], p["bladder_stiffening"], p["length_mm"]
    braid = 2.0 * pa * p["braid_a"] * (1.0 - e)
    bladder = p["bladder_n"] * (1.0 + 2.0 * c * e / et) / ((1.0 + c) * et)
    return np.asarray((braid + bladder) / length + p["k_spring_n_mm"], dtype=np.float64)


def _mods(v: Array, mods: dict[str, Array]) -> tuple[Array, Array, Array]:
    dv = mods.get("dv")
    f_ext = mods.get("f_ext")
    rubber = mods.get("rubber")
    return (
        np.asarray(v if dv is None else v + dv, dtype=np.float64),
        np.zeros_like(v) if f_ext is None else f_ext,
        np.ones_like(v) if rubber is None else rubber,
    )


# ---- superelastic NiTi return wire (Graesser-Cozzarelli) ----------------------------------------


def graesser_cozzarelli(strain: Array, p: dict[str, float]) -> Array:
    """Stress [units of the yield stress Y] of a superelastic wire at the strain [units of Y / E]:
    ``d s = d e - |d e| |s - b|^(n - 1) (s - b)``, back stress ``b = alpha (e_in + r)``, ``e_in = e -
    s``, where the superelastic recovery ``r`` moves towards ``f_T |e_in|^c erf(a e)`` while
    unloading (``e de < 0``) and towards 0 while loading, by ``|de| / gc_switch`` of the way (the
    model's switch, made continuous in the strain travelled so that the stress never overshoots
    its surface); sub-stepped (at most :data:`GC_STEP` per step), from rest (``s = 0``)."""
    alpha, n, f_t, c_exp, a_erf = (
        p["gc_alpha"],
        p["gc_sharpness"],
        p["gc_recovery"],
        p["gc_recovery_power"],
        p["gc_erf"],
    )
    switch = p["gc_switch"]
    out = np.empty(strain.size)
    s, r, prev = 0.0, 0.0, float(strain[0])
    for i, e_new in enumerate(strain.tolist()):
        de_total = e_new - prev
        if de_total != 0.0:
            steps = max(1, int(math.ceil(abs(de_total) / GC_STEP)))
            de = de_total / steps
            e = prev
            for _ in range(steps):
                e_in = e - s
                target = f_t * abs(e_in) ** c_exp * math.erf(a_erf * e) if e * de < 0.0 else 0.0
                r += (target - r) * min(1.0, abs(de) / switch)
                over = s - alpha * (e_in + r)
                s += de - abs(de) * abs(over) ** (n - 1.0) * over
                e += de
        out[i] = s
        prev = e_new
    return out


def nitinol_flag_return(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] with the NiTi wire's force ``F_w s`` put back into the force balance; the
    wire is prestrained ``e_pre`` and stretched by ``e_span`` [Y / E] over the stroke."""
    ve, f_ext, rubber = _mods(v, mods)
    x0 = static_stroke(ve, p, f_ext, rubber)
    strain = p["wire_prestrain"] + p["wire_span"] * x0 / p["stroke_mm"]
    force = p["wire_force_n"] * graesser_cozzarelli(strain, p)
    return static_stroke(ve, p, f_ext + force, rubber)


# ---- granular jamming sleeve (Mohr-Coulomb, critical-state packing) -------------------------------


def jamming_force(x0: Array, v: Array, p: dict[str, float]) -> Array:
    """The sleeve's shear force [N] along the stroke ``x0`` [mm] at the confinement ``N = n0 + v``:
    elastic at ``k (N / (n0 + 1))^(1/3)`` until ``|F| = mu N F_j``, then sliding; ``mu = mu_c +
    d (phi - phi_c(N))``, and the packing ``phi`` relaxes with the slip towards ``phi_c(N) =
    lam log(N / (n0 + 1))`` as ``exp(-slip / s_c)`` (it starts at ``phi_0``)."""
    n0, k0, fj = p["jam_floor"], p["jam_stiffness_n_mm"], p["jam_force_n"]
    mu_c, dil, lam, s_c = p["jam_mu_c"], p["jam_dilatancy"], p["jam_lambda"], p["jam_slip_mm"]
    out = np.empty(x0.size)
    force, phi, prev = 0.0, p["jam_phi0"], float(x0[0])
    for i, (xi, vi) in enumerate(zip(x0.tolist(), v.tolist())):
        normal = n0 + max(vi, 0.0)
        rel = normal / (n0 + 1.0)
        force += k0 * rel ** (1.0 / 3.0) * (xi - prev)
        phi_c = lam * math.log(rel)
        limit = max(mu_c + dil * (phi - phi_c), 0.05) * normal * fj
        if abs(force) > limit:
            slip = (abs(force) - limit) / (k0 * rel ** (1.0 / 3.0))
            phi = phi_c + (phi - phi_c) * math.exp(-slip / s_c)
            limit = max(mu_c + dil * (phi - phi_c), 0.05) * normal * fj
            force = math.copysign(limit, force)
        out[i] = force
        prev = xi
    return out


def jamming_sleeve(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] with the sleeve's shear force put back into the force balance."""
    ve, f_ext, rubber = _mods(v, mods)
    x0 = static_stroke(ve, p, f_ext, rubber)
    return static_stroke(ve, p, f_ext + jamming_force(x0, ve, p), rubber)


# ---- Mullins-softened bladder on a Coulomb braid ----------------------------------------------------


def ogden_roxburgh_eta(energy: Array, p: dict[str, float]) -> Array:
    """The Ogden-Roxburgh softening factor ``1 - erf((W_max - W) / (m + beta W_max)) / r`` of the
    strain energy ``W`` (share of the top's) below its running maximum ``W_max``."""
    w_max = np.maximum.accumulate(energy)
    arg = (w_max - energy) / (p["or_m"] + p["or_beta"] * w_max)
    erf = np.vectorize(math.erf, otypes=[np.float64])
    return np.asarray(1.0 - erf(arg) / p["or_r"], dtype=np.float64)


def jenkins_force(x0: Array, v: Array, p: dict[str, float], force_key: str, slide_key: str) -> Array:
    """A Jenkins element's force [N] along ``x0`` [mm]: a spring of ``F / delta`` that slides at
    ``F (0.3 + 0.7 v)`` (the crossings' normal force grows with the pressure), ``F`` = ``p[force_key]``
    [N], ``delta`` = ``p[slide_key]`` [mm]; from rest."""
    f_top, k = p[force_key], p[force_key] / p[slide_key]
    out = np.empty(x0.size)
    force, prev = 0.0, float(x0[0])
    for i, (xi, vi) in enumerate(zip(x0.tolist(), v.tolist())):
        limit = f_top * (0.3 + 0.7 * min(max(vi, 0.0), 1.2))
        force = min(max(force + k * (xi - prev), -limit), limit)
        out[i] = force
        prev = xi
    return out


def mullins_bladder(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm]: the bladder's resistance times the Ogden-Roxburgh factor of its energy
    (``(x0 / stroke)^2``), the braid's friction put back into the force balance."""
    ve, f_ext, rubber = _mods(v, mods)
    x0 = static_stroke(ve, p, f_ext, rubber)
    eta = ogden_roxburgh_eta((x0 / p["stroke_mm"]) ** 2, p)
    soft = rubber * eta
    x1 = static_stroke(ve, p, f_ext, soft)
    return static_stroke(ve, p, f_ext + jenkins_force(x1, ve, p, "braid_friction_n", "braid_slide_mm"), soft)


# ---- breakaway (static above kinetic) Iwan crossings -------------------------------------------------


def breakaway_force(x0: Array, p: dict[str, float]) -> Array:
    """The Iwan set's force [N] along ``x0`` [mm]: element ``j`` (breakaway ``F_s q_j``, ``q_j`` the
    mid-quantiles of a triangular spread, spring ``F_s q_j / delta_j``, ``delta_j`` spread over
    ``delta_min..delta_max``) sticks until its breakaway force, then slides at ``kappa`` x it in the
    direction of travel until the motion reverses; from rest."""
    m = IWAN_ELEMENTS
    fs_total, kappa = p["breakaway_n"], p["kinetic_ratio"]
    quant = [(j + 0.5) / m for j in range(m)]
    weights = [q * (2.0 - q) for q in quant]
    total = sum(weights)
    fs = [fs_total * w / total for w in weights]
    deltas = [p["slide_min_mm"] + (p["slide_max_mm"] - p["slide_min_mm"]) * q for q in quant]
    ks = [f / d for f, d in zip(fs, deltas)]
    force = [0.0] * m
    sliding = [0.0] * m  # +1 / -1 while sliding that way, 0 while stuck
    out = np.empty(x0.size)
    prev = float(x0[0])
    for i, xi in enumerate(x0.tolist()):
        dx = xi - prev
        if dx != 0.0:
            d = 1.0 if dx > 0.0 else -1.0
            for j in range(m):
                if sliding[j] == d:
                    continue  # keeps sliding at the kinetic force
                sliding[j] = 0.0
                fj = force[j] + ks[j] * dx
                if abs(fj) > fs[j]:
                    fj = math.copysign(kappa * fs[j], fj)
                    sliding[j] = d
                force[j] = fj
        out[i] = sum(force)
        prev = xi
    return out


def breakaway_crossings(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Contraction [mm] with the crossings' force put back into the force balance."""
    ve, f_ext, rubber = _mods(v, mods)
    x0 = static_stroke(ve, p, f_ext, rubber)
    return static_stroke(ve, p, f_ext + breakaway_force(x0, p), rubber)


BLIND9_DRIVES: dict[str, Drive] = {
    "nitinol_flag_return": nitinol_flag_return,
    "jamming_sleeve": jamming_sleeve,
    "mullins_bladder": mullins_bladder,
    "breakaway_crossings": breakaway_crossings,
}


def normalised_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The muscle's pressure [share of peak] for the set pressure ``u`` [bar]."""
    return np.asarray(muscle_pressure(u, dt_s, p) / p["peak"], dtype=np.float64)


def _core(name: str) -> Core:
    drive = BLIND9_DRIVES[name]

    def core(u: Array, dt_s: float, p: dict[str, float]) -> Array:
        return drive(normalised_pressure(u, dt_s, p), dt_s, p, {})

    core.__name__ = name
    core.__doc__ = f"Contraction [mm] of the {name} core for the set pressure ``u`` [bar] (no effect)."
    return core


BLIND9_CORES: dict[str, Core] = {name: _core(name) for name in BLIND9_DRIVES}


def _draw_muscle(rng: np.random.Generator, g: dict[str, float], stroke: float) -> None:
    """A Chou-Hannaford braid (20-28 deg, 10-16 mm, 150-350 mm) with a bladder taking 4-10 % of
    the peak to inflate onto the braid and 10-20 % of the top force (stiffening 0.3-1.5), a weight
    of 5-15 % of it and a spring set so that the frictionless stroke at the peak is ``stroke`` (at
    most 60 % of the braid's free contraction)."""
    angle = math.radians(float(rng.uniform(20.0, 28.0)))
    d0, length = float(rng.uniform(10.0, 16.0)), float(rng.uniform(150.0, 350.0))
    a, b = 3.0 / math.tan(angle) ** 2, 1.0 / math.sin(angle) ** 2
    e = min(stroke / length, 0.6 * (1.0 - math.sqrt(b / a)))
    area = math.pi * d0 * d0 / 4.0
    contact = float(rng.uniform(0.04, 0.1))
    braid_top = BAR_N_MM2 * area * g["peak"] * (1.0 - contact) * (a * (1.0 - e) ** 2 - b)
    bladder = float(rng.uniform(0.1, 0.2)) * braid_top
    top = braid_top - bladder
    weight = float(rng.uniform(0.05, 0.15)) * top
    k = (top - weight) / (e * length)
    g.update(braid_angle_rad=angle, diameter_mm=d0, length_mm=length, braid_a=a, braid_b=b, area_mm2=area)
    g.update(top_strain=e, stroke_mm=e * length, bladder_n=bladder, bladder_stiffening=rng.uniform(0.3, 1.5))
    g.update(weight_n=weight, k_spring_n_mm=k, top_force_n=top, contact_share=contact)


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke ~14-36 mm, a loop
    3-20 % of the stroke wide), its rig's constants included."""
    stroke = float(rng.uniform(14.0, 36.0))
    g = draw_rig(rng, peak)
    _draw_muscle(rng, g, stroke)
    top = g["top_force_n"]
    if core == "nitinol_flag_return":
        alpha, power = float(rng.uniform(0.05, 0.15)), float(rng.uniform(0.3, 0.6))
        g.update(wire_prestrain=rng.uniform(0.2, 0.6), wire_span=rng.uniform(3.0, 5.0))
        top_strain = g["wire_prestrain"] + g["wire_span"]
        inelastic = top_strain - (1.0 + alpha * top_strain) / (1.0 + alpha)  # on the loading plateau
        # the recovery sized so that the unloading plateau lies 0.5-0.9 Y below the loading one, in tension
        recovery = float(rng.uniform(1.1, 1.5)) / (alpha * inelastic**power)
        g.update(gc_alpha=alpha, gc_sharpness=rng.uniform(2.0, 4.0), gc_recovery=recovery, gc_recovery_power=power)
        g.update(gc_erf=rng.uniform(50.0, 200.0), gc_switch=rng.uniform(0.1, 0.3))
        g.update(wire_force_n=rng.uniform(0.1, 0.16) * top)
        return g
    if core == "jamming_sleeve":
        g.update(jam_floor=rng.uniform(0.1, 0.25), jam_force_n=rng.uniform(0.06, 0.1) * top)
        g.update(jam_stiffness_n_mm=g["jam_force_n"] / (rng.uniform(0.01, 0.03) * g["stroke_mm"]))
        g.update(
            jam_mu_c=rng.uniform(0.5, 0.7), jam_dilatancy=rng.uniform(1.0, 3.0), jam_lambda=rng.uniform(0.03, 0.08)
        )
        g.update(jam_slip_mm=rng.uniform(0.005, 0.02) * g["stroke_mm"], jam_phi0=rng.uniform(-0.1, 0.1))
        return g
    if core == "mullins_bladder":
        g.update(or_r=rng.uniform(2.0, 4.0), or_m=rng.uniform(0.05, 0.2), or_beta=rng.uniform(0.05, 0.2))
        g.update(
            braid_friction_n=rng.uniform(0.05, 0.09) * top, braid_slide_mm=rng.uniform(0.01, 0.03) * g["stroke_mm"]
        )
        return g
    if core == "breakaway_crossings":
        g.update(breakaway_n=rng.uniform(0.05, 0.085) * top, kinetic_ratio=rng.uniform(0.6, 0.85))
        g.update(slide_min_mm=rng.uniform(0.003, 0.01) * g["stroke_mm"])
        g.update(slide_max_mm=g["slide_min_mm"] + rng.uniform(0.03, 0.08) * g["stroke_mm"])
        return g
    raise KeyError(f"unknown blind9 core {core!r}; known: {', '.join(BLIND9_CORES)}")
