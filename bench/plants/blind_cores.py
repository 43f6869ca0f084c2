"""Four blind hysteresis cores for a pneumatic muscle rig, unlike the tuning and fresh families.

Every core maps an input ``u`` [bar gauge, 0..peak] to a contraction ``y`` [mm] with
``core(u, dt_s, params, hooks) -> y``. :class:`Hooks` carries per-sample arrays through which
the effects of :mod:`bench.plants.blind_effects` act inside the physics:

* ``width``: factor on the hysteresis width (friction level, relay spread, play radii, branch split).
* ``load_kg``: payload [kg] added to the fixed one in the muscle's force balance.
* ``rubber``: factor on the rubber bladder's stiffness opposing contraction.

The muscle statics are the McKibben balance of :func:`muscle_contraction` (Chou-Hannaford with
``kappa = 1``, Tondu-Lopez with ``kappa > 1``) against a payload and a spring.

* :func:`lugre_mckibben`: payload mass on a muscle with a LuGre friction element (Stribeck,
  presliding bristles) and a return spring; second-order mechanics, 2 ms sub-steps.
* :func:`preisach_resonant`: a Preisach plane of crisp relays with a factorised Gaussian x
  log-normal density (exact, through a tabulated Everett function and a wiping-out memory),
  a Tondu-Lopez balance, then a lightly damped second-order stage (5-20 Hz).
* :func:`asym_play_poly`: asymmetric play operators (rising and falling thresholds differ), a
  cubic output map, load sag through a pressure-stiffened muscle, a soft saturation.
* :func:`valve_chamber`: ``u`` is the command of a proportional valve that fills a chamber from
  the supply and vents it to atmosphere; the air heats on filling and cools on venting and
  relaxes to the wall (thermal time constant 1.5-5 s), which moves the pressure; the pressure
  drives scaled-branch (Madelung-rule) hysteresis and a Chou-Hannaford balance.

Plausible parameters are drawn by :func:`bench.plants.blind_family.draw_blind_params`.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import cont2discrete, lfilter

Array = NDArray[np.float64]
G_MS2 = 9.81
BAR_PA = 1e5


@dataclass(frozen=True)
class Hooks:
    """Per-sample modifiers an effect passes into a core (ones / zeros: no effect)."""

    width: Array
    load_kg: Array
    rubber: Array

    @staticmethod
    def neutral(n: int) -> Hooks:
        return Hooks(np.ones(n), np.zeros(n), np.ones(n))


def muscle_contraction(p_bar: Array | float, weight_n: Array | float, k_n: Array | float, g: dict[str, float]) -> Array:
    """Contraction ratio solving ``p A0 (a (1 - kappa e)^2 - b) = W + K e`` (clipped at 0, the end stop).

    ``A0 = pi r0^2`` [m^2], ``a = 3 / tan^2 theta0``, ``b = 1 / sin^2 theta0``; ``W`` [N] payload
    weight, ``K`` [N per unit contraction] the spring plus rubber.
    """
    q = np.maximum(np.asarray(p_bar, dtype=np.float64), 1e-6) * BAR_PA * np.pi * g["r0_m"] ** 2
    a = 3.0 / np.tan(g["theta0"]) ** 2
    b = 1.0 / np.sin(g["theta0"]) ** 2
    kap = g["kappa"]
    kk = np.asarray(k_n, dtype=np.float64) / kap
    s = (-kk + np.sqrt(kk * kk + 4.0 * q * a * (q * b + weight_n + kk))) / (2.0 * q * a)  # s = 1 - kappa e
    return np.maximum((1.0 - s) / kap, 0.0)


def muscle_force(p_bar: float, e: float, g: dict[str, float]) -> float:
    """Chou-Hannaford force [N] at pressure ``p_bar`` and contraction ratio ``e``."""
    s = 1.0 - g["kappa"] * e
    return (
        p_bar
        * BAR_PA
        * np.pi
        * g["r0_m"] ** 2
        * (3.0 * s * s / np.tan(g["theta0"]) ** 2 - 1.0 / np.sin(g["theta0"]) ** 2)
    )


def lugre_mckibben(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """``(m + L) x'' = F(u, x/L0) - (m + L) g - (k_s + k_r rubber) x - F_f`` [N, m, kg].

    LuGre friction ``F_f = s0 z + s1 z' + s2 x'`` with ``z' = x' - s0 |x'| z / gs(x')`` and
    ``gs = width (Fc + (Fs - Fc) exp(-(x'/vs)^2))``; the bristle state relaxes exactly over each
    sub-step. The muscle cannot lengthen past its rest length (end stop at ``x = 0``).
    """
    sub = max(1, int(np.ceil(dt_s / 0.002)))
    h = dt_s / sub
    x, v, z = 0.0, 0.0, 0.0
    s0, s1, s2, vs = p["sigma0"], p["sigma1"], p["sigma2"], p["vs_ms"]
    out = np.empty_like(u)
    prev = float(u[0])
    for i, (ui, wi, li, ri) in enumerate(
        zip(u.tolist(), hooks.width.tolist(), hooks.load_kg.tolist(), hooks.rubber.tolist())
    ):
        mass = p["mass_kg"] + li
        k = p["k_spring"] + p["k_rubber"] * ri
        fc, fs = p["fc_n"] * wi, p["fs_n"] * wi
        du = (ui - prev) / sub
        for s in range(sub):
            pb = prev + du * (s + 1)
            gs = fc + (fs - fc) * math.exp(-((v / vs) ** 2))
            zss = gs / s0 if v >= 0 else -gs / s0
            z_new = zss + (z - zss) * math.exp(-s0 * abs(v) * h / gs)
            zdot = (z_new - z) / h
            z = z_new
            force = muscle_force(pb, x / p["l0_m"], p) - mass * G_MS2 - k * x - s0 * z - s1 * zdot - s2 * v
            v += h * force / mass
            x += h * v
            if x <= 0.0:
                x = 0.0
                v = max(v, 0.0)
        prev = ui
        out[i] = x * 1000.0
    return out


WIDTH_LEVELS = np.geomspace(1.0 / 3.0, 3.0, 9)  # index 4 is the nominal spread


def _everett_tables(p: dict[str, float], n: int = 121) -> Array:
    """Everett function ``E[k, a, b]``: weight of the relays with ``b <= beta <= alpha <= a`` on an
    ``n``-point grid of normalised input, for the relay-spread factor ``WIDTH_LEVELS[k]``.

    Density: Gaussian in the relay midpoint times log-normal in the half spread (median
    ``half * w``); weights are normalised so the nominal plane holds 1.
    """
    grid = np.linspace(0.0, 1.0, n)
    alpha, beta = np.meshgrid(grid, grid, indexing="ij")
    mid, half = 0.5 * (alpha + beta), np.maximum(0.5 * (alpha - beta), 1e-9)
    out = np.empty((WIDTH_LEVELS.size, n, n))
    for k, w in enumerate(WIDTH_LEVELS.tolist()):
        dens = np.exp(
            -0.5 * ((mid - p["mid"]) / p["mid_sd"]) ** 2 - 0.5 * (np.log(half / (w * p["half"])) / p["half_sd"]) ** 2
        )
        dens = np.where(alpha > beta, dens / half, 0.0)
        out[k] = np.cumsum(np.cumsum(dens[:, ::-1], axis=1)[:, ::-1], axis=0)  # sum over b <= beta, alpha <= a
    return out / out[4, -1, 0]


def _everett(table: Array, wpos: Array, a: Array, b: Array) -> Array:
    """Trilinear lookup of :func:`_everett_tables` at width position ``wpos``, inputs ``a >= b`` in [0, 1]."""
    nw, n = table.shape[0], table.shape[1]
    wi = np.clip(np.floor(wpos).astype(int), 0, nw - 2)
    fw = np.clip(wpos - wi, 0.0, 1.0)
    xa, xb = np.clip(a, 0.0, 1.0) * (n - 1), np.clip(b, 0.0, 1.0) * (n - 1)
    ia, ib = np.minimum(xa.astype(int), n - 2), np.minimum(xb.astype(int), n - 2)
    fa, fb = xa - ia, xb - ib
    total = np.zeros(np.shape(a))
    for dw, cw in ((0, 1.0 - fw), (1, fw)):
        k = wi + dw
        bil = (table[k, ia, ib] * (1 - fa) * (1 - fb) + table[k, ia + 1, ib] * fa * (1 - fb)) + (
            table[k, ia, ib + 1] * (1 - fa) * fb + table[k, ia + 1, ib + 1] * fa * fb
        )
        total = total + cw * bil
    return np.asarray(total, dtype=np.float64)


def preisach_share(v: Array, width: Array, p: dict[str, float]) -> Array:
    """Share [0, 1] of relays on for normalised input ``v`` [0, 1], starting all off (vented).

    Exact for crisp relays of fixed spread: a stack of alternating extrema with wiping out, each
    branch ``y = y_r + E(v, m_r)`` rising, ``y = y_r - E(M_r, v)`` falling. A varying spread
    factor reshapes the branches from the last reversal on (the thresholds drift with it).
    """
    table = _everett_tables(p)
    wpos = np.interp(np.log(width), np.log(WIDTH_LEVELS), np.arange(WIDTH_LEVELS.size, dtype=np.float64))
    n = v.size
    anchor_u, anchor_y, rising = np.zeros(n), np.zeros(n), np.ones(n, dtype=bool)
    stack_u, stack_y = [0.0], [0.0]  # extrema and the output there; [0]: the vented start
    up = True
    last_u = 0.0
    for i, vi in enumerate(v.tolist()):
        if i > 0 and ((up and vi < last_u) or (not up and vi > last_u)):
            hi, lo = (last_u, stack_u[-1]) if up else (stack_u[-1], last_u)
            e = float(_everett(table, wpos[i - 1 : i], np.array([hi]), np.array([lo]))[0])
            stack_u.append(last_u)
            stack_y.append(stack_y[-1] + (e if up else -e))
            up = not up
        while len(stack_u) >= 3 and ((up and vi >= stack_u[-2]) or (not up and vi <= stack_u[-2])):
            del stack_u[-2:], stack_y[-2:]  # a closed minor loop is wiped out
        if len(stack_u) == 1:
            up = True
        anchor_u[i], anchor_y[i], rising[i] = stack_u[-1], stack_y[-1], up
        last_u = vi
    hi_a = np.where(rising, v, anchor_u)
    lo_a = np.where(rising, anchor_u, v)
    e_all = _everett(table, wpos, hi_a, lo_a)
    return anchor_y + np.where(rising, e_all, -e_all)


def preisach_resonant(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """Effective pressure ``p_eff = peak ((1 - s) v + s P(v))`` [bar] (``v = u / peak``, ``P`` the
    Preisach share), a Tondu-Lopez balance against payload, spring and rubber giving ``x`` [mm],
    then ``y'' + 2 zeta wn y' + wn^2 y = wn^2 x`` (``wn = 2 pi f_res``, zero-order hold, at rest).
    """
    v = np.clip(u / p["peak"], 0.0, 1.0)
    eff = p["peak"] * ((1.0 - p["share"]) * v + p["share"] * preisach_share(v, hooks.width, p))
    weight = (p["payload_kg"] + hooks.load_kg) * G_MS2
    k = (p["k_spring"] + p["k_rubber"] * hooks.rubber) * p["l0_m"]
    x = 1000.0 * p["l0_m"] * muscle_contraction(eff, weight, k, p)
    wn, zeta = 2.0 * np.pi * p["f_res_hz"], p["zeta"]
    num, den, _ = cont2discrete(([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn]), dt_s, method="zoh")
    b = np.asarray(num, dtype=np.float64).ravel()
    return np.asarray(lfilter(b, np.asarray(den, dtype=np.float64), x), dtype=np.float64)


def asym_play_poly(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """``z = c0 v + sum c_i play_i(v)``, asymmetric plays ``P = min(v + rd_i, max(v - ru_i, P))``
    (rising threshold ``ru_i``, falling ``rd_i``, both times ``width``), then the free contraction
    ``f(z) = stroke (a1 z + a2 z^2 + a3 z^3)`` [mm], the sag ``(m + L) g / (k0 + k1 z)`` [mm]
    of a muscle that stiffens with pressure (rubber factor ``rubber``), and a soft end stop
    ``y = ymax tanh(max(y, 0) / ymax)``.
    """
    v = np.clip(u / p["peak"], 0.0, 1.0)
    n_op = 5
    ru = [p["r_up"] * (k + 1) / n_op for k in range(n_op)]
    rd = [p["r_down"] * (k + 1) / n_op for k in range(n_op)]
    plays = [0.0] * n_op
    c = [p["c_plays"] / n_op] * n_op
    z = np.empty_like(v)
    for i, (vi, wi) in enumerate(zip(v.tolist(), hooks.width.tolist())):
        acc = 0.0
        for k in range(n_op):
            pk = plays[k]
            lo, hi = vi - ru[k] * wi, vi + rd[k] * wi
            pk = lo if pk < lo else hi if pk > hi else pk
            plays[k] = pk
            acc += c[k] * pk
        z[i] = acc
    z = (1.0 - p["c_plays"]) * v + z
    free = p["stroke_mm"] * (p["a1"] * z + p["a2"] * z * z + p["a3"] * z**3)
    stiff = (p["k0_n_mm"] + p["k1_n_mm"] * z) * (1.0 + p["rubber_share"] * (hooks.rubber - 1.0))
    free = free * (1.0 + p["rubber_share"]) / (1.0 + p["rubber_share"] * hooks.rubber)
    y = free - (p["payload_kg"] + hooks.load_kg) * G_MS2 / stiff
    return np.asarray(p["ymax_mm"] * np.tanh(np.maximum(y, 0.0) / p["ymax_mm"]), dtype=np.float64)


_CHAMBER_CACHE: dict[bytes, Array] = {}
R_AIR, GAMMA, P_ATM = 287.0, 1.4, 1.013e5


def chamber_pressure(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Gauge pressure [bar] of a chamber of volume ``V`` behind a proportional 3/3 valve
    commanded to ``u`` [bar gauge].

    The valve opens ``min(1, |u - P| / band)`` of its orifice, from a 7 bar supply when ``P < u``
    and to atmosphere when ``P > u``: ``m' = C open sqrt(|Pu^2 - Pd^2| / (R Tu))`` [kg/s].
    Energy ``m cv T' = m'_in (cp Ts - cv T) - m'_out R T - hA (T - Tw)`` with
    ``hA = m_ref cv / tau_th``: the air heats on filling and cools on venting and relaxes to the
    wall in ``tau_th`` (1.5-5 s), so the pressure settles with a slow thermal tail;
    ``P = m R T / V``. Euler at <= 1 ms (the wall exchange exact); cached for the on/off renders of a record.
    """
    key = hashlib.blake2b(u.tobytes() + np.array([dt_s, *p.values()]).tobytes(), digest_size=16).digest()
    if key in _CHAMBER_CACHE:
        return _CHAMBER_CACHE[key]
    vol, cflow, t_wall, band = p["volume_m3"], p["orifice"], 293.15, p["band_bar"] * BAR_PA
    cv = R_AIR / (GAMMA - 1.0)
    cp = cv + R_AIR
    m_ref = (P_ATM + 0.5 * p["peak"] * BAR_PA) * vol / (R_AIR * t_wall)
    ha = m_ref * cv / p["tau_th_s"]
    supply = P_ATM + 7.0 * BAR_PA
    sub = max(1, int(np.ceil(dt_s / 0.001)))
    h = dt_s / sub
    temp, mass = t_wall, P_ATM * vol / (R_AIR * t_wall)
    out = np.empty_like(u)
    for i, ui in enumerate(u.tolist()):
        target = P_ATM + ui * BAR_PA
        for _ in range(sub):
            pres = mass * R_AIR * temp / vol
            opening = min(1.0, abs(target - pres) / band)
            if pres < target:
                flow = cflow * opening * math.sqrt(max(supply * supply - pres * pres, 0.0) / (R_AIR * t_wall))
                heat = flow * (cp * t_wall - cv * temp)
            else:
                flow = -cflow * opening * math.sqrt(max(pres * pres - P_ATM * P_ATM, 0.0) / (R_AIR * temp))
                heat = flow * R_AIR * temp
            mass = max(mass + h * flow, 1e-9)
            temp += h * heat / (mass * cv)
            temp = t_wall + (temp - t_wall) * math.exp(-h * ha / (mass * cv))  # wall exchange, exact
        out[i] = (mass * R_AIR * temp / vol - P_ATM) / BAR_PA
    _CHAMBER_CACHE.clear()  # keep one entry: on/off renders of one record share it
    _CHAMBER_CACHE[key] = out
    return out


def scaled_branches(v: Array, width: Array, p: dict[str, float]) -> Array:
    """Madelung-rule hysteresis in [0, 1]: the branch from the last reversal ``(x_r, y_r)``
    towards the last open extremum ``(x_t, y_t)`` (at first the major-loop tips (0, 0), (1, 1))
    is the limiting branch's shape ``tanh(slope (x - 0.5 -+ split width))`` scaled between the
    two points; reaching the target closes the minor loop and the older branch resumes.
    """
    slope, split = p["slope"], p["split"]
    out = np.empty_like(v)
    stack: list[tuple[float, float]] = [(0.0, 0.0), (1.0, 1.0), (0.0, 0.0)]  # ..., target, origin
    up = True
    last_x, last_y = 0.0, 0.0
    for i, (xi, wi) in enumerate(zip(v.tolist(), width.tolist())):
        if (up and xi < last_x) or (not up and xi > last_x):
            stack.append((last_x, last_y))
            up = not up
        while len(stack) > 3 and ((up and xi >= stack[-2][0]) or (not up and xi <= stack[-2][0])):
            del stack[-2:]  # the target extremum is reached: that minor loop is closed
        (xr, yr), (xt, yt) = stack[-1], stack[-2]
        centre = 0.5 + split * wi if up else 0.5 - split * wi
        sr, st = np.tanh(slope * (xr - centre)), np.tanh(slope * (xt - centre))
        if abs(st - sr) < 1e-12:
            yi = yr
        else:
            yi = yr + (yt - yr) * (np.tanh(slope * (xi - centre)) - sr) / (st - sr)
        out[i] = yi
        last_x, last_y = xi, float(yi)
    return out


def valve_chamber(u: Array, dt_s: float, p: dict[str, float], hooks: Hooks) -> Array:
    """Supply command ``u`` [bar] -> chamber pressure (:func:`chamber_pressure`) -> effective
    pressure ``peak ((1 - s) P/peak + s H(P/peak))`` with ``H`` of :func:`scaled_branches`
    (braid friction) -> Chou-Hannaford balance against payload, spring and rubber [mm]."""
    pres = np.clip(chamber_pressure(u, dt_s, p), 0.0, None)
    v = np.clip(pres / p["peak"], 0.0, 1.0)
    eff = p["peak"] * ((1.0 - p["share"]) * v + p["share"] * scaled_branches(v, hooks.width, p))
    weight = (p["payload_kg"] + hooks.load_kg) * G_MS2
    k = (p["k_spring"] + p["k_rubber"] * hooks.rubber) * p["l0_m"]
    return np.asarray(1000.0 * p["l0_m"] * muscle_contraction(eff, weight, k, p), dtype=np.float64)


Core = Callable[[Array, float, dict[str, float], Hooks], Array]
BLIND_CORES: dict[str, Core] = {
    "lugre_mckibben": lugre_mckibben,
    "preisach_resonant": preisach_resonant,
    "asym_play_poly": asym_play_poly,
    "valve_chamber": valve_chamber,
}
