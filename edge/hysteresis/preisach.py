"""Discrete Preisach model on an Everett map (Schreiber eqs 3-6).

Relays ``(a, b)`` with ``a >= b`` switch on when the input rises to ``a`` and off when it falls
to ``b``. With 0/1 relays and density ``mu >= 0`` the Everett function

    E(a, b) = integral of mu over {b <= beta <= alpha <= a}

is the output change along a first-order reversal curve, and the output follows from the
alternating stack of dominant turning points (wiping-out property)::

    rising from the turning point (u_m, y_m):   y = y_m + E(u, u_m)
    falling from the turning point (u_M, y_M):  y = y_M - E(u_M, u)

An input beyond the previous turning point of the other kind pops both (wiping-out), so a step
costs O(1) amortised. ``E`` lives on a uniform grid of ``n + 1`` levels: bilinear between nodes,
linear (``E = E[j+1, j] (t_a - t_b)``) in the diagonal half-cells so that ``E(a, a) = 0`` and
every branch is strictly increasing when the diagonal cells carry mass. A branch is then
piecewise linear in the input, so the inverse model (input: desired output) solves it exactly
by a binary search over the node values of the branch: this is the inverse Everett map ``G``
of eq 6 evaluated on demand. Forward and inverse share one memory: the stack holds
``(u, y)`` pairs and the inverse compares outputs where the forward compares inputs.

Stack depth is bounded (``capacity``): when full, the innermost (smallest, most recent) loop
is forgotten, an error no larger than that loop's Everett value.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import ModelError
from edge.hysteresis.base import HysteresisModel, check_range
from edge.hysteresis.table import LookupTable


def everett_from_masses(masses: NDArray[np.float64]) -> NDArray[np.float64]:
    """Everett nodes ``E[j, k] = sum_{k <= q < p <= j} mu[p, q]`` from cell masses ``mu[p, q]``."""
    # 2-D cumulative sum: over p upward, over q downward
    return np.flip(np.cumsum(np.flip(np.cumsum(np.tril(masses, -1), axis=0), axis=1), axis=1), axis=1)


def masses_from_everett(everett: NDArray[np.float64]) -> NDArray[np.float64]:
    """Cell masses ``mu[p, q]`` (p > q) from Everett nodes: the mixed second difference."""
    e = np.tril(np.asarray(everett, dtype=float), -1)
    size = e.shape[0]
    mu = np.zeros_like(e)
    for p in range(1, size):
        for q in range(p):
            mu[p, q] = (
                e[p, q]
                - e[p - 1, q]
                - (e[p, q + 1] if q + 1 < p else 0.0)
                + (e[p - 1, q + 1] if q + 1 < p - 1 else 0.0)
            )
    return mu


class PreisachKernel:
    """Per-tick forward or inverse Preisach evaluation on plain Python floats."""

    stage = "preisach"

    def __init__(self, arrays: dict[str, NDArray[np.float64]]) -> None:
        self._lo, self._hi, n = arrays["grid"].tolist()
        self._n = int(n)
        self._h = (self._hi - self._lo) / self._n
        self._e = arrays["everett"].tolist()
        self._inverted = bool(arrays["inverted"])
        self.su = arrays["stack_u"].tolist()
        self.sy = arrays["stack_y"].tolist()
        self.u, self.y, rising, depth = arrays["cursor"].tolist()
        self.rising, self.depth = bool(rising), int(depth)

    def arrays(self) -> dict[str, NDArray[np.float64]]:
        """Parameters and current state as arrays (the table form)."""
        return {
            "grid": np.array([self._lo, self._hi, self._n]),
            "everett": np.array(self._e),
            "inverted": np.array(float(self._inverted)),
            "stack_u": np.array(self.su),
            "stack_y": np.array(self.sy),
            "cursor": np.array([self.u, self.y, float(self.rising), float(self.depth)]),
        }

    def _cell(self, v: float) -> tuple[int, float]:
        t = (v - self._lo) / self._h
        j = int(t)
        if j >= self._n:
            j = self._n - 1
        elif j < 0:
            j = 0
        return j, t - j

    def everett(self, a: float, b: float) -> float:
        """``E(a, b)``, zero for ``a <= b``."""
        if a <= b:
            return 0.0
        j, fa = self._cell(a)
        k, fb = self._cell(b)
        e = self._e
        if j == k:
            return e[j + 1][j] * (fa - fb)
        return (1.0 - fb) * ((1.0 - fa) * e[j][k] + fa * e[j + 1][k]) + fb * (
            (1.0 - fa) * e[j][k + 1] + fa * e[j + 1][k + 1]
        )

    def _solve_rising(self, b: float, target: float) -> float:
        """The input ``a >= b`` with ``E(a, b) = target`` (clamped to the grid)."""
        if target <= 0.0:
            return b
        k, fb = self._cell(b)
        e = self._e

        def node(j: int) -> float:
            return (1.0 - fb) * e[j][k] + fb * e[j][k + 1]

        lo_j, hi_j = k + 1, self._n
        if node(hi_j) <= target:
            return self._hi
        while lo_j < hi_j:  # smallest j with node(j) >= target
            mid = (lo_j + hi_j) // 2
            if node(mid) >= target:
                hi_j = mid
            else:
                lo_j = mid + 1
        grid_j = self._lo + lo_j * self._h
        if lo_j == k + 1:
            return b + (grid_j - b) * target / node(lo_j)
        below = node(lo_j - 1)
        return grid_j - self._h + self._h * (target - below) / (node(lo_j) - below)

    def _solve_falling(self, a: float, target: float) -> float:
        """The input ``b <= a`` with ``E(a, b) = target`` (clamped to the grid)."""
        if target <= 0.0:
            return a
        j, fa = self._cell(a)
        e = self._e

        def node(k: int) -> float:
            return (1.0 - fa) * e[j][k] + fa * e[j + 1][k]

        if node(0) <= target:
            return self._lo
        lo_k, hi_k = 0, j
        while lo_k < hi_k:  # largest k with node(k) >= target
            mid = (lo_k + hi_k + 1) // 2
            if node(mid) >= target:
                lo_k = mid
            else:
                hi_k = mid - 1
        grid_k = self._lo + lo_k * self._h
        if lo_k == j:
            return a - (a - grid_k) * target / node(j)
        above = node(lo_k)
        return grid_k + self._h * (above - target) / (above - node(lo_k + 1))

    def _push(self) -> None:
        d = self.depth
        if d == len(self.su):  # full: forget the innermost loop
            d -= 2
        self.su[d] = self.u
        self.sy[d] = self.y
        self.depth = d + 1

    def step(self, v: float) -> float:
        """Forward: ``v`` is the input, returns the output. Inverse: the other way round."""
        inverted = self._inverted
        current = self.y if inverted else self.u
        if self.rising and v < current or not self.rising and v > current:
            self._push()
            self.rising = not self.rising
        keys = self.sy if inverted else self.su
        d = self.depth
        if self.rising:
            while d >= 3 and v >= keys[d - 2]:
                d -= 2
        else:
            while d >= 3 and v <= keys[d - 2]:
                d -= 2
        self.depth = d
        au, ay = self.su[d - 1], self.sy[d - 1]
        if inverted:
            self.y = v
            if self.rising:
                self.u = self._solve_rising(au, v - ay)
            else:
                self.u = self._solve_falling(au, ay - v)
            return self.u
        self.u = v
        self.y = ay + self.everett(v, au) if self.rising else ay - self.everett(au, v)
        return self.y


class PreisachModel(HysteresisModel):
    """Preisach model (see module docstring).

    Args:
        u_range: input interval covered by the Everett grid (inputs are clamped to it).
        everett: ``(n+1, n+1)`` Everett nodes; ``everett[j, k]`` for ``j > k`` on the uniform
            grid ``linspace(*u_range, n+1)``; the rest is ignored (treated as 0).
        y_min: output at negative saturation (all relays off).
        inverted: build the inverse model (input: output of the forward model).
        capacity: turning points kept (even, >= 4).
    """

    kind = "preisach"

    def __init__(
        self,
        u_range: tuple[float, float],
        everett: ArrayLike,
        y_min: float,
        *,
        inverted: bool = False,
        capacity: int = 128,
    ) -> None:
        lo, hi = check_range(*u_range, "Preisach u_range")
        e = np.tril(np.asarray(everett, dtype=float), -1)
        if e.ndim != 2 or e.shape[0] != e.shape[1] or e.shape[0] < 2:
            raise ModelError(f"Everett map must be square with >= 2 levels; got {e.shape}")
        mu = masses_from_everett(e)
        n = e.shape[0] - 1
        diagonal = np.array([mu[p, p - 1] for p in range(1, n + 1)])
        tolerance = 1e-9 * max(float(e[n, 0]), 1e-300)
        if np.any(np.tril(mu, -1) < -tolerance) or np.any(diagonal <= 0):
            raise ModelError(
                "Everett map is not a valid Preisach density (negative cell mass or empty "
                "diagonal cell); identify with non-negative masses and a positive diagonal"
            )
        if capacity < 4 or capacity % 2:
            raise ModelError(f"stack capacity must be even and >= 4; got {capacity}")
        self.u_range = (lo, hi)
        self.everett = e
        self.y_min = float(y_min)
        self.inverted = inverted
        self.capacity = capacity
        self._kernel = PreisachKernel(
            {
                "grid": np.array([lo, hi, n]),
                "everett": e,
                "inverted": np.array(float(inverted)),
                "stack_u": np.zeros(capacity),
                "stack_y": np.zeros(capacity),
                "cursor": np.array([lo, self.y_min, 1.0, 0.0]),
            }
        )
        self.reset(lo, "ascending")

    @property
    def n_levels(self) -> int:
        return self.everett.shape[0]

    @property
    def y_max(self) -> float:
        """Output at positive saturation (all relays on)."""
        return self.y_min + float(self.everett[-1, 0])

    @property
    def input_range(self) -> tuple[float, float]:
        return (self.y_min, self.y_max) if self.inverted else self.u_range

    def step(self, u: float) -> float:
        return self._kernel.step(self._clamp(float(u)))

    def _saturate(self, positive: bool) -> None:
        k = self._kernel
        lo, hi = self.u_range
        k.su[0], k.sy[0] = hi, self.y_max
        if positive:
            k.depth, k.rising, k.u, k.y = 1, False, hi, self.y_max
        else:
            k.su[1], k.sy[1] = lo, self.y_min
            k.depth, k.rising, k.u, k.y = 2, True, lo, self.y_min

    def get_state(self) -> dict[str, NDArray[np.float64]]:
        a = self._kernel.arrays()
        return {"stack_u": a["stack_u"], "stack_y": a["stack_y"], "cursor": a["cursor"]}

    def set_state(self, state: dict[str, NDArray[np.float64]]) -> None:
        k = self._kernel
        if np.asarray(state["stack_u"]).size != self.capacity:
            raise ModelError(f"Preisach state has a different stack capacity than {self.capacity}")
        k.su = np.asarray(state["stack_u"], dtype=float).tolist()
        k.sy = np.asarray(state["stack_y"], dtype=float).tolist()
        k.u, k.y, rising, depth = np.asarray(state["cursor"], dtype=float).tolist()
        k.rising, k.depth = bool(rising), int(depth)

    def inverse(self) -> PreisachModel:
        """Same Everett map and memory, driven by the output."""
        model = PreisachModel(
            self.u_range, self.everett, self.y_min, inverted=not self.inverted, capacity=self.capacity
        )
        model.set_state(self.get_state())
        return model

    def compile(self) -> LookupTable:
        return LookupTable.chain(self.kind, [(PreisachKernel.stage, self._kernel.arrays())], self.input_range)
