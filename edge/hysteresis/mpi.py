"""Modified PI model (Kuhnen; Ai2019 eq 8): a PI model followed by a dead-zone shaper.

Forward: ``y = s(PI[u])``; inverse: ``u = PI^-1[s^-1(y)]`` (Ai2019 eq 12). The shaper ``s`` is
a :class:`~edge.hysteresis.shaper.MonotonePiecewiseLinear` (a dead-zone superposition plus
offsets), so the inverse shaper is a swap of knot coordinates and the inverse PI comes from
:func:`~edge.hysteresis.pi.inverse_pi_parameters`. The memory lives in the PI part only.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.hysteresis.base import Branch, HysteresisModel, as_signal, clip_signal
from edge.hysteresis.pi import PIModel
from edge.hysteresis.shaper import MonotonePiecewiseLinear
from edge.hysteresis.table import LookupTable


class MPIModel(HysteresisModel):
    """``y = shaper(pi(u))``, or with ``shaper_first=True`` ``y = pi(shaper(u))`` (the inverse form).

    Args:
        pi: the PI part (owns the memory).
        shaper: the memoryless monotone map.
        shaper_first: evaluation order; ``False`` for a forward MPI model.
    """

    kind = "mpi"

    def __init__(self, pi: PIModel, shaper: MonotonePiecewiseLinear, *, shaper_first: bool = False) -> None:
        self.pi = pi
        self.shaper = shaper
        self.shaper_first = shaper_first
        self._input_range = self._outer(pi.input_range)
        self._memory_range = self._outer(pi.memory_range)

    def _outer(self, bounds: tuple[float, float]) -> tuple[float, float]:
        """PI-input bounds as bounds of this model's input (through the shaper if it comes first)."""
        if not self.shaper_first:
            return bounds
        inverse = self.shaper.inverse()
        lo, hi = (float(inverse(np.array([b]))[0]) if math.isfinite(b) else b for b in bounds)
        return lo, hi

    @property
    def input_range(self) -> tuple[float, float]:
        return self._input_range

    @property
    def memory_range(self) -> tuple[float, float]:
        return self._memory_range

    def step(self, u: float) -> float:
        u = self._clamp(float(u))
        if self.shaper_first:
            return self.pi.step(self.shaper.scalar(u))
        return self.shaper.scalar(self.pi.step(u))

    def simulate(self, u: ArrayLike) -> NDArray[np.float64]:
        signal = as_signal(u)
        clipped, self.saturated = clip_signal(signal, *self.input_range)
        if self.shaper_first:
            return self.pi.simulate(self.shaper(clipped))
        return self.shaper(self.pi.simulate(clipped))

    def _saturate(self, positive: bool) -> None:
        self.pi._saturate(positive)

    def reset(self, u0: float = 0.0, branch: Branch = "ascending") -> None:
        """The memory is the PI part's: reset it at the PI input corresponding to ``u0``."""
        u0 = self._clamp(float(u0))
        self.pi.reset(self.shaper.scalar(u0) if self.shaper_first else u0, branch)
        self.saturated = False

    def get_state(self) -> dict[str, NDArray[np.float64]]:
        return self.pi.get_state()

    def set_state(self, state: dict[str, NDArray[np.float64]]) -> None:
        self.pi.set_state(state)

    def inverse(self) -> MPIModel:
        """``PI^-1 o shaper^-1``, clamping desired outputs to the reachable range."""
        if self.shaper_first:
            return MPIModel(self.pi.inverse(), self.shaper.inverse(), shaper_first=False)
        return MPIModel(self.pi.inverse(), self.shaper.inverse(), shaper_first=True)

    def compile(self) -> LookupTable:
        stages = [self.pi.kernel_stage(), self.shaper.kernel_stage()]
        if self.shaper_first:
            stages.reverse()
        return LookupTable.chain(self.kind, stages, self.input_range)
