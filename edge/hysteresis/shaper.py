"""Memoryless monotone shapers: dead-zone superpositions and their piecewise-linear form.

Dead-zone operator (Ai2019 eq 6)::

    S(x, g) = max(x - g, 0)  if g > 0
              x              if g = 0
              min(x - g, 0)  if g < 0

and the superposition ``s(x) = sum_j v_j S(x, g_j)`` (eq 7) is a continuous piecewise-linear
map through the origin whose slope changes by ``v_j`` at ``g_j``. It is stored here as knots
``(x_k, y_k)`` plus the slopes beyond the first and last knot, which makes inversion a swap of
coordinates. :func:`dead_zone_form` recovers ``(g, v)`` from knots, so Ai2019 eq 14
(the inverse's thresholds and weights) is checked against the swap in the tests.
"""

from __future__ import annotations

from bisect import bisect_right

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import ModelError


def dead_zone(x: NDArray[np.float64], threshold: float) -> NDArray[np.float64]:
    """Ai2019 eq 6 evaluated on an array."""
    if threshold > 0:
        return np.maximum(x - threshold, 0.0)
    if threshold < 0:
        return np.minimum(x - threshold, 0.0)
    return np.asarray(x, dtype=float)


class MonotonePiecewiseLinear:
    """Strictly increasing, continuous piecewise-linear map with linear extrapolation.

    Args:
        x_knots: strictly increasing abscissae (input units).
        y_knots: ordinates, strictly increasing (output units).
        slope_left: slope below the first knot (> 0).
        slope_right: slope above the last knot (> 0).
    """

    def __init__(self, x_knots: ArrayLike, y_knots: ArrayLike, slope_left: float, slope_right: float) -> None:
        self.x_knots = np.asarray(x_knots, dtype=float)
        self.y_knots = np.asarray(y_knots, dtype=float)
        self.slope_left = float(slope_left)
        self.slope_right = float(slope_right)
        if self.x_knots.ndim != 1 or self.x_knots.shape != self.y_knots.shape or not self.x_knots.size:
            raise ModelError("shaper knots must be two 1-D arrays of equal, non-zero length")
        if np.any(np.diff(self.x_knots) <= 0) or np.any(np.diff(self.y_knots) <= 0):
            raise ModelError("shaper is not strictly increasing; constrain the dead-zone slopes to be positive")
        if not (self.slope_left > 0 and self.slope_right > 0):
            raise ModelError(f"shaper end slopes must be > 0; got {slope_left}, {slope_right}")
        self.scalar = PiecewiseLinearKernel(self.kernel_stage()[1]).step
        """Evaluate one value (binary search over the knots, no array allocation)."""

    @classmethod
    def from_dead_zones(cls, thresholds: ArrayLike, weights: ArrayLike) -> MonotonePiecewiseLinear:
        """Build from Ai2019 eq 7: thresholds ``g_j`` (one of them 0) and weights ``v_j``."""
        g = np.asarray(thresholds, dtype=float)
        v = np.asarray(weights, dtype=float)
        if g.shape != v.shape or not np.any(g == 0):
            raise ModelError("dead-zone thresholds need one weight each and must include g=0")
        knots = np.unique(np.append(g, 0.0))
        y = sum(vj * dead_zone(knots, gj) for gj, vj in zip(g, v))
        slope_left = float(v[g <= 0].sum())
        slope_right = float(v[g >= 0].sum())
        return cls(knots, y, slope_left, slope_right)

    def __call__(self, x: ArrayLike) -> NDArray[np.float64]:
        """Evaluate on an array."""
        x = np.asarray(x, dtype=float)
        y = np.interp(x, self.x_knots, self.y_knots)
        below = x < self.x_knots[0]
        above = x > self.x_knots[-1]
        y[below] = self.y_knots[0] + self.slope_left * (x[below] - self.x_knots[0])
        y[above] = self.y_knots[-1] + self.slope_right * (x[above] - self.x_knots[-1])
        return y

    def inverse(self) -> MonotonePiecewiseLinear:
        """The inverse map (coordinates swapped, slopes inverted)."""
        return MonotonePiecewiseLinear(self.y_knots, self.x_knots, 1.0 / self.slope_left, 1.0 / self.slope_right)

    def kernel_stage(self) -> tuple[str, dict[str, NDArray[np.float64]]]:
        """This map as a ``pwl`` lookup-table stage."""
        return PiecewiseLinearKernel.stage, {
            "x_knots": self.x_knots,
            "y_knots": self.y_knots,
            "end_slopes": np.array([self.slope_left, self.slope_right]),
        }


def dead_zone_form(shaper: MonotonePiecewiseLinear) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Thresholds and weights ``(g, v)`` of eq 7 equal to ``shaper``.

    Representable only when the origin is a knot mapped to 0 with the same slope on both of
    its sides (eq 6 cannot bend at 0). A weight is the slope jump at its threshold, taken
    away from the origin: ``v_j = slope right - slope left`` for ``g_j > 0`` and
    ``slope left - slope right`` for ``g_j < 0``.
    """
    xk, yk = shaper.x_knots, shaper.y_knots
    origin = np.flatnonzero(xk == 0.0)
    if origin.size != 1 or yk[origin[0]] != 0.0:
        raise ModelError("a dead-zone superposition maps 0 to 0 at a knot; this shaper does not")
    slopes = np.concatenate([[shaper.slope_left], np.diff(yk) / np.diff(xk), [shaper.slope_right]])
    k0 = int(origin[0])
    if not np.isclose(slopes[k0], slopes[k0 + 1]):
        raise ModelError("shaper bends at the origin, which dead-zone operators cannot represent")
    jumps = slopes[1:] - slopes[:-1]  # jump at knot k
    v = np.where(xk > 0, jumps, -jumps)
    v[k0] = slopes[k0 + 1]
    return xk.copy(), v


class PiecewiseLinearKernel:
    """Per-tick evaluation of a :class:`MonotonePiecewiseLinear` by binary search."""

    stage = "pwl"

    def __init__(self, arrays: dict[str, NDArray[np.float64]]) -> None:
        self._x = arrays["x_knots"].tolist()
        self._y = arrays["y_knots"].tolist()
        self._slopes = (np.diff(arrays["y_knots"]) / np.diff(arrays["x_knots"])).tolist()
        self._left, self._right = arrays["end_slopes"].tolist()
        self._last = len(self._x) - 1

    def step(self, x: float) -> float:
        k = bisect_right(self._x, x) - 1
        if k < 0:
            return self._y[0] + self._left * (x - self._x[0])
        if k >= self._last:
            return self._y[-1] + self._right * (x - self._x[-1])
        return self._y[k] + self._slopes[k] * (x - self._x[k])
