"""Three hysteresis plants that are not the HIL and not a Preisach model.

Each core maps an input sequence ``u`` [0..peak] to an output [mm-like] with
``core(u, dt_s, width, params) -> y``; ``width`` is a per-sample factor on the plant's
hysteresis width (1: nominal) through which rate, load and temperature effects act.

* :func:`bouc_wen`: Bouc-Wen hysteresis (n = 1.5) driving a second-order mechanical stage.
* :func:`generalised_play`: a generalised Prandtl-Ishlinskii / KP-like sum of plays with
  nonlinear (saturating) envelopes, then a first-order lag of 40-150 ms.
* :func:`friction_spring`: a LuGre-type bristle friction element in series with a stiffening
  spring, massless (overdamped), integrated with sub-steps.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


def bouc_wen(u: Array, dt_s: float, width: Array, p: dict[str, float]) -> Array:
    """``z' = A u' - beta |u'| |z|^(n-1) z - gamma u' |z|^n``, force ``k u + alpha width z``,
    then ``m y'' + c y' + y = force`` (natural frequency ``wn_hz``, damping ``zeta``)."""
    a, beta, gamma, n = 1.0, p["beta"], p["gamma"], 1.5
    alpha, k = p["alpha"], p["k"]
    wn, zeta = 2 * np.pi * p["wn_hz"], p["zeta"]
    sub = max(1, int(np.ceil(dt_s / 0.002)))
    h = dt_s / sub
    z, y, v = 0.0, k * float(u[0]), 0.0
    out = np.empty_like(u)
    prev = float(u[0])
    for i, (ui, wi) in enumerate(zip(u.tolist(), width.tolist())):
        du = (ui - prev) / sub
        for s in range(sub):
            uu = prev + du * (s + 1)
            dz = a * du - beta * abs(du) * abs(z) ** (n - 1) * z - gamma * du * abs(z) ** n
            z += dz
            force = k * uu + alpha * wi * z
            acc = wn * wn * (force - y) - 2 * zeta * wn * v
            v += h * acc
            y += h * v
        prev = ui
        out[i] = y
    return out


def generalised_play(u: Array, dt_s: float, width: Array, p: dict[str, float]) -> Array:
    """Sum of generalised plays: ``z = min(g(u + r w), max(g(u - r w), z))`` with a saturating
    envelope ``g(v) = peak tanh(s v / peak) / s``; weights fall with the threshold."""
    peak = float(np.max(u)) or 1.0
    s = p["saturation"]
    radii = np.linspace(0.0, p["max_radius"] * peak, 8)
    weights = p["gain"] * np.exp(-radii / (0.3 * peak)) / 8 * 3

    def g(v: Array) -> Array:
        return peak * np.tanh(s * v / peak) / s

    z = g(np.full(radii.size, float(u[0])) + radii)  # vented: every play on its descending branch
    out = np.empty_like(u)
    for i, (ui, wi) in enumerate(zip(u.tolist(), width.tolist())):
        r = radii * wi
        z = np.minimum(g(ui + r), np.maximum(g(ui - r), z))
        out[i] = weights @ z
    alpha = 1.0 - np.exp(-dt_s / p["lag_s"])
    from scipy.signal import lfilter

    return lfilter([alpha], [1.0, alpha - 1.0], out, zi=[out[0] * (1 - alpha)])[0]


def friction_spring(u: Array, dt_s: float, width: Array, p: dict[str, float]) -> Array:
    """Actuator free stroke ``a = c u``; spring ``F = k (d + d^3 / d0^2)`` with ``d = a - y``;
    bristles ``z' = y' - sigma0 |y'| z / Fc``, friction ``sigma0 z + sigma2 y'`` balancing
    the spring (massless), ``Fc`` scaled by ``width``."""
    c, k, d0 = p["c"], p["k"], p["d0"]
    sigma0, sigma2, fc = p["sigma0"], p["sigma2"], p["fc"]
    tau = sigma2 / (k + sigma0)
    sub = max(1, int(np.ceil(dt_s / (0.3 * tau))))
    h = dt_s / sub
    y, z = c * float(u[0]), 0.0
    out = np.empty_like(u)
    for i, (ui, wi) in enumerate(zip(u.tolist(), width.tolist())):
        a = c * ui
        f_c = fc * wi
        for _ in range(sub):
            d = a - y
            spring = k * (d + d**3 / d0**2)
            v = (spring - sigma0 * z) / sigma2
            z += h * (v - sigma0 * abs(v) * z / f_c)
            z = min(max(z, -f_c / sigma0), f_c / sigma0)
            y += h * v
        out[i] = y
    return out


CORES = {"bouc_wen": bouc_wen, "generalised_play": generalised_play, "friction_spring": friction_spring}


def draw_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Physically plausible parameters for ``core``, drawn from ``rng`` (output span ~20-40)."""
    if core == "bouc_wen":
        return {
            "beta": rng.uniform(2.0, 5.0) / peak,
            "gamma": rng.uniform(-1.0, 1.0) / peak,
            "alpha": rng.uniform(4.0, 8.0),
            "k": rng.uniform(6.0, 9.0),
            "wn_hz": rng.uniform(1.5, 4.0),
            "zeta": rng.uniform(0.4, 0.9),
        }
    if core == "generalised_play":
        return {
            "saturation": rng.uniform(0.6, 1.4),
            "max_radius": rng.uniform(0.15, 0.3),
            "gain": rng.uniform(8.0, 12.0),
            "lag_s": rng.uniform(0.04, 0.15),
        }
    k = rng.uniform(8.0, 12.0)
    return {
        "c": rng.uniform(8.0, 10.0),
        "k": k,
        "d0": rng.uniform(5.0, 10.0),
        "sigma0": 20.0 * k,
        "sigma2": k * rng.uniform(0.02, 0.06),
        "fc": k * rng.uniform(1.5, 3.0),
    }
