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
* ``compile()``: the lookup-table form (:class:`edge.hysteresis.lut.LookupTable`).
"""

from __future__ import annotations

import abc
import math
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import ModelError

Branch = Literal["ascending", "descending", "centered"]
"""Initial memory for ``reset``: arrived at ``u0`` from far below, from far above, or with no
memory at all (a demagnetised state centred on ``u0``)."""

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

    @abc.abstractmethod
    def reset(self, u0: float = 0.0, branch: Branch = "ascending") -> None:
        """Put the model into the memory state named by ``branch`` at input ``u0``."""

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
    def compile(self) -> LookupTable:  # noqa: F821  (imported lazily to avoid a cycle)
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
        if u < lo:
            self.saturated = True
            return lo
        if u > hi:
            self.saturated = True
            return hi
        self.saturated = False
        return u
