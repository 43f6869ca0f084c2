"""PI identification by constrained least squares (non-negative play weights).

Thresholds ``r_i = i * (range / 2) / n`` (i = 0..n-1) for free weights; the output is linear in
the weights and an offset, solved with bounds ``w_0 > 0``, ``w_i >= 0`` (which keeps the model
invertible). The 3-parameter form of Ai2019 eq 5 (``r_i = beta*i``,
``w_i = delta*exp(-mu*r_i)``) is fitted by variable projection: for each ``beta`` on a grid
the play outputs are computed once, ``mu`` is searched on a bracket and ``delta`` and the offset
are linear.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import minimize_scalar

from edge.errors import ModelError
from edge.hysteresis.pi import PIModel, branch_play_state, exponential_pi_parameters, play_outputs
from host.identify.common import (
    HysteresisEstimator,
    MemoryStart,
    average_slope,
    bounded_lsq,
    check_slope_ratio,
)


def start_plays(u: NDArray[np.float64], thresholds: NDArray[np.float64], start: MemoryStart) -> NDArray[np.float64]:
    """Play outputs from ``start.index`` on, starting in the state ``start.branch``."""
    z0 = branch_play_state(float(u[start.index]), thresholds, start.branch)
    return play_outputs(u[start.index :], thresholds, z0)


def uniform_thresholds(u: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """``n`` thresholds from 0 to just under half the input range."""
    return np.arange(n) * (float(np.ptp(u)) / 2.0) / n


class PIEstimator(HysteresisEstimator):
    """Identify a :class:`~edge.hysteresis.pi.PIModel`.

    Args:
        n_operators: number of play operators (the first has threshold 0, the linear term).
        parameterisation: ``"free"`` weights or Ai2019's 3-parameter ``"exponential"``.
        min_slope_ratio: lower bound of ``w_0`` (the slope right after a reversal) relative to
            the average slope; see :data:`host.identify.common.MIN_SLOPE_DOC`.
    """

    def __init__(
        self,
        *,
        n_operators: int = 25,
        parameterisation: Literal["free", "exponential"] = "free",
        min_slope_ratio: float = 0.01,
    ) -> None:
        if n_operators < 1:
            raise ModelError(f"n_operators must be >= 1; got {n_operators}")
        if parameterisation not in ("free", "exponential"):
            raise ModelError(f"parameterisation {parameterisation!r} unknown; use 'free' or 'exponential'")
        self.n_operators = n_operators
        self.parameterisation = parameterisation
        self.min_slope_ratio = check_slope_ratio(min_slope_ratio)

    def _parameter_count(self) -> int:
        return self.n_operators + 1

    def _identify(self, u: NDArray[np.float64], y: NDArray[np.float64], start: MemoryStart) -> PIModel:
        target = y[start.index :]
        if self.parameterisation == "free":
            thresholds = uniform_thresholds(u, self.n_operators)
            floor = self.min_slope_ratio * average_slope(u, y)
            weights, offset = self._fit_free(start_plays(u, thresholds, start), target, floor)
        else:
            thresholds, weights, offset = self._fit_exponential(u, target, start)
        return PIModel(thresholds, weights, output_offset=offset, actuator_range=(float(u.min()), float(u.max())))

    @staticmethod
    def _fit_free(
        plays: NDArray[np.float64], target: NDArray[np.float64], first_weight_floor: float
    ) -> tuple[NDArray[np.float64], float]:
        n = plays.shape[1]
        design = np.column_stack([plays, np.ones(len(plays))])
        lower = np.r_[first_weight_floor, np.zeros(n - 1), -np.inf]
        x = bounded_lsq(design, target, lower)
        return x[:n], float(x[n])

    def _fit_exponential(
        self, u: NDArray[np.float64], target: NDArray[np.float64], start: MemoryStart
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
        floor = self.min_slope_ratio * float(np.ptp(target) / np.ptp(u))  # delta = w_0 >= floor
        ones = np.ones(len(target))

        def solve(column: NDArray[np.float64]) -> tuple[float, float, float]:
            delta, c = bounded_lsq(np.column_stack([column, ones]), target, np.array([floor, -np.inf]))
            residual = column * delta + c - target
            return float(residual @ residual), float(delta), float(c)

        beta, mu = exponential_search(u, start, self.n_operators, lambda column: solve(column)[0])
        thresholds, shape = exponential_pi_parameters(self.n_operators, beta, 1.0, mu)
        _, delta, c = solve(start_plays(u, thresholds, start) @ shape)
        self.beta_, self.mu_, self.delta_ = beta, mu, delta
        return thresholds, delta * shape, c


def exponential_search(
    u: NDArray[np.float64], start: MemoryStart, n: int, cost_of_column: Callable[[NDArray[np.float64]], float]
) -> tuple[float, float]:
    """``(beta, mu)`` of Ai2019 eq 5 minimising ``cost_of_column(plays @ exp(-mu r))``.

    ``cost_of_column`` solves the linear rest of the problem (``delta``, offsets, ...) for the
    summed play column with unit ``delta`` and returns its squared residual. For each ``beta``
    the plays are computed once and ``mu`` is searched on a bracket; ``beta`` is taken on a grid
    up to half the input range, then refined between the grid neighbours of the best point.
    """
    if n < 2:
        raise ModelError("the exponential parameterisation needs n_operators >= 2")
    beta_max = float(np.ptp(u)) / 2.0 / (n - 1)  # largest threshold at half the input range

    def profile(beta: float) -> tuple[float, float]:
        thresholds = beta * np.arange(n, dtype=np.float64)
        plays = start_plays(u, thresholds, start)
        span = 8.0 / thresholds[-1]
        search = minimize_scalar(
            lambda mu: cost_of_column(plays @ np.exp(-mu * thresholds)), bounds=(-span / 4, span), method="bounded"
        )
        return float(search.fun), float(search.x)

    grid = beta_max * np.linspace(0.1, 1.0, 10)
    profiles = [profile(beta) for beta in grid]
    best = int(np.argmin([cost for cost, _ in profiles]))
    refined = minimize_scalar(
        lambda beta: profile(beta)[0],
        bounds=(grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]),
        method="bounded",
        options={"xatol": 1e-4 * beta_max, "maxiter": 12},
    )
    if refined.fun < profiles[best][0]:
        return float(refined.x), profile(float(refined.x))[1]
    return float(grid[best]), profiles[best][1]
