"""Four hysteresis cores for the thirteenth (blind11) plant family, unlike the other forty-eight.

Every core maps a set pressure ``u`` [bar gauge, 0..peak] to a payload stroke ``y`` [mm],
``core(u, dt_s, params) -> y``, through the regulator and the line
(:func:`bench.plants.blind11_rig.muscle_pressure`). Each is a *drive* ``drive(v, dt_s, params,
mods) -> y`` of the muscle's normalised pressure ``v`` [share of peak] in which some effects act
(:mod:`bench.plants.blind11_effects`): ``mods`` may hold ``"dv"`` (a pressure share added to what
the muscle holds), ``"lift"`` (a share added to its lift-off pressure), ``"f_ext"`` (a force [N]
added to what it pulls against) and ``"fibre"`` (a factor on the braid fibres' compliance).

The muscle (:func:`muscle_strain`) is a Chou-Hannaford braid whose fibres *stretch* under the
pressure (Kothera's extensible braid: the fibres lengthen by ``lambda = 1 + c_f v``, 1.5-4 % at
the peak, so the braid's ``a (1 - e)^2 - b`` becomes ``a (1 - e)^2 - b lambda^2``), with a bladder
that takes a lift-off pressure (3-8 % of the peak) and resists linearly, pulling a weight and a
return element. The balance is a
quadratic in the strain, solved in closed form (vectorised). The hysteresis, and what makes each
core new against the other families' cores:

* :func:`runin_crossings`: the braid's crossings as a Prandtl-Ishlinskii set of plays in the
  pressure whose *density runs in*: each play's radius wears down with the slip it has made
  (Archard) from 1 + ``runin_gain`` times its run-in size, and part of the wear is undone every
  time the muscle is vented below its lift-off (the bladder lets go of the braid and the crossings
  re-seat). No other core's hysteresis changes with its own history: here the loop after a vent
  is wider and narrows over the next cycles.
* :func:`wrapped_tiedown`: the payload's return spring is tied down to the frame by an elastic
  textile *strap wrapped 2-3 turns around a post* (a round-turn tie-down): the strap grips the post
  by distributed capstan friction (``|dT / dphi| <= mu T``) and stretches elastically where it
  slips, so the return force relaxes with a *memory stored as the strap's tension profile* (fronts
  entering from the loaded end with the critical gradient in log-tension, Bean's critical state;
  nested fronts, the deeper ones wiped out as a new one passes them; a branch leaves a reversal
  with no give at all). The only core whose memory is a field, solved with the muscle's and the
  payload's balance each sample.
* :func:`contact_births`: the bladder touches the braid at *Greenwood-Williamson* asperities (six
  height classes) that come into contact one after another as the pressure rises (onsets from the
  lift-off to 90 % of the peak, denser at low pressure) and
  leave as it falls: each contact is a Mindlin element whose normal load grows as ``(v -
  v_i)^(3/2)`` and tangential stiffness as ``(v - v_i)^(1/2)`` and is *born unloaded wherever the
  stroke is when it touches*, so the friction's anchors record the strokes at which the contacts
  formed, and contacts die as the pressure falls (their force fading with their load). The set of
  elements changes with the input; the friction is solved with the force balance each sample.
* :func:`wire_rope_return`: the return element is a *wire-rope isolator* (loops of stranded steel
  cable whose strands rub) following the *Menegotto-Pinto* law: smooth branches from each
  reversal along the isolator's elastic stiffness towards the kinematic-hardening asymptote
  opposite, their curvature ``R = R0 - a1 xi / (a2 + xi)`` rounding off the more the previous
  excursion went past the asymptotes' intersection (a Bauschinger effect). Not Masing, no
  return-point memory, no play or relay set; the stroke is solved from the force balance with the
  isolator's branch each sample.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind11_rig import draw_rig, muscle_pressure

Array = NDArray[np.float64]
BAR_N_MM2 = 0.1  # 1 bar = 0.1 N/mm^2
RUNIN_PLAYS = 8
CONTACTS = 6
NEWTON_STEPS = 6


class Drive(Protocol):
    def __call__(self, v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array: ...


class Core(Protocol):
    def __call__(self, u: Array, dt_s: float, p: dict[str, float]) -> Array: ...


# ---- the muscle: extensible Chou-Hannaford braid -------------------------------------------------------


def _mod(v: Array, mods: dict[str, Array], key: str, default: float) -> Array:
    m = mods.get(key)
    return np.full_like(v, default) if m is None else np.asarray(m, dtype=np.float64)


def pull_coefficients(v: Array, p: dict[str, float], mods: dict[str, Array]) -> tuple[Array, Array, Array]:
    """Per sample: the muscle's total pressure share ``v + dv``, and ``c2``, ``c0`` [N] of its pull
    ``c2 (1 - e)^2 - c0`` at strain ``e``: ``c2 = Q v' a``, ``c0 = Q v' b lambda^2`` with ``v'`` the
    share past lift-off (``lift_share + lift``), ``Q`` the force of the whole range on the rest area
    and ``lambda = 1 + c_f fibre v`` the fibres' stretch."""
    vt = np.asarray(v, dtype=np.float64) + _mod(v, mods, "dv", 0.0)
    beyond = np.clip(vt - p["lift_share"] - _mod(v, mods, "lift", 0.0), 0.0, None)
    lam = 1.0 + p["fibre_compliance"] * _mod(v, mods, "fibre", 1.0) * np.clip(vt, 0.0, None)
    q = BAR_N_MM2 * p["area_mm2"] * p["peak"] * beyond
    return vt, q * p["braid_a"], q * p["braid_b"] * lam * lam


def muscle_strain(c2: Array | float, c0: Array | float, k1: float, hold: Array | float) -> Array:
    """The strain where ``c2 (1 - e)^2 - c0 = hold + k1 e`` (``k1`` [N per unit strain] the linear
    resistance, ``hold`` [N] the rest): with ``z = 1 - e``, ``c2 z^2 + k1 z - s = 0``, ``s = c0 + hold
    + k1``, taken as ``z = 2 s / (k1 + sqrt(k1^2 + 4 c2 s))`` (no cancellation); 0 where the muscle
    cannot lift (it rests at full length)."""
    s = np.asarray(c0, dtype=np.float64) + np.asarray(hold, dtype=np.float64) + k1
    root = np.sqrt(k1 * k1 + 4.0 * np.asarray(c2, dtype=np.float64) * np.clip(s, 0.0, None))
    z = 2.0 * s / (k1 + root)
    return np.asarray(np.clip(1.0 - z, 0.0, None), dtype=np.float64)


def _strain1(c2: float, c0: float, k1: float, hold: float) -> float:
    """:func:`muscle_strain` for one sample (scalar, for the per-sample loops)."""
    s = c0 + hold + k1
    z = 2.0 * s / (k1 + math.sqrt(k1 * k1 + 4.0 * c2 * max(s, 0.0)))
    return max(1.0 - z, 0.0)


def spring_k1(p: dict[str, float]) -> float:
    """The return spring's and the bladder's linear resistance [N per unit strain]."""
    return p["k_spring_n_mm"] * p["length_mm"] + p["bladder_n"]


def static_stroke(v: Array, p: dict[str, float], mods: dict[str, Array], f: Array | float = 0.0) -> Array:
    """The frictionless stroke [mm] at pressure share ``v`` with the linear return spring (the force
    ``f`` [N] and ``mods["f_ext"]`` added to the weight)."""
    _, c2, c0 = pull_coefficients(v, p, mods)
    hold = p["weight_n"] + _mod(v, mods, "f_ext", 0.0) + np.asarray(f, dtype=np.float64)
    return np.asarray(muscle_strain(c2, c0, spring_k1(p), hold) * p["length_mm"], dtype=np.float64)


def balance_stiffness(v: Array, x: Array, p: dict[str, float]) -> Array:
    """The balance's stiffness [N/mm] at ``(v, x)`` with the linear return spring: how much the
    pull's surplus falls per mm of stroke, ``(2 c2 (1 - e) + k1) / L`` (at least 1e-6)."""
    _, c2, _ = pull_coefficients(v, p, {})
    e = np.asarray(x, dtype=np.float64) / p["length_mm"]
    return np.asarray(np.clip((2.0 * c2 * (1.0 - e) + spring_k1(p)) / p["length_mm"], 1e-6, None))


# ---- run-in crossings ------------------------------------------------------------------------------------


def runin_pressure(v: Array, p: dict[str, float]) -> Array:
    """The pressure share [of peak] the muscle's balance gets after the crossings' friction: ``v -
    sum_j w_j (v - a_j)``, ``a_j`` play ``j``'s output (``|v - a_j| <= r_j``); ``r_j = r_inf_j (1 + g
    exp(-s_j / s_c))``, ``s_j`` the slip play ``j`` has made; each time ``v`` falls below the lift-off
    share, ``s_j`` keeps ``1 - reseat`` of itself. From rest on ``v[0]``, unworn."""
    n = RUNIN_PLAYS
    r_inf = [p[f"play_r{j}"] for j in range(n)]
    w = [p[f"play_w{j}"] for j in range(n)]
    gain, s_c, keep, lift = p["runin_gain"], p["runin_slip"], 1.0 - p["reseat_share"], p["lift_share"]
    v0 = float(v[0]) if v.size else 0.0
    a = [v0] * n
    s = [0.0] * n
    r = [ri * (1.0 + gain) for ri in r_inf]
    held = sum(w) * v0  # sum_j w_j a_j, kept up to date as the plays move
    keep_v = 1.0 - sum(w)
    vented = v0 < lift
    out = np.empty(v.size)
    for i, vi in enumerate(v.tolist()):
        if vi < lift:
            if not vented:
                vented = True
                s = [sj * keep for sj in s]
                r = [ri * (1.0 + gain * math.exp(-sj / s_c)) for ri, sj in zip(r_inf, s)]
        else:
            vented = False
        for j in range(n):
            aj, rj = a[j], r[j]
            if aj < vi - rj:
                s[j] += vi - rj - aj
                rj = r_inf[j] * (1.0 + gain * math.exp(-s[j] / s_c))
                r[j] = rj
                held += w[j] * (vi - rj - aj)
                a[j] = vi - rj
            elif aj > vi + rj:
                s[j] += aj - vi - rj
                rj = r_inf[j] * (1.0 + gain * math.exp(-s[j] / s_c))
                r[j] = rj
                held += w[j] * (vi + rj - aj)
                a[j] = vi + rj
        out[i] = keep_v * vi + held
    return out


def runin_crossings(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Stroke [mm] of the balance at the pressure share left after the crossings' friction (the
    plays see the muscle's whole pressure, ``dv`` included)."""
    vt = np.asarray(v, dtype=np.float64) + _mod(v, mods, "dv", 0.0)
    rest = {k: m for k, m in mods.items() if k != "dv"}
    return static_stroke(runin_pressure(vt, p), p, rest)


# ---- wrapped anchor strap --------------------------------------------------------------------------------


class StrapProfile:
    """The tension profile of a strap wrapped on a post, as nested capstan fronts in log-tension.

    ``y(phi) = ln T`` along the wrap angle ``phi`` [rad] from the loaded end. A front entering from
    the end has ``dy/dphi = -d mu`` (``d = +1`` while the end's tension rises); the front of a past
    reversal value ``m_j`` meets the next older one halfway in log-tension (at the tension
    ``sqrt(M_j M_(j-1))``), or the untouched strap ``T0`` at the full distance. The end's yield [mm]
    is ``R / EA`` times the integral of ``T - T0`` over the wrap, ``scale_mm_per_n`` x [N rad]. Each
    stored level keeps its value ``m``, direction ``d``, tension ``M``, end depth ``D`` [rad], tension
    there ``E`` and the integral of the levels below it ``C``, so an evaluation costs O(1)."""

    def __init__(self, t0: float, mu: float, scale_mm_per_n: float) -> None:
        self.y0, self.t0, self.mu, self.scale = math.log(t0), t0, mu, scale_mm_per_n
        self.levels: list[tuple[float, float, float, float, float, float]] = []  # (m, d, M, D, E, C)
        self.c, self.tension = self.y0, t0  # the loaded end's log-tension and tension now
        self.dir = 1.0

    def _kept(self, c: float, d: float) -> int:
        """How many stored levels are left once a front at ``c`` (direction ``d``) has wiped out
        those it passes (two at a time; the oldest alone once the front reaches the untouched strap)."""
        lv = self.levels
        k = len(lv)
        while k >= 2 and d * (c - lv[k - 2][0]) >= 0.0:
            k -= 2
        if k == 1 and d * (c - (2.0 * self.y0 - lv[0][0])) >= 0.0:
            k = 0
        return k

    def _integral(self, tension: float, c: float, d: float, k: int) -> tuple[float, float]:
        """The integral [N rad] of ``T - T0`` over the wrap with the end at ``tension`` (``c`` its log)
        over ``k`` kept levels, and its derivative in ``c``."""
        mu, t0 = self.mu, self.t0
        if k == 0:
            here = d * (c - self.y0) / mu
            return (tension - t0) / (d * mu) - t0 * here, (tension - t0) / (d * mu)
        m, _, big_m, depth, e_end, below = self.levels[k - 1]
        here = d * (c - m) / (2.0 * mu)
        meet = math.sqrt(tension * big_m)
        return (tension - 2.0 * meet + e_end) / (d * mu) - t0 * depth + below, (tension - meet) / (d * mu)

    def yield_mm(self, tension: float) -> tuple[float, float]:
        """The end's yield [mm] and its derivative [mm/N] if its tension moved on (in the current
        direction) to ``tension``, without storing it."""
        c = math.log(tension)
        d, lv = self.dir, self.levels
        k = len(lv)
        if k >= 2 and d * (c - lv[k - 2][0]) >= 0.0 or k == 1:  # a level may be wiped out
            k = self._kept(c, d)
        total, slope = self._integral(tension, c, d, k)
        return self.scale * total, self.scale * slope / tension

    def turn(self) -> None:
        """The end's tension reverses here: store it as a level and turn the direction."""
        c, d, mu, t0 = self.c, self.dir, self.mu, self.t0
        k = self._kept(c, d)
        del self.levels[k:]
        if k == 0:
            depth, e_end, below = d * (c - self.y0) / mu, t0, 0.0
        else:
            m, dk, big_m, d_top, e_top, c_top = self.levels[k - 1]
            depth, e_end = d * (c - m) / (2.0 * mu), math.sqrt(self.tension * big_m)
            below = c_top + (e_end - e_top) / (dk * mu) - t0 * (d_top - depth)  # the level beneath, now settled
        self.levels.append((c, d, self.tension, depth, e_end, below))
        self.dir = -d

    def move(self, tension: float) -> None:
        """Store the end's new tension (in the current direction), wiping out passed levels."""
        c = math.log(tension)
        del self.levels[self._kept(c, self.dir) :]
        self.c, self.tension = c, tension


def wrapped_tiedown(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """The payload's stroke [mm] ``y = L e``, the muscle's contraction at what it pulls against: the
    weight, ``f_ext`` and the return spring's force ``S = S0 + k (y - u(S))``, ``u`` the tie-down's
    yield (the wrap's, :class:`StrapProfile`, and the free strap's ``(S - S0) l / EA``). ``S`` is
    solved each sample by Newton with a bracket: the previous sample was balanced, so the surplus at
    the old force under the new pressure (the strap unchanged) gives the direction first (a reversal
    is stored before the new front starts) and the first step. From rest, the strap evenly at the
    spring's preload ``S0``."""
    _, c2a, c0a = pull_coefficients(v, p, mods)
    f_ext = _mod(v, mods, "f_ext", 0.0)
    length, k, w, bladder = p["length_mm"], p["k_spring_n_mm"], p["weight_n"], p["bladder_n"]
    free, s0 = p["strap_free_mm_per_n"], p["spring_preload_n"]
    strap = StrapProfile(s0, p["strap_mu"], p["strap_mm_per_n"])
    tol = 1e-9 * s0
    force, u, du = s0, 0.0, 0.0  # the spring's force [N], the strap's yield [mm] and its slope [mm/N]
    out = np.empty(v.size)
    for i, (c2, c0, fe) in enumerate(zip(c2a.tolist(), c0a.tolist(), f_ext.tolist())):
        hold = w + fe
        e = _strain1(c2, c0, bladder, hold + force)
        y = length * e
        g = force - s0 - k * (y - u - free * (force - s0))
        if abs(g) > tol:
            d = 1.0 if g < 0.0 else -1.0  # the root lies above the present force if g < 0
            if d != strap.dir:
                strap.turn()
                du = 0.0  # the new front has no depth yet: the strap gives nothing at first
            lo, hi = (force, math.inf) if d > 0.0 else (1e-6 * s0, force)
            sn = force
            for _ in range(NEWTON_STEPS):
                if g < 0.0:
                    lo = sn
                else:
                    hi = sn
                de = 1.0 / (2.0 * c2 * (1.0 - e) + bladder) if e > 0.0 else 0.0
                step = sn - g / (1.0 + k * (length * de + du + free))
                sn = step if lo < step < hi else (0.5 * (lo + hi) if math.isfinite(hi) else 2.0 * lo)
                e = _strain1(c2, c0, bladder, hold + sn)
                y = length * e
                u, du = strap.yield_mm(sn)
                g = sn - s0 - k * (y - u - free * (sn - s0))
                if abs(g) < tol:
                    break
            force = sn
            strap.move(force)
        out[i] = y
    return out


# ---- Greenwood-Williamson contacts born during the stroke ---------------------------------------------


def contact_friction(v: Array, p: dict[str, float], mods: dict[str, Array]) -> tuple[Array, Array]:
    """The contacts' friction force [N] (opposing the contraction when positive) and the stroke
    [mm], solved together: contact ``i`` (onset ``v_i``) has the slip limit ``L_i = L (v - v_i)^1.5``
    and the tangential stiffness ``k_i = k (v - v_i)^0.5``, its force moving by ``k_i dx`` and
    clipped to ``+-L_i`` (so it is born unloaded and fades as it leaves); each sample the stuck
    contacts' stiffness and the slipping ones' limits are put into the balance linearised about the
    stroke at the present friction (tangent stiffness ``K``), and the stroke is then taken from the
    exact balance. From rest."""
    _, c2a, c0a = pull_coefficients(v, p, mods)
    f_ext = _mod(v, mods, "f_ext", 0.0)
    vt = np.clip(np.asarray(v, dtype=np.float64) + _mod(v, mods, "dv", 0.0), 0.0, None)
    onsets = np.array([p[f"onset{j}"] for j in range(CONTACTS)])
    reach = np.clip(np.subtract.outer(vt, onsets), 0.0, None)
    alive = np.searchsorted(onsets, vt, side="left").tolist()  # onsets rise: the live ones lead
    limits = (p["contact_limit_n"] * reach**1.5).tolist()
    stiff = (p["contact_k_n_mm"] * np.sqrt(reach)).tolist()
    k1, length, w = spring_k1(p), p["length_mm"], p["weight_n"]
    f = [0.0] * CONTACTS
    x_prev = 0.0
    out_f, out_x = np.empty(v.size), np.empty(v.size)
    falling = np.concatenate([[False], np.diff(vt) < 0.0]).tolist()
    for i, (c2, c0, fe, n, lim, kk, fall) in enumerate(
        zip(c2a.tolist(), c0a.tolist(), f_ext.tolist(), alive, limits, stiff, falling)
    ):
        if fall:  # the contacts that left (limit 0) drop their force; the others' limits pull theirs in
            fs = [(lim[j] if f[j] > lim[j] else -lim[j] if f[j] < -lim[j] else f[j]) for j in range(n)]
            fs += [0.0] * (CONTACTS - n)
        else:
            fs = f
        if n == 0:  # no contact: the frictionless balance
            f = fs
            x_prev = _strain1(c2, c0, k1, w + fe) * length
            out_f[i], out_x[i] = 0.0, x_prev
            continue
        total = sum(fs)
        e = _strain1(c2, c0, k1, w + fe + total)
        x_free = e * length  # the stroke if no contact's force changed
        if e > 0.0:
            k_bal = (2.0 * c2 * (1.0 - e) + k1) / length
            dx = x_free - x_prev
            seen = (-1.0, 0.0)
            for _ in range(4):  # until the set of slipping contacts stays the same
                k_stuck, shift = 0.0, 0.0
                for j in range(n):
                    fj, lj, kj = fs[j], lim[j], kk[j]
                    trial = fj + kj * dx
                    if trial >= lj:
                        shift += lj - fj
                    elif trial <= -lj:
                        shift -= lj + fj
                    else:
                        k_stuck += kj
                if (k_stuck, shift) == seen:
                    break
                seen = (k_stuck, shift)
                dx = (x_free - x_prev - shift / k_bal) / (1.0 + k_stuck / k_bal)
        else:
            dx = -x_prev  # resting at full length: every contact is dragged back with it
        f = []
        for j in range(n):
            fj, lj = fs[j] + kk[j] * dx, lim[j]
            f.append(lj if fj > lj else -lj if fj < -lj else fj)
        f += [0.0] * (CONTACTS - n)
        total = sum(f)
        x_prev = _strain1(c2, c0, k1, w + fe + total) * length
        out_f[i], out_x[i] = total, x_prev
    return out_f, out_x


def contact_births(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Stroke [mm] with the contacts' friction solved with the force balance."""
    return contact_friction(v, p, mods)[1]


# ---- wire-rope isolator return (Menegotto-Pinto) ------------------------------------------------------


class MenegottoPinto:
    """The isolator's force [N] at the stroke ``x`` [mm] on its present branch.

    Elastic stiffness ``e0`` [N/mm], hardening share ``b``, yield force ``fy`` [N] (the asymptotes
    ``R = b e0 x +- (1 - b) fy``); a branch from the reversal ``(x_r, R_r)`` runs along ``R* = b x* +
    (1 - b) x* / (1 + x*^Rc)^(1/Rc)`` in coordinates scaled from the reversal to the intersection
    ``(x_0, R_0)`` of the elastic line with the opposite asymptote; ``Rc = R0 - a1 xi / (a2 + xi)``,
    ``xi`` the distance (in yield strokes) from ``x_0`` back to the furthest stroke reached that way."""

    def __init__(self, e0: float, b: float, fy: float, r0: float, a1: float, a2: float) -> None:
        self.e0, self.b, self.fy, self.r0, self.a1, self.a2 = e0, b, fy, r0, a1, a2
        self.dy = fy / e0
        self.x_max, self.x_min = 0.0, 0.0
        self.dir = 1.0
        self._branch(0.0, 0.0, first=True)

    def _branch(self, x_r: float, r_r: float, first: bool = False) -> None:
        e0, b, fy, d = self.e0, self.b, self.fy, self.dir
        self.x_r, self.r_r = x_r, r_r
        self.x_0 = (e0 * x_r - r_r + d * (1.0 - b) * fy) / ((1.0 - b) * e0)
        self.r_0 = r_r + e0 * (self.x_0 - x_r)
        far = self.x_max if d > 0.0 else self.x_min
        xi = 0.0 if first else abs(far - self.x_0) / self.dy
        self.rc = self.r0 - self.a1 * xi / (self.a2 + xi)
        span_x = self.x_0 - self.x_r
        self._inv_span = 1.0 / span_x if span_x != 0.0 else 0.0
        self._span_r = self.r_0 - self.r_r
        self._inv_rc, self._tail = 1.0 / self.rc, 1.0 + 1.0 / self.rc

    def force(self, x: float) -> tuple[float, float]:
        """The force [N] and its slope [N/mm] at ``x`` on the present branch (``x`` on its side)."""
        if self._inv_span == 0.0:  # on the asymptote itself
            return self.r_r + self.b * self.e0 * (x - self.x_r), self.b * self.e0
        s = (x - self.x_r) * self._inv_span
        if s < 0.0:
            s = 0.0
        b = self.b
        base = 1.0 + s**self.rc
        r = self.r_r + self._span_r * (b * s + (1.0 - b) * s / base**self._inv_rc)
        return r, self._span_r * self._inv_span * (b + (1.0 - b) / base**self._tail)

    def turn(self, x: float) -> None:
        """The stroke reverses at ``x``: a new branch from there towards the other asymptote."""
        r, _ = self.force(x)
        self.dir = -self.dir
        self._branch(x, r)

    def reach(self, x: float) -> None:
        """Record the furthest strokes either way."""
        self.x_max, self.x_min = max(self.x_max, x), min(self.x_min, x)


def wire_rope_return(v: Array, dt_s: float, p: dict[str, float], mods: dict[str, Array]) -> Array:
    """Stroke [mm] where ``c2 (1 - e)^2 - c0 = W + f_ext + B e + R(x)``, ``R`` the isolator's force on
    its branch, by Newton with a bracket: the previous sample was balanced, so the surplus at the old
    stroke under the new pressure (the isolator's force unchanged) gives the direction first (a
    reversal starts a new branch there, leaving along the elastic stiffness) and the first step;
    resting at 0 when the muscle cannot lift the payload off its stop. From rest."""
    _, c2a, c0a = pull_coefficients(v, p, mods)
    f_ext = _mod(v, mods, "f_ext", 0.0)
    length, w, bladder = p["length_mm"], p["weight_n"], p["bladder_n"]
    iso = MenegottoPinto(p["iso_e0_n_mm"], p["iso_b"], p["iso_fy_n"], p["iso_r0"], p["iso_a1"], p["iso_a2"])
    x, r, dr = 0.0, 0.0, p["iso_e0_n_mm"]  # the stroke [mm], the isolator's force [N] and slope [N/mm]
    out = np.empty(v.size)
    for i, (c2, c0, fe) in enumerate(zip(c2a.tolist(), c0a.tolist(), f_ext.tolist())):
        tol = 1e-9 * (w + fe + 1.0)
        e = x / length
        g = c2 * (1.0 - e) ** 2 - c0 - w - fe - bladder * e - r
        d = 1.0 if g > 0.0 else -1.0
        if abs(g) > tol and not (d < 0.0 and x <= 0.0):
            if d != iso.dir:
                iso.turn(x)
                dr = iso.e0
            lo, hi = (x, length) if d > 0.0 else (0.0, x)
            xn = x
            for _ in range(NEWTON_STEPS):
                if g > 0.0:
                    lo = xn
                else:
                    hi = xn
                step = xn + g / ((2.0 * c2 * (1.0 - e) + bladder) / length + dr)
                if step <= 0.0 < hi:  # down to the stop?
                    r, dr = iso.force(0.0)
                    if c2 - c0 - w - fe - r <= 0.0:
                        xn = 0.0
                        break
                xn = step if lo < step < hi else 0.5 * (lo + hi)
                e = xn / length
                r, dr = iso.force(xn)
                g = c2 * (1.0 - e) ** 2 - c0 - w - fe - bladder * e - r
                if abs(g) < tol:
                    break
            x = xn
            iso.reach(x)
        out[i] = x
    return out


BLIND11_DRIVES: dict[str, Drive] = {
    "runin_crossings": runin_crossings,
    "wrapped_tiedown": wrapped_tiedown,
    "contact_births": contact_births,
    "wire_rope_return": wire_rope_return,
}


def normalised_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The muscle's pressure [share of peak] for the set pressure ``u`` [bar]."""
    return np.asarray(muscle_pressure(u, dt_s, p) / p["peak"], dtype=np.float64)


def _core(name: str) -> Core:
    drive = BLIND11_DRIVES[name]

    def core(u: Array, dt_s: float, p: dict[str, float]) -> Array:
        return drive(normalised_pressure(u, dt_s, p), dt_s, p, {})

    core.__name__ = name
    core.__doc__ = f"Stroke [mm] of the {name} core for the set pressure ``u`` [bar] (no effect)."
    return core


BLIND11_CORES: dict[str, Core] = {name: _core(name) for name in BLIND11_DRIVES}


# ---- parameters ------------------------------------------------------------------------------------------


def _draw_muscle(rng: np.random.Generator, g: dict[str, float], stroke: float) -> None:
    """An extensible Chou-Hannaford braid (18-26 deg, 10-18 mm, 150-380 mm, its fibres stretching
    1.5-4 % at the peak) contracting 10-28 % at the peak to ``stroke`` [mm] (moved into that range if
    needed), its bladder taking 3-8 %
    of the peak to lift off and 8-18 % of the top force, a weight of 5-12 % of the rest and a
    linear return spring set so that the frictionless stroke at the peak is ``stroke``."""
    angle = math.radians(float(rng.uniform(18.0, 26.0)))
    a, b = 3.0 / math.tan(angle) ** 2, 1.0 / math.sin(angle) ** 2
    d0 = float(rng.uniform(10.0, 18.0))
    c_f = float(rng.uniform(0.015, 0.04))
    free = 1.0 - math.sqrt(b / a) * (1.0 + c_f)
    length = float(rng.uniform(150.0, 380.0))
    e_top = float(np.clip(stroke / length, 0.10, min(0.28, 0.75 * free)))
    stroke = e_top * length
    area = math.pi * d0 * d0 / 4.0
    lift = float(rng.uniform(0.03, 0.08))
    g.update(braid_angle_rad=angle, braid_a=a, braid_b=b, diameter_mm=d0, area_mm2=area, length_mm=length)
    g.update(fibre_compliance=c_f, lift_share=lift, top_strain=e_top, stroke_mm=stroke)
    top = BAR_N_MM2 * area * g["peak"] * (1.0 - lift) * (a * (1.0 - e_top) ** 2 - b * (1.0 + c_f) ** 2)
    bladder = float(rng.uniform(0.08, 0.18)) * top
    weight = float(rng.uniform(0.05, 0.12)) * (top - bladder)
    g.update(bladder_n=bladder / e_top, weight_n=weight, top_force_n=top)
    g["k_spring_n_mm"] = (top - bladder - weight) / (e_top * length)


def _frictionless_tension_range(g: dict[str, float]) -> float:
    """The return spring's force [N] at the top stroke plus the weight: the tension at the peak."""
    return g["weight_n"] + g["k_spring_n_mm"] * g["stroke_mm"]


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` at supply range ``peak`` [bar] (stroke 15-42 mm), its rig's
    constants included."""
    if core not in BLIND11_DRIVES:
        raise KeyError(f"unknown blind11 core {core!r}; known: {', '.join(BLIND11_DRIVES)}")
    g = draw_rig(rng, peak)
    _draw_muscle(rng, g, float(rng.uniform(16.0, 42.0)))
    top = g["top_force_n"]
    if core == "runin_crossings":
        r_max = float(rng.uniform(0.05, 0.1))
        weights = rng.dirichlet(np.full(RUNIN_PLAYS, 2.0)) * float(rng.uniform(0.45, 0.7))
        for j in range(RUNIN_PLAYS):
            g[f"play_r{j}"] = r_max * ((j + 0.5) / RUNIN_PLAYS) ** 1.2
            g[f"play_w{j}"] = float(weights[j])
        g.update(runin_gain=rng.uniform(0.3, 0.8), runin_slip=rng.uniform(0.3, 0.8))
        g["reseat_share"] = rng.uniform(0.4, 0.8)
        return g
    if core == "wrapped_tiedown":
        # the spring is preloaded to 4-10 % of the top force; the strap's yield at the top force,
        # virgin, is a share of the stroke (sets R / EA); it wraps far enough that no front reaches
        # its tied tail
        s0 = float(rng.uniform(0.04, 0.1)) * top
        s_top = s0 + g["k_spring_n_mm"] * g["stroke_mm"]
        tau = s_top / s0
        share = float(rng.uniform(0.12, 0.25))
        mu = float(rng.uniform(0.25, 0.45))
        virgin = s0 * (tau - 1.0 - math.log(tau)) / mu  # N rad, per unit R / EA
        g.update(spring_preload_n=s0, strap_mu=mu, strap_mm_per_n=share * g["stroke_mm"] / virgin)
        g["strap_turns"] = max(float(rng.uniform(2.0, 3.0)), 1.5 * math.log(2.0 * tau) / (2.0 * math.pi * mu))
        g["strap_free_mm_per_n"] = float(rng.uniform(0.02, 0.06)) * g["stroke_mm"] / (s_top - s0)
        g["weight_n"] = max(g["weight_n"] - s0, 0.3 * g["weight_n"])  # the preload takes part of the weight's role
        g["k_spring_n_mm"] *= 1.0 + share  # so that the payload still reaches about the stroke at the peak
        return g
    if core == "contact_births":
        lift = g["lift_share"]
        q = (np.arange(CONTACTS) + 0.5) / CONTACTS
        for j, qj in enumerate(q.tolist()):
            g[f"onset{j}"] = lift + (0.9 - lift) * qj**1.4
        onsets = np.array([g[f"onset{j}"] for j in range(CONTACTS)])
        level = float(rng.uniform(0.045, 0.08)) * top  # all contacts' limit at the peak
        g["contact_limit_n"] = level / float(np.sum((1.0 - onsets) ** 1.5))
        slip = float(rng.uniform(0.02, 0.05)) * g["stroke_mm"]  # the first contact's slip distance at the peak
        g["contact_k_n_mm"] = g["contact_limit_n"] * (1.0 - lift) / slip
        return g
    # wire_rope_return: the isolator replaces the linear spring (its secant over the stroke about it)
    k_s = g["k_spring_n_mm"]
    b = float(rng.uniform(0.3, 0.55))
    e0 = k_s / b * float(rng.uniform(0.9, 1.1))
    fy = float(rng.uniform(0.025, 0.06)) * top / (1.0 - b)
    r0 = float(rng.uniform(15.0, 20.0))
    g.update(iso_e0_n_mm=e0, iso_b=b, iso_fy_n=fy, iso_r0=r0)
    g.update(iso_a1=r0 - float(rng.uniform(1.5, 3.5)), iso_a2=rng.uniform(0.1, 0.2))  # Rc stays above 1.5
    g["k_spring_n_mm"] = b * e0  # the linear spring the after-core forms use for the balance's stiffness
    return g
