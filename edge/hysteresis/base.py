"""What every hysteresis model in pmactl provides.

A model maps an input signal to an output signal with memory. Each one offers

* ``step(u) -> y``: one tick, O(number of operators), no array allocation;
* ``simulate(u_array) -> y_array``: the same as calling ``step`` on every sample, from the
  current state, leaving the model in the final state;
* explicit state: ``reset(u0, branch)``, ``get_state()`` / ``set_state()``;
* ``inverse()``: the inverse model as an object of the same interface;
* ``input_range``: inputs outside it are clamped to it and ``saturated`` is set for that step.
  For an inverse this is the range of outputs the actuator can reach: a desired output beyond
  it is clamped and flagged, never NaN;
* ``compile()``: the lookup-table form (:class:`edge.hysteresis.table.LookupTable`).
"""

from __future__ import annotations

import abc
import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import ModelError
from edge.hysteresis.table import LookupTable

Branch = Literal["ascending", "descending", "centered"]
"""Initial memory for ``reset``: arrived at ``u0`` from the bottom of the model's range
(negative saturation), from its top (positive saturation), or demagnetised around ``u0`` by a
decaying alternation inside the range. Every state is one a real input inside the range can
produce, so a forward model and its inverse reset with the same branch at corresponding
points (``u0`` and the forward output at ``u0``) hold the same memory."""

DEMAGNETISE_CYCLES = 64

BRANCHES: tuple[str, ...] = ("ascending", "descending", "centered")


def check_branch(branch: str) -> None:
    """Raise :class:`ModelError` unless ``branch`` is one of :data:`BRANCHES`."""
    if branch not in BRANCHES:
        raise ModelError(f"branch {branch!r} unknown; use one of {', '.join(BRANCHES)}")


def as_signal(u: ArrayLike, name: str = "u") -> NDArray[np.float64]:
    """Return ``u`` as a finite 1-D float array or raise :class:`ModelError`."""
    arr = np.asarray(u, dtype=float)
    if arr.ndim != 1:
        raise ModelError(f"{name} must be a 1-D signal; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ModelError(f"{name} contains NaN or inf; clean the signal before simulating")
    return arr


def check_range(lo: float, hi: float, what: str) -> tuple[float, float]:
    """Validate an interval ``lo < hi`` (infinite ends allowed) and return it as floats."""
    lo, hi = float(lo), float(hi)
    if math.isnan(lo) or math.isnan(hi) or not lo < hi:
        raise ModelError(f"{what} ({lo}, {hi}) is empty or NaN; give lo < hi")
    return lo, hi


_FLAG_TOLERANCE = 1e-9


def clamp_and_flag(u: float, lo: float, hi: float) -> tuple[float, bool]:
    """``u`` clamped to ``[lo, hi]`` and whether it was beyond by more than rounding.

    Overshoot below ``1e-9 * (1 + |bound|)`` is clamped silently: it is what a forward model's
    output at the end of its range looks like after floating-point rounding.
    """
    if u < lo:
        return lo, lo - u > _FLAG_TOLERANCE * (1.0 + abs(lo))
    if u > hi:
        return hi, u - hi > _FLAG_TOLERANCE * (1.0 + abs(hi))
    return u, False


def clip_signal(signal: NDArray[np.float64], lo: float, hi: float) -> tuple[NDArray[np.float64], bool]:
    """A whole signal clamped to ``[lo, hi]`` and whether its last sample was flagged."""
    clipped = np.clip(signal, lo, hi)
    return clipped, bool(signal.size) and clamp_and_flag(float(signal[-1]), lo, hi)[1]


class HysteresisModel(abc.ABC):
    """Interface shared by PI, MPI, DPI and Preisach models (see module docstring)."""

    kind: str = "abstract"
    saturated: bool = False

    @property
    @abc.abstractmethod
    def input_range(self) -> tuple[float, float]:
        """Inputs are clamped to this closed interval (units of the model input)."""

    @abc.abstractmethod
    def step(self, u: float) -> float:
        """Advance one sample with input ``u`` and return the output."""

    @property
    def memory_range(self) -> tuple[float, float]:
        """Finite input interval whose ends saturate the memory (default: ``input_range``)."""
        return self.input_range

    @abc.abstractmethod
    def _saturate(self, positive: bool) -> None:
        """Set the state reached at the top (``positive``) or bottom of ``memory_range``."""

    def reset(self, u0: float = 0.0, branch: Branch = "ascending") -> None:
        """Put the model into the memory state named by ``branch`` (see :data:`Branch`) at ``u0``."""
        check_branch(branch)
        lo, hi = self.memory_range
        target = min(hi, max(lo, float(u0)))
        self._saturate(positive=branch == "descending")
        if branch == "centered":
            for i in range(DEMAGNETISE_CYCLES, 0, -1):
                amplitude = i / DEMAGNETISE_CYCLES * (hi - lo)
                self.step(min(hi, target + amplitude))
                self.step(max(lo, target - amplitude))
        self.step(target)
        self.saturated = False

    @abc.abstractmethod
    def get_state(self) -> dict[str, NDArray[np.float64]]:
        """A copy of the full memory state (save/restore with :meth:`set_state`)."""

    @abc.abstractmethod
    def set_state(self, state: dict[str, NDArray[np.float64]]) -> None:
        """Restore a state returned by :meth:`get_state` of a model with equal parameters."""

    @abc.abstractmethod
    def inverse(self) -> HysteresisModel:
        """The inverse model: its input is this model's output and vice versa."""

    @abc.abstractmethod
    def compile(self) -> LookupTable:
        """The lookup-table form of this model in its current state."""

    def simulate(self, u: ArrayLike) -> NDArray[np.float64]:
        """Run :meth:`step` over every sample of ``u`` from the current state."""
        signal = as_signal(u)
        out = np.empty_like(signal)
        step = self.step
        for i, value in enumerate(signal.tolist()):
            out[i] = step(value)
        return out

    def _clamp(self, u: float) -> float:
        lo, hi = self.input_range
        value, self.saturated = clamp_and_flag(u, lo, hi)
        return value
