"""The bundle's neural state-space forward net on the edge (``pmactl train --model state-space``).

The step graph (:func:`host.train.state_space.export_onnx`) maps the pressure ``u`` [bar] and the
carried state ``x`` (1, nx) to the contraction ``y`` [mm] (``C x``, the output at this step) and
``x_next``. It needs no operator table: the hysteresis lives in the state. The state starts at
zeros (rest, the vented muscle) on every :meth:`StateSpaceForward.reset`.

:class:`StateSpaceNet` runs the onnxruntime session only (one session call per net step: a
few small MatMuls and a Tanh). :class:`StateSpaceForward` is the forward role, ``step(pressure_bar)
-> mm``: on a loop faster than the net's ``step_s`` the net steps every ``ticks_per_step`` ticks
and the output is extrapolated linearly in between from its last two net steps, as
:class:`edge.control.net_narmax.NetForward` does with its residual.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from edge.control.fused_graph import Choice
from edge.control.ort_session import tick_session
from edge.errors import BundleError

KIND = "state-space"


def is_state_space(spec: Mapping[str, object]) -> bool:
    """Whether a manifest net entry describes a state-space step graph."""
    return spec.get("model") == KIND


class StateSpaceNet:
    """One state-space step graph with its state ``x``; ``step(u) -> y``, ``reset()``.

    Args:
        path: the ``.onnx`` step graph.
        spec: the manifest's entry for it (``inputs`` ``["u", "x"]``, ``output`` ``"y"``, ``state``).
    """

    kind = KIND

    def __init__(self, path: str | Path, spec: Mapping[str, object]) -> None:
        import onnxruntime as ort  # on the SBC only when a bundle holds a net

        self.path = Path(path)
        state = spec.get("state")
        size = state[0].get("size") if isinstance(state, list) and state and isinstance(state[0], dict) else None
        if spec.get("inputs") != ["u", "x"] or spec.get("output") != "y" or not isinstance(size, int) or size < 1:
            raise BundleError(f"{self.path}: not a state-space step graph description in the manifest; re-export")
        self._session = tick_session(self.path, "the state-space net")
        declared = {i.name for i in self._session.get_inputs()}
        if declared != {"u", "x"}:
            raise BundleError(f"{self.path}: graph inputs {sorted(declared)} are not a state-space step; re-export")
        self.state_order = size
        self._u = np.zeros((1, 1), np.float32)
        self._y = np.zeros((1, 1), np.float32)
        self._x = np.zeros((1, size), np.float32)
        self._x_next = np.zeros((1, size), np.float32)
        binding = self._session.io_binding()
        value = ort.OrtValue.ortvalue_from_numpy
        binding.bind_ortvalue_input("u", value(self._u))
        binding.bind_ortvalue_input("x", value(self._x))
        binding.bind_ortvalue_output("y", value(self._y))
        binding.bind_ortvalue_output("x_next", value(self._x_next))
        self._binding = binding
        self.choice = Choice("onnxruntime", "state-space step graph: onnxruntime only (no fused evaluator)")

    def reset(self) -> None:
        """State back to zeros: rest (on arming)."""
        self._x.fill(0.0)

    def step(self, u: float) -> float:
        """``y`` [mm] at this step for the pressure ``u`` [bar] (NaN when not finite); the state advances."""
        self._u[0, 0] = u
        self._session.run_with_iobinding(self._binding)
        np.copyto(self._x, self._x_next)
        y = float(self._y[0, 0])
        return y if math.isfinite(y) else math.nan


class StateSpaceForward:
    """The state-space forward model: ``step(pressure_bar) -> mm``, ``reset()`` on arming.

    Args:
        net: the step graph's evaluator.
        ticks_per_step: loop ticks per net step (see module docstring).
    """

    input_range = (-math.inf, math.inf)

    def __init__(self, net: StateSpaceNet, ticks_per_step: int) -> None:
        if ticks_per_step < 1:
            raise BundleError(f"{net.path}: ticks_per_step {ticks_per_step} must be at least 1")
        self.net, self.ticks_per_step = net, ticks_per_step
        self.kind = net.kind
        self.reset()

    def reset(self) -> None:
        """State to rest (zeros), extrapolation cleared."""
        self.net.reset()
        self._count = 0
        self._y = self._slope = 0.0
        self._first = True

    def step(self, pressure_bar: float) -> float:
        """The contraction [mm] at this tick for this tick's pressure [bar]."""
        count = self._count
        if count == 0:
            y = self.net.step(pressure_bar)
            self._slope = 0.0 if self._first else (y - self._y) / self.ticks_per_step
            self._y, self._first = y, False
        self._count = count + 1 if count + 1 < self.ticks_per_step else 0
        return self._y + self._slope * count

    def simulate(self, values: Sequence[float] | np.ndarray) -> np.ndarray:
        """``step`` over every value from the current state."""
        return np.array([self.step(float(v)) for v in np.asarray(values, float).tolist()])
