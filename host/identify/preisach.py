"""Preisach identification: least squares on the Everett cells, or first-order reversal curves.

``method="lsq"`` (general data): the model output is linear in the Everett nodes (bilinear
interpolation, :mod:`edge.hysteresis.preisach`), and the nodes are cumulative sums of the cell
masses ``mu >= 0``. Walking the turning-point stack over the data gives one regressor row per
sample; the normal equations are accumulated in chunks (memory independent of the data length)
and solved with ``mu >= 0`` (diagonal cells > 0 so that the inverse exists).

``method="forc"`` (Mayergoyz, Schreiber): every descending branch that starts from the ascending
major branch (its preceding minimum at the bottom of the range) is a first-order reversal curve
and gives ``E(alpha, beta) = y(alpha) - y(alpha, beta)`` directly; the values are interpolated
onto the grid, then projected onto non-negative cell masses.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import cho_factor, solve_triangular

from edge.errors import DataError, ModelError
from edge.hysteresis.preisach import PreisachModel, everett_from_masses, masses_from_everett
from host.identify.common import (
    HysteresisEstimator,
    MemoryStart,
    average_slope,
    bounded_lsq,
    check_slope_ratio,
)


class EverettGrid:
    """Index bookkeeping for the nodes ``(j, k)``, ``j > k``, of an ``n``-interval grid."""

    def __init__(self, lo: float, hi: float, n: int) -> None:
        self.lo, self.hi, self.n = lo, hi, n
        self.h = (hi - lo) / n
        self.size = n * (n + 1) // 2
        self.rows, self.cols = np.tril_indices(n + 1, -1)  # flat index -> (j, k)
        self.flat = np.full((n + 1, n + 1), -1, dtype=int)
        self.flat[self.rows, self.cols] = np.arange(self.size)

    def cell(self, v: float) -> tuple[int, float]:
        t = (v - self.lo) / self.h
        j = min(max(int(t), 0), self.n - 1)
        return j, t - j

    def weights(self, a: float, b: float) -> list[tuple[int, float]]:
        """``E(a, b)`` as ``[(node flat index, weight)]`` (mirrors ``PreisachKernel.everett``)."""
        if a <= b:
            return []
        j, fa = self.cell(a)
        k, fb = self.cell(b)
        flat = self.flat
        if j == k:
            return [(flat[j + 1, j], fa - fb)]
        terms = [
            (flat[j, k], (1 - fa) * (1 - fb)),
            (flat[j + 1, k], fa * (1 - fb)),
            (flat[j, k + 1], (1 - fa) * fb),
            (flat[j + 1, k + 1], fa * fb),
        ]
        return [(i, w) for i, w in terms if i >= 0]  # E[k+1, k+1] is 0, not a node

    def mass_to_node(self) -> NDArray[np.float64]:
        """Matrix ``P`` with ``E_nodes = P @ mu_cells`` (same flat indexing for cells)."""
        j, k = self.rows, self.cols
        p, q = self.rows, self.cols
        return ((k[:, None] <= q[None, :]) & (p[None, :] <= j[:, None])).astype(float)

    def to_matrix(self, values: NDArray[np.float64]) -> NDArray[np.float64]:
        out = np.zeros((self.n + 1, self.n + 1))
        out[self.rows, self.cols] = values
        return out


def regressor_chunks(
    u: NDArray[np.float64], grid: EverettGrid, start: MemoryStart, capacity: int, chunk: int = 4096
) -> Iterator[NDArray[np.float64]]:
    """Yield blocks of regressor rows: ``y[t] = y_min + rows[t] @ E_nodes``.

    Walks the same turning-point stack as ``PreisachKernel.step`` (forward mode), carrying a
    row of node weights instead of an output value for each turning point.
    """
    lo, hi = grid.lo, grid.hi
    stack_u = np.zeros(capacity)
    stack_rows = np.zeros((capacity, grid.size))
    full = np.zeros(grid.size)
    full[grid.flat[grid.n, 0]] = 1.0  # y(hi) = y_min + E(hi, lo)
    stack_u[0], stack_rows[0] = hi, full
    # as PreisachModel.reset: "descending" falls from positive saturation to the first sample,
    # "ascending" rises from negative saturation
    if start.branch == "descending":
        depth, rising, cur_u, cur_row = 1, False, hi, full.copy()
    else:
        stack_u[1] = lo
        depth, rising, cur_u, cur_row = 2, True, lo, np.zeros(grid.size)
    signal = np.clip(u[start.index :], lo, hi)
    block = np.zeros((min(chunk, signal.size), grid.size))
    filled = 0
    for v in signal.tolist():
        if rising and v < cur_u or not rising and v > cur_u:
            if depth == capacity:
                depth -= 2
            stack_u[depth], stack_rows[depth] = cur_u, cur_row
            depth += 1
            rising = not rising
        if rising:
            while depth >= 3 and v >= stack_u[depth - 2]:
                depth -= 2
        else:
            while depth >= 3 and v <= stack_u[depth - 2]:
                depth -= 2
        anchor = float(stack_u[depth - 1])
        cur_row = stack_rows[depth - 1].copy()
        if rising:
            for index, weight in grid.weights(v, anchor):
                cur_row[index] += weight
        else:
            for index, weight in grid.weights(anchor, v):
                cur_row[index] -= weight
        cur_u = v
        block[filled] = cur_row
        filled += 1
        if filled == block.shape[0]:
            yield block
            filled = 0
    if filled:
        yield block[:filled]


def forc_everett(u: NDArray[np.float64], y: NDArray[np.float64], grid: EverettGrid) -> NDArray[np.float64]:
    """Everett nodes from the first-order descending curves in ``(u, y)``; see module docstring."""
    moving = np.flatnonzero(np.diff(u) != 0)
    if moving.size == 0:
        raise DataError("the input never moves; first-order reversal curves need sweeps")
    direction = np.sign(np.diff(u)[moving])
    # every run's first sample (an extremum), plus the record's last sample closing the last run
    starts = moving[np.r_[0, np.flatnonzero(np.diff(direction) != 0) + 1]]
    turns = np.r_[starts, u.size - 1]
    levels = grid.lo + grid.h * np.arange(grid.n + 1)
    band = 0.02 * (grid.hi - grid.lo)
    curves: list[tuple[float, NDArray[np.float64]]] = []
    for a, b, c in zip(turns[:-1], turns[1:], turns[2:]):
        # a: start of an ascending run (a minimum), b: its maximum, c: the next minimum
        if direction[np.searchsorted(moving, a)] <= 0 or u[a] > grid.lo + band:
            continue
        alpha = float(u[b])
        branch_u, branch_e = u[b : c + 1][::-1], (y[b] - y[b : c + 1])[::-1]
        order = np.argsort(branch_u, kind="stable")
        below = levels[levels <= alpha]
        curves.append((alpha, np.interp(below, branch_u[order], branch_e[order])))
    if len(curves) < 3:
        raise DataError(
            f"only {len(curves)} first-order reversal curves found (descending branches that start "
            "on the ascending major branch); record FORCs or use method='lsq'"
        )
    everett = np.zeros((grid.n + 1, grid.n + 1))
    for k in range(grid.n):
        known_alpha = [levels[k]] + [a for a, e in curves if e.size > k]
        known_e = [0.0] + [float(e[k]) for a, e in curves if e.size > k]
        order = np.argsort(known_alpha)
        everett[k + 1 :, k] = np.interp(levels[k + 1 :], np.array(known_alpha)[order], np.array(known_e)[order])
    return everett


class PreisachEstimator(HysteresisEstimator):
    """Identify a :class:`~edge.hysteresis.preisach.PreisachModel`.

    Args:
        n_levels: grid intervals ``n`` over the training input range (``n (n+1) / 2`` cells).
        method: ``"lsq"`` (any data) or ``"forc"`` (first-order reversal curves).
        capacity: turning-point stack capacity of the model.
        min_slope_ratio: lower bound of the slope right after a reversal (diagonal cell mass
            / grid step) relative to the average slope; see
            :data:`host.identify.common.MIN_SLOPE_DOC`.
    """

    def __init__(
        self,
        *,
        n_levels: int = 20,
        method: Literal["lsq", "forc"] = "lsq",
        capacity: int = 128,
        min_slope_ratio: float = 0.01,
    ) -> None:
        if n_levels < 2:
            raise ModelError(f"n_levels must be >= 2; got {n_levels}")
        if method not in ("lsq", "forc"):
            raise ModelError(f"method {method!r} unknown; use 'lsq' or 'forc'")
        self.n_levels = n_levels
        self.method = method
        self.capacity = capacity
        self.min_slope_ratio = check_slope_ratio(min_slope_ratio)

    def _parameter_count(self) -> int:
        return self.n_levels * (self.n_levels + 1) // 2 + 1

    def _identify(self, u: NDArray[np.float64], y: NDArray[np.float64], start: MemoryStart) -> PreisachModel:
        target = y[start.index :]
        grid = EverettGrid(float(u.min()), float(u.max()), self.n_levels)
        floor = self.min_slope_ratio * average_slope(u, y) * grid.h
        if self.method == "lsq":
            everett, y_min = self._least_squares(u, target, grid, start, floor)
            return PreisachModel((grid.lo, grid.hi), everett, y_min, capacity=self.capacity)
        masses = np.maximum(masses_from_everett(forc_everett(u, y, grid)), 0.0)
        for p in range(1, grid.n + 1):
            masses[p, p - 1] = max(masses[p, p - 1], floor)
        everett = everett_from_masses(masses)
        shape = PreisachModel((grid.lo, grid.hi), everett, 0.0, capacity=self.capacity)
        shape.reset(float(u[start.index]), start.branch)
        y_min = float(np.mean(target - shape.simulate(u[start.index :])))  # the output level
        return PreisachModel((grid.lo, grid.hi), everett, y_min, capacity=self.capacity)

    def _least_squares(
        self,
        u: NDArray[np.float64],
        target: NDArray[np.float64],
        grid: EverettGrid,
        start: MemoryStart,
        floor: float,
    ) -> tuple[NDArray[np.float64], float]:
        size = grid.size
        gram = np.zeros((size + 1, size + 1))
        rhs = np.zeros(size + 1)
        offset = 0
        for block in regressor_chunks(u, grid, start, self.capacity):
            rows = np.column_stack([block, np.ones(len(block))])
            part = target[offset : offset + len(block)]
            gram += rows.T @ rows
            rhs += rows.T @ part
            offset += len(block)
        transform = np.zeros((size + 1, size + 1))
        transform[:size, :size] = grid.mass_to_node()
        transform[size, size] = 1.0
        gram = transform.T @ gram @ transform
        rhs = transform.T @ rhs
        gram[np.diag_indices_from(gram)] += 1e-9 * np.trace(gram) / gram.shape[0]
        factor, _ = cho_factor(gram, lower=True)
        lower_factor = np.tril(factor)
        target_t = solve_triangular(lower_factor, rhs, lower=True)
        diagonal = grid.rows == grid.cols + 1
        lower = np.r_[np.where(diagonal, floor, 0.0), -np.inf]
        solution = bounded_lsq(lower_factor.T, target_t, lower)
        masses = grid.to_matrix(solution[:size])
        return everett_from_masses(masses), float(solution[size])
