"""Static muscle force laws ``F(p, eps)`` identified by least squares (PAMInertial eq 1, Ai2019 eqs 15-16).

Both are estimators in scikit-learn's shape: ``__init__`` stores options, ``fit(pressure_bar,
contraction_ratio, force_n)`` learns attributes ending in ``_`` and returns ``self``;
``predict`` gives the force and ``pressure`` the inverse (the pressure that makes a force at a
contraction), which is what a joint's static inversion needs.

Tondu-Lopez (PAMInertial eq 1)::

    F = S p [a (1 - k eps)^2 - b],   S = pi r0^2

``p`` the gauge pressure [Pa], ``eps`` the contraction ratio (contraction / rest length, 0..1),
``a = 3 / tan^2(alpha0)`` and ``b = 1 / sin^2(alpha0)`` from the braid angle ``alpha0`` at rest,
``k`` the shortening factor of the cylindrical part (tapered ends). Written out it is linear in
``(a - b, -2 a k, a k^2)`` times ``S p``, so the least squares is linear and exact;
``a = c1^2 / (4 c2)``, ``k = -c1 / (2 a)``, ``b = a - c0``. Without the radius only ``S a`` and
``S b`` are identifiable (``area_m2`` is then 1 and ``a``, ``b`` are in m^2).

Sarosi (Ai2019 eq 15, Sarosi 2012)::

    F = (p + a) e^{b kappa} + c p kappa + d p + e

in Sarosi's units: ``p`` in kPa, ``kappa`` the contraction in percent, ``F`` in N, so ``a``
[kPa], ``b`` [1/%], ``c`` [N/(kPa %)], ``d`` [N/kPa], ``e`` [N] (the first term carries an implicit
1 N/kPa). Linear in ``a, c, d, e`` for a fixed ``b``: ``b`` is found by a bounded scalar search
(variable projection), then all five get standard errors from the full Jacobian. Eq 16 is its
inverse ``p = (F - a e^{b kappa} - e) / (e^{b kappa} + c kappa + d)``.
"""

from __future__ import annotations

import math
from typing import Self

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar

from edge.errors import DataError, ModelError

Array = NDArray[np.float64]


def _inputs(
    pressure_bar: ArrayLike, contraction_ratio: ArrayLike, force_n: ArrayLike | None = None
) -> tuple[Array, ...]:
    arrays = [np.asarray(pressure_bar, float), np.asarray(contraction_ratio, float)]
    if force_n is not None:
        arrays.append(np.asarray(force_n, float))
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    arrays = [np.broadcast_to(a, shape).ravel() for a in arrays]
    if not all(np.all(np.isfinite(a)) for a in arrays):
        raise DataError("pressure, contraction or force holds NaN or inf; remove those samples")
    return tuple(arrays)


def _check_fit_data(p: Array, eps: Array, minimum: int, force: Array) -> None:
    if p.size < minimum:
        raise DataError(f"only {p.size} samples; a static force fit needs at least {minimum}")
    if np.ptp(force) <= 0.05 * max(float(np.max(np.abs(force))), 1e-12):
        raise DataError(
            "the force hardly varies (a constant load): a force law needs the force to change; record an "
            "isometric run (pmactl hil record --scenario isometric) or isotonic curves at several loads"
        )
    if np.ptp(p) <= 0 or np.ptp(eps) <= 0:
        raise DataError(
            "pressure or contraction does not vary: the force law needs both to change "
            "(record isotonic curves at several loads: pmactl hil record --scenario isotonic --effect load_dependence)"
        )


def _standard_errors(jacobian: Array, residual: Array) -> Array:
    dof = max(residual.size - jacobian.shape[1], 1)
    covariance = np.linalg.pinv(jacobian.T @ jacobian) * float(residual @ residual) / dof
    return np.asarray(np.sqrt(np.clip(np.diag(covariance), 0.0, None)), dtype=np.float64)


class TonduLopezForce:
    """Tondu-Lopez static force (module docstring).

    Args:
        radius_m: inner radius ``r0`` [m] at rest; ``None`` fits ``S a`` and ``S b`` instead.

    Learned: ``a_``, ``b_`` (dimensionless, or m^2 without a radius), ``k_`` (dimensionless),
    ``area_m2_``, ``braid_angle_deg_`` (``alpha0`` from ``b = 1/sin^2``, when ``b > 1``),
    ``se_`` (standard errors of a, b, k by the delta method), ``rmse_n_``.
    """

    def __init__(self, radius_m: float | None = None) -> None:
        self.radius_m = radius_m

    def fit(self, pressure_bar: ArrayLike, contraction_ratio: ArrayLike, force_n: ArrayLike) -> Self:
        p, eps, force = _inputs(pressure_bar, contraction_ratio, force_n)
        _check_fit_data(p, eps, 4, force)
        if self.radius_m is not None and not self.radius_m > 0:
            raise ModelError(f"radius_m {self.radius_m} must be positive (metres)")
        area = math.pi * self.radius_m**2 if self.radius_m is not None else 1.0
        sp = area * p * 1e5
        design = np.column_stack([sp, sp * eps, sp * eps**2])
        coef, *_ = np.linalg.lstsq(design, force, rcond=None)
        c0, c1, c2 = (float(c) for c in coef)
        if c2 <= 0:
            raise DataError(
                "the force does not fall with contraction as a Tondu-Lopez muscle does (fitted curvature <= 0); "
                "check the sign of the contraction and the force columns"
            )
        a = c1**2 / (4 * c2)
        k = -c1 / (2 * a)
        b = a - c0
        residual = force - design @ coef
        cov_c = np.linalg.pinv(design.T @ design) * float(residual @ residual) / max(residual.size - 3, 1)
        # d(a, b, k) / d(c0, c1, c2), with k = -c1 / (2 a) = -2 c2 / c1
        da = [0.0, c1 / (2 * c2), -(c1**2) / (4 * c2**2)]
        jac = np.array([da, [-1.0, da[1], da[2]], [0.0, 2 * c2 / c1**2, -2 / c1] if c1 else [0.0, 0.0, 0.0]])
        self.a_, self.b_, self.k_, self.area_m2_ = a, b, k, area
        self.se_ = np.sqrt(np.clip(np.diag(jac @ cov_c @ jac.T), 0.0, None))
        self.braid_angle_deg_ = math.degrees(math.asin(1 / math.sqrt(b))) if self.radius_m and b > 1 else float("nan")
        self.rmse_n_ = float(np.sqrt(np.mean(residual**2)))
        return self

    def predict(self, pressure_bar: ArrayLike, contraction_ratio: ArrayLike) -> Array:
        """Force [N] at gauge pressure [bar] and contraction ratio."""
        p, eps = _inputs(pressure_bar, contraction_ratio)
        return self.area_m2_ * p * 1e5 * (self.a_ * (1 - self.k_ * eps) ** 2 - self.b_)

    def pressure(self, force_n: ArrayLike, contraction_ratio: ArrayLike) -> Array:
        """Gauge pressure [bar] that gives ``force_n`` at ``contraction_ratio`` (NaN where unreachable)."""
        f, eps = _inputs(force_n, contraction_ratio)
        shape = self.a_ * (1 - self.k_ * eps) ** 2 - self.b_
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(shape > 0, f / (self.area_m2_ * 1e5 * shape), np.nan)

    def get_params(self) -> dict[str, object]:
        return {"radius_m": self.radius_m}

    def as_dict(self) -> dict[str, object]:
        return {
            "model": "tondu-lopez",
            "a": self.a_,
            "b": self.b_,
            "k": self.k_,
            "a_se": float(self.se_[0]),
            "b_se": float(self.se_[1]),
            "k_se": float(self.se_[2]),
            "area_m2": self.area_m2_,
            "braid_angle_deg": self.braid_angle_deg_,
            "rmse_n": self.rmse_n_,
        }


class SarosiForce:
    """Sarosi's static force (module docstring); pressure in bar and contraction ratio at the API.

    Args:
        b_bounds: search interval of the exponent ``b`` [1/%].

    Learned: ``a_`` [kPa], ``b_`` [1/%], ``c_`` [N/(kPa %)], ``d_`` [N/kPa], ``e_`` [N], ``se_``
    (standard errors, same order), ``rmse_n_``.
    """

    def __init__(self, b_bounds: tuple[float, float] = (-1.0, 1.0)) -> None:
        self.b_bounds = b_bounds

    @staticmethod
    def _linear(p_kpa: Array, kappa: Array, force: Array, b: float) -> tuple[Array, Array, Array]:
        growth = np.exp(b * kappa)
        design = np.column_stack([growth, p_kpa * kappa, p_kpa, np.ones_like(p_kpa)])
        target = force - p_kpa * growth
        coef, *_ = np.linalg.lstsq(design, target, rcond=None)
        return coef, target - design @ coef, design

    def fit(self, pressure_bar: ArrayLike, contraction_ratio: ArrayLike, force_n: ArrayLike) -> Self:
        p, eps, force = _inputs(pressure_bar, contraction_ratio, force_n)
        _check_fit_data(p, eps, 6, force)
        p_kpa, kappa = p * 100.0, eps * 100.0

        def cost(b: float) -> float:
            return float(np.sum(self._linear(p_kpa, kappa, force, b)[1] ** 2))

        grid = np.linspace(*self.b_bounds, 81)
        start = float(grid[int(np.argmin([cost(b) for b in grid]))])
        step = grid[1] - grid[0]
        lo, hi = max(start - step, self.b_bounds[0]), min(start + step, self.b_bounds[1])
        b = float(minimize_scalar(cost, bounds=(lo, hi), method="bounded", options={"xatol": 1e-10}).x)
        coef, residual, design = self._linear(p_kpa, kappa, force, b)
        a, c, d, e = (float(v) for v in coef)
        growth = np.exp(b * kappa)
        d_b = (p_kpa + a) * kappa * growth
        jacobian = np.column_stack([design[:, 0], d_b, design[:, 1], design[:, 2], design[:, 3]])
        self.a_, self.b_, self.c_, self.d_, self.e_ = a, b, c, d, e
        self.se_ = _standard_errors(jacobian, residual)
        self.rmse_n_ = float(np.sqrt(np.mean(residual**2)))
        return self

    def predict(self, pressure_bar: ArrayLike, contraction_ratio: ArrayLike) -> Array:
        """Force [N] at gauge pressure [bar] and contraction ratio (eq 15)."""
        p, eps = _inputs(pressure_bar, contraction_ratio)
        p_kpa, kappa = p * 100.0, eps * 100.0
        return (p_kpa + self.a_) * np.exp(self.b_ * kappa) + self.c_ * p_kpa * kappa + self.d_ * p_kpa + self.e_

    def pressure(self, force_n: ArrayLike, contraction_ratio: ArrayLike) -> Array:
        """Gauge pressure [bar] for ``force_n`` at ``contraction_ratio`` (eq 16)."""
        f, eps = _inputs(force_n, contraction_ratio)
        kappa = eps * 100.0
        growth = np.exp(self.b_ * kappa)
        return (f - self.a_ * growth - self.e_) / (growth + self.c_ * kappa + self.d_) / 100.0

    def get_params(self) -> dict[str, object]:
        return {"b_bounds": self.b_bounds}

    def as_dict(self) -> dict[str, object]:
        names = ("a_kpa", "b_per_percent", "c_n_per_kpa_percent", "d_n_per_kpa", "e_n")
        values = (self.a_, self.b_, self.c_, self.d_, self.e_)
        out: dict[str, object] = {"model": "sarosi"}
        out.update({n: v for n, v in zip(names, values)})
        out.update({f"{n}_se": float(s) for n, s in zip(names, self.se_)})
        out["rmse_n"] = self.rmse_n_
        return out


FORCE_MODELS = {"tondu-lopez": TonduLopezForce, "sarosi": SarosiForce}
