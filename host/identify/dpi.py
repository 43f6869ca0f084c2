"""DPI identification from the expansion and contraction branches.

The input range of the training data is cut into ``N`` equal digits (``dXe = dXc = dX``), so
the digit fills are those of a PI model with thresholds ``r_i = i dX / 2`` (see
:mod:`edge.hysteresis.dpi`): ``s_i = (z_i - z_{i+1}) / dX + 1/2`` from play outputs ``z``.
Splitting every fill change into its expansion and contraction part, the uncompensated output
``y = y_start + sum_i dYe_i Fe_i(t) - sum_i dYc_i Fc_i(t)`` (``Fe``/``Fc``: cumulative fill gained
while expanding / lost while contracting) is linear in the pairs: a bounded least-squares
problem with ``dY > 0`` and one soft equality ``sum dYe = sum dYc`` (the major loop closes, so
the compensator is inactive on it).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import Bounds, LinearConstraint, minimize

from edge.errors import ModelError
from edge.hysteresis.dpi import DPIModel
from edge.hysteresis.pi import branch_play_state, play_outputs
from host.identify.common import (
    HysteresisEstimator,
    MemoryStart,
    average_slope,
    bounded_lsq,
    check_slope_ratio,
)


def digit_fills(u: NDArray[np.float64], dx: float, n: int, start: MemoryStart) -> NDArray[np.float64]:
    """Fill of every digit (columns) at every sample from ``start.index`` (rows).

    The equivalent PI model has ``n + 1`` plays centred on the input range; the last one
    (threshold = half the range) never moves inside the range and starts centred.
    """
    thresholds = np.arange(n + 1, dtype=np.float64) * (dx / 2.0)
    x = u - (float(u.min()) + n * dx / 2.0)
    z0 = branch_play_state(float(x[start.index]), thresholds, start.branch)
    z0[-1] = 0.0
    z = play_outputs(x[start.index :], thresholds, z0)
    return (z[:, :-1] - z[:, 1:]) / dx + 0.5


def branch_regressors(fills: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Cumulative fill gained (expansion) and lost (contraction) per digit since the start."""
    change = np.diff(fills, axis=0, prepend=fills[:1])
    return np.cumsum(np.maximum(change, 0.0), axis=0), np.cumsum(np.maximum(-change, 0.0), axis=0)


def bound_asymmetry(
    design: NDArray[np.float64], target: NDArray[np.float64], lower: NDArray[np.float64], n: int, ratio: float
) -> NDArray[np.float64]:
    """Bounded least squares whose first ``2 n`` unknowns are ``(dYe, dYc)`` with every
    ``dYc_i / dYe_i`` in ``[1 / ratio, ratio]``.

    The plain bounded fit is exact and used whenever it already satisfies the ratios; otherwise
    the quadratic programme (the same normal equations plus ``2 n`` linear inequalities) is
    solved by SLSQP from the symmetric pairs, which are feasible.
    """
    x = bounded_lsq(design, target, lower)
    dye, dyc = x[:n], x[n : 2 * n]
    if not math.isfinite(ratio) or np.all((dyc <= ratio * dye) & (dye <= ratio * dyc)):
        return x
    scale = np.linalg.norm(design, axis=0)
    scale[scale == 0] = 1.0
    scaled = design / scale
    hessian, gradient = scaled.T @ scaled, scaled.T @ target
    pairs = np.zeros((2 * n, x.size))
    digits = np.arange(n)
    pairs[digits, digits], pairs[digits, n + digits] = -ratio, 1.0  # dYc - ratio dYe <= 0
    pairs[n + digits, digits], pairs[n + digits, n + digits] = 1.0, -ratio  # dYe - ratio dYc <= 0
    mean = (dye + dyc) / 2.0
    result = minimize(
        lambda z: 0.5 * z @ hessian @ z - gradient @ z,
        np.r_[mean, mean, x[2 * n :]] * scale,
        jac=lambda z: hessian @ z - gradient,
        method="SLSQP",
        bounds=Bounds(lower * scale, np.inf),
        constraints=[LinearConstraint(pairs / scale, -np.inf, 0.0)],
        options={"maxiter": 1000, "ftol": 1e-14},
    )
    if not result.success:
        raise ModelError(
            f"DPI fit with max_asymmetry={ratio:g} did not converge ({result.message}); "
            "try a larger max_asymmetry or fewer operators"
        )
    return np.asarray(result.x / scale, dtype=np.float64)


class DPIEstimator(HysteresisEstimator):
    """Identify a :class:`~edge.hysteresis.dpi.DPIModel`.

    As in seed 002, the pairs are identified from the branches without the compensator (one
    bounded least-squares problem) and the compensator acts online, at turning points, to keep
    the model from drifting. On a closed major loop it is inactive; on minor loops of an
    asymmetric model it rescales the branch, so the deployed model's minor loops can differ
    slightly from the regression's (``train_prediction_`` is the deployed, compensated model).
    A fit with the compensator in the loop is a fixed point of "regress with the branch scales
    frozen"; that iteration does not contract, and a proper Gauss-Newton needs the scale
    derivatives through every branch: left for when data shows the gain is worth it.

    Args:
        n_operators: number of digits ``N``.
        closure_weight: weight of the soft constraint ``sum dYe = sum dYc`` relative to one
            sample's residual, scaled by the number of samples.
        min_slope_ratio: lower bound of every ``dY_i / dX_i`` relative to the average slope;
            see :data:`host.identify.common.MIN_SLOPE_DOC`.
        max_asymmetry: bound on every digit's ``dYc_i / dYe_i`` and its reciprocal. The
            inverse model's rounding error can grow by up to this factor at each reversal (see
            :mod:`edge.hysteresis.dpi`): unbounded, the shipped example data gives ratios up to
            630 and an inverse table off by up to 4e-6 bar; bounded at 10, 2e-12 bar, and the
            held-out error is no worse (6.72 vs 6.74 mm). ``inf`` restores the unbounded fit.
    """

    def __init__(
        self,
        *,
        n_operators: int = 25,
        closure_weight: float = 1.0,
        min_slope_ratio: float = 0.01,
        max_asymmetry: float = 10.0,
    ) -> None:
        if n_operators < 1:
            raise ModelError(f"n_operators must be >= 1; got {n_operators}")
        if not max_asymmetry >= 1.0:
            raise ModelError(f"max_asymmetry must be >= 1 (inf: unbounded); got {max_asymmetry}")
        self.n_operators = n_operators
        self.closure_weight = closure_weight
        self.min_slope_ratio = check_slope_ratio(min_slope_ratio)
        self.max_asymmetry = float(max_asymmetry)

    def _parameter_count(self) -> int:
        return 2 * self.n_operators + 1

    def _identify(self, u: NDArray[np.float64], y: NDArray[np.float64], start: MemoryStart) -> DPIModel:
        n = self.n_operators
        target = y[start.index :]
        x0, x1 = float(u.min()), float(u.max())
        dx = (x1 - x0) / n
        gained, lost = branch_regressors(digit_fills(u, dx, n, start))
        design = np.column_stack([gained, -lost, np.ones(len(target))])
        closure = np.sqrt(self.closure_weight * len(target)) * np.r_[np.ones(n), -np.ones(n), 0.0]
        floor = self.min_slope_ratio * average_slope(u, y) * dx
        x = bound_asymmetry(
            np.vstack([design, closure]),
            np.r_[target, 0.0],
            np.r_[np.full(2 * n, floor), -np.inf],
            n,
            self.max_asymmetry,
        )
        dye, dyc, y_start = x[:n], x[n : 2 * n], float(x[2 * n])
        # y_start is the output in the start state; the model is translation invariant in y,
        # so build it at y0 = 0, read its output in that state and shift by the difference
        widths = np.full(n, dx)
        probe = DPIModel(widths, dye, widths, dyc, x0=x0, y0=0.0, x1=x1, y1=float(dye.sum()))
        probe.reset(float(u[start.index]), start.branch)
        y0 = y_start - probe.step(float(u[start.index]))
        return DPIModel(widths, dye, widths, dyc, x0=x0, y0=y0, x1=x1, y1=y0 + float(dye.sum()))
