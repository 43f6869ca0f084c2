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

import numpy as np
from numpy.typing import NDArray

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
    """

    def __init__(self, *, n_operators: int = 25, closure_weight: float = 1.0, min_slope_ratio: float = 0.01) -> None:
        if n_operators < 1:
            raise ModelError(f"n_operators must be >= 1; got {n_operators}")
        self.n_operators = n_operators
        self.closure_weight = closure_weight
        self.min_slope_ratio = check_slope_ratio(min_slope_ratio)

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
        x = bounded_lsq(np.vstack([design, closure]), np.r_[target, 0.0], np.r_[np.full(2 * n, floor), -np.inf])
        dye, dyc, y_start = x[:n], x[n : 2 * n], float(x[2 * n])
        # y_start is the output in the start state; the model is translation invariant in y,
        # so build it at y0 = 0, read its output in that state and shift by the difference
        widths = np.full(n, dx)
        probe = DPIModel(widths, dye, widths, dyc, x0=x0, y0=0.0, x1=x1, y1=float(dye.sum()))
        probe.reset(float(u[start.index]), start.branch)
        y0 = y_start - probe.step(float(u[start.index]))
        return DPIModel(widths, dye, widths, dyc, x0=x0, y0=y0, x1=x1, y1=y0 + float(dye.sum()))
