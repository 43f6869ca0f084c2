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
from collections.abc import Iterator

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

CHUNK_ROWS = 65_536  # rows of the design built at a time: memory stays ~50 MB for any record length


def fill_chunks(
    u: NDArray[np.float64], dx: float, n: int, start: MemoryStart, rows: int = CHUNK_ROWS
) -> Iterator[NDArray[np.float64]]:
    """:func:`digit_fills` in consecutive row blocks of at most ``rows`` (the plays carry over)."""
    thresholds = np.arange(n + 1, dtype=np.float64) * (dx / 2.0)
    x = u - (float(u.min()) + n * dx / 2.0)
    z0 = branch_play_state(float(x[start.index]), thresholds, start.branch)
    z0[-1] = 0.0
    for first in range(start.index, u.size, rows):
        z = play_outputs(x[first : first + rows], thresholds, z0)
        z0 = z[-1].copy()
        yield (z[:, :-1] - z[:, 1:]) / dx + 0.5


def digit_fills(u: NDArray[np.float64], dx: float, n: int, start: MemoryStart) -> NDArray[np.float64]:
    """Fill of every digit (columns) at every sample from ``start.index`` (rows).

    The equivalent PI model has ``n + 1`` plays centred on the input range; the last one
    (threshold = half the range) never moves inside the range and starts centred.
    """
    return np.concatenate(list(fill_chunks(u, dx, n, start)))


def branch_regressors(fills: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Cumulative fill gained (expansion) and lost (contraction) per digit since the start."""
    change = np.diff(fills, axis=0, prepend=fills[:1])
    return np.cumsum(np.maximum(change, 0.0), axis=0), np.cumsum(np.maximum(-change, 0.0), axis=0)


def compressed_branch_problem(
    u: NDArray[np.float64], y: NDArray[np.float64], dx: float, n: int, start: MemoryStart
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(R, r)`` with ``|R x - r|^2 = |[gained, -lost, 1] x - y|^2 + const`` for every ``x``.

    The triangular factor of the design and target, accumulated block by block (QR of the
    previous factor stacked on the next rows), so the design of a long record is never held
    whole: ``2 n + 1`` columns at 1e6 samples are 400 MB in float64, several copies 2.4 GB.
    """
    width = 2 * n + 1
    factor = np.zeros((0, width + 1))
    previous: NDArray[np.float64] | None = None
    gained_sum, lost_sum = np.zeros(n), np.zeros(n)
    row = start.index
    for fills in fill_chunks(u, dx, n, start):
        change = np.diff(fills, axis=0, prepend=fills[:1] if previous is None else previous)
        previous = fills[-1:]
        gained = np.cumsum(np.maximum(change, 0.0), axis=0) + gained_sum
        lost = np.cumsum(np.maximum(-change, 0.0), axis=0) + lost_sum
        gained_sum, lost_sum = gained[-1], lost[-1]
        block = np.column_stack([gained, -lost, np.ones(len(fills)), y[row : row + len(fills)]])
        row += len(fills)
        factor = np.asarray(np.linalg.qr(np.vstack([factor, block]), mode="r"), dtype=np.float64)
    factor = factor[:width]
    return factor[:, :width], factor[:, width]


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
    # the objective in units of |target|^2: SLSQP's tolerance is absolute, and on 1e5 samples the
    # unnormalised objective (~1e7) left it at its iteration limit ("did not converge")
    norm = float(target @ target) or 1.0
    hessian, gradient = scaled.T @ scaled / norm, scaled.T @ target / norm
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
        options={"maxiter": 5000, "ftol": 1e-15},
    )
    if not result.success:
        raise ModelError(
            f"DPI fit with max_asymmetry={ratio:g} did not converge ({result.message}); "
            "try a larger max_asymmetry or fewer operators"
        )
    return np.asarray(result.x / scale, dtype=np.float64)


class DPIEstimator(HysteresisEstimator):
    """Identify a :class:`~edge.hysteresis.dpi.DPIModel`.

    As in Zhou2022, the pairs are identified from the branches without the compensator (one
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
        design, projected = compressed_branch_problem(u, y, dx, n, start)
        closure = np.sqrt(self.closure_weight * len(target)) * np.r_[np.ones(n), -np.ones(n), 0.0]
        floor = self.min_slope_ratio * average_slope(u, y) * dx
        x = bound_asymmetry(
            np.vstack([design, closure]),
            np.r_[projected, 0.0],
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
