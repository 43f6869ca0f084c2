"""The bundle's LSTM-NARMAX nets on the edge: one ONNX step graph each, state carried by the edge.

A net step graph (``models_export.onnx_step``) maps the step inputs ``u`` and ``n`` and the
carried state (``u_lag``, ``n_lag``, ``y_lag``, LSTM ``h`` and ``c``) to ``y`` and the next
state. :class:`NarmaxNet` runs it tick by tick: the onnxruntime session with bound,
preallocated buffers, and the fused numpy step compiled from the same verified file
(:func:`edge.control.fused_graph.narmax_from_graph`), kept only when it reproduces the session
on a probe trajectory and is faster (:attr:`NarmaxNet.choice`).

Two roles use it (:mod:`edge.control.net_roles` builds them from a bundle):

* :class:`NetInverse`, the feedforward: desired contraction [mm] -> pressure [bar]. ``u`` is the
  target, ``n`` the bundle's rate-independent inverse table at that target, ``y`` the command;
  the net adds what the table cannot know (valve lag, speed-dependent friction);
* :class:`NetForward`, the forward model a twin runs: pressure [bar] -> contraction [mm], ``n``
  the tanh-warped PI operator table the net was trained on (Wu2025).

A net was trained at its recording's sample period (``step_s`` in the manifest, 10 ms for
``edge record``'s default 100 Hz). On a faster loop it steps every ``ticks_per_step`` ticks;
the table under it steps every tick and the net's residual ``y - n`` is extrapolated linearly in
between (from its last two net steps), so the output follows the reference at the loop rate and
the rate-dependent part does not lag by half a net step.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Protocol

import numpy as np

from edge.control.fused import FusedNarmax
from edge.control.fused_graph import Choice, choose, narmax_from_graph
from edge.control.onnx_graph import GraphFormatError, read_graph
from edge.control.ort_session import tick_session
from edge.errors import BundleError
from edge.hysteresis.lut import CompiledModel

STATE_NAMES = ("u_lag", "n_lag", "y_lag", "h", "c")
PROBE_STEPS = 400  # parity probe: a two-tone trajectory over the net's training ranges
WARMUP_RUNS = 100


class StepNet(Protocol):
    """A net step graph with its carried state (:class:`NarmaxNet`,
    :class:`edge.control.net_hammerstein.HammersteinNet`)."""

    path: Path
    kind: str  # the model family: "lstm-narmax" | "hammerstein"
    choice: Choice  # which evaluator runs it, and why

    def reset(self) -> None: ...

    def step(self, u: float, n: float) -> float: ...


class NarmaxNet:
    """One LSTM-NARMAX step graph with its state; ``step(u, n) -> y``, ``reset()``.

    Args:
        path: the ``.onnx`` step graph.
        spec: the manifest's entry for it (``inputs``, ``output``, ``state``, ``u_range``,
            ``n_range``; see ``models_export.bundle``).

    Start (after :meth:`reset`): the first step sets the lags to its own inputs (``y(-1) = n``)
    and zeroes the LSTM state, as the trainer's free runs start.
    """

    kind = "lstm-narmax"

    def __init__(self, path: str | Path, spec: Mapping[str, object]) -> None:
        import onnxruntime as ort  # on the SBC only when a bundle holds a net

        self.path = Path(path)
        state = spec.get("state")
        sizes = {str(s.get("input")): int(s.get("size", 0)) for s in state} if isinstance(state, list) else {}
        if list(sizes) != list(STATE_NAMES) or spec.get("inputs") != ["u", "n"] or spec.get("output") != "y":
            raise BundleError(f"{self.path}: not an LSTM-NARMAX step graph description in the manifest; re-export")
        self._session = tick_session(self.path)
        declared = {i.name for i in self._session.get_inputs()}
        if declared != {"u", "n", *STATE_NAMES}:
            raise BundleError(f"{self.path}: graph inputs {sorted(declared)} are not an LSTM-NARMAX step; re-export")
        self._u = np.zeros((1, 1), np.float32)
        self._n = np.zeros((1, 1), np.float32)
        self._y = np.zeros((1, 1), np.float32)
        self._state_in = {name: np.zeros((1, sizes[name]), np.float32) for name in STATE_NAMES}
        self._state_out = {name: np.zeros((1, sizes[name]), np.float32) for name in STATE_NAMES}
        self._pairs = [(self._state_in[name], self._state_out[name]) for name in STATE_NAMES]
        binding = self._session.io_binding()
        value = ort.OrtValue.ortvalue_from_numpy
        binding.bind_ortvalue_input("u", value(self._u))
        binding.bind_ortvalue_input("n", value(self._n))
        binding.bind_ortvalue_output("y", value(self._y))
        for name in STATE_NAMES:
            binding.bind_ortvalue_input(name, value(self._state_in[name]))
            binding.bind_ortvalue_output(f"{name}_out", value(self._state_out[name]))
        self._binding = binding
        for _ in range(WARMUP_RUNS):
            self._session.run_with_iobinding(binding)
        self._fused: FusedNarmax | None = None
        try:
            self._fused = narmax_from_graph(read_graph(self.path))
        except GraphFormatError:
            self._fused = None
        self._fresh = True
        self._use_fused = False
        self.choice = self._choose(spec)

    def _choose(self, spec: Mapping[str, object]) -> Choice:
        u_lo, u_hi = _range(spec.get("u_range"), (0.0, 1.0))
        n_lo, n_hi = _range(spec.get("n_range"), (u_lo, u_hi))
        t = np.arange(PROBE_STEPS) / PROBE_STEPS
        shape = 0.5 + 0.4 * np.sin(2 * np.pi * 3 * t) + 0.1 * np.sin(2 * np.pi * 17 * t)
        probes = np.column_stack([u_lo + (u_hi - u_lo) * shape, n_lo + (n_hi - n_lo) * shape]).tolist()
        fused = None if self._fused is None else self._fused_probe
        choice = choose(self._onnx_probe, fused, probes, self.reset)
        self._use_fused = choice.evaluator == "numpy-fused"
        self.reset()
        return choice

    def _onnx_probe(self, row: Sequence[float]) -> float:
        self._use_fused = False
        return self.step(row[0], row[1])

    def _fused_probe(self, row: Sequence[float]) -> float:
        self._use_fused = True
        return self.step(row[0], row[1])

    def reset(self) -> None:
        """Forget the state: the next step starts the net afresh (on arming)."""
        self._fresh = True

    def _start(self, u: float, n: float) -> None:
        for name, array in self._state_in.items():
            array.fill(u if name == "u_lag" else n if name in ("n_lag", "y_lag") else 0.0)
        if self._fused is not None:
            self._fused.reset(u, n)
        self._fresh = False

    def step(self, u: float, n: float) -> float:
        """``y`` for this step's ``u`` and ``n`` (NaN when the net's output is not finite)."""
        if self._fresh:
            self._start(u, n)
        if self._use_fused and self._fused is not None:
            y = self._fused.step(u, n)
        else:
            self._u[0, 0], self._n[0, 0] = u, n
            self._session.run_with_iobinding(self._binding)
            for state_in, state_out in self._pairs:
                np.copyto(state_in, state_out)
            y = float(self._y[0, 0])
        return y if math.isfinite(y) else math.nan


def _range(value: object, default: tuple[float, float]) -> tuple[float, float]:
    if isinstance(value, list) and len(value) == 2 and all(isinstance(v, int | float) for v in value):
        return float(value[0]), float(value[1])
    return default


class _HeldResidual:
    """A table stepped every tick plus a net's residual ``y - n`` updated every ``ticks_per_step``."""

    def __init__(self, net: StepNet, table: CompiledModel, ticks_per_step: int) -> None:
        if ticks_per_step < 1:
            raise BundleError(f"{net.path}: ticks_per_step {ticks_per_step} must be at least 1")
        self.net, self.table, self.ticks_per_step = net, table, ticks_per_step
        self.input_range = table.input_range
        self._count = 0
        self._residual = self._slope = 0.0
        self._first = True

    def reset(self) -> None:
        """Table memory back to its rest state, net state cleared (on arming)."""
        self.table.reset()
        self.net.reset()
        self._count = 0
        self._residual = self._slope = 0.0
        self._first = True

    def _held(self, u: float, n: float) -> float:
        count = self._count
        if count == 0:
            residual = self.net.step(u, n) - n
            # the residual's change per tick, for the ticks until the next net step (first: none)
            self._slope = 0.0 if self._first else (residual - self._residual) / self.ticks_per_step
            self._residual, self._first = residual, False
        self._count = count + 1 if count + 1 < self.ticks_per_step else 0
        return n + self._residual + self._slope * count

    def simulate(self, values: Sequence[float] | np.ndarray) -> np.ndarray:
        """``step`` over every value from the current state."""
        return np.array([self.step(float(v)) for v in np.asarray(values, float).tolist()])

    def step(self, value: float) -> float:  # pragma: no cover - defined by the subclasses
        raise NotImplementedError


class NetInverse(_HeldResidual):
    """The net feedforward: ``step(target_mm) -> bar``, ``reset()`` on arming (see module docstring).

    Args:
        net: the inverse step graph (``u`` desired contraction [mm], ``n`` table inverse [bar]).
        table: the bundle's inverse table (its memory is this feedforward's memory).
        ticks_per_step: loop ticks per net step (the net's ``step_s`` over the loop period).
    """

    kind = "lstm-narmax-inverse"

    def __init__(self, net: StepNet, table: CompiledModel, ticks_per_step: int, preview_s: float = 0.0) -> None:
        super().__init__(net, table, ticks_per_step)
        self.preview_s = preview_s  # the controller steps this inverse with the reference this far ahead [s]

    def step(self, target_mm: float) -> float:
        return self._held(target_mm, self.table.step(target_mm))


class NetForward(_HeldResidual):
    """The net forward model: ``step(pressure_bar) -> mm``, ``reset()`` on arming.

    Args:
        net: the forward step graph (``u`` pressure [bar], ``n`` the operator's output [mm]): an
            LSTM-NARMAX or a Hammerstein (:mod:`edge.control.net_hammerstein`).
        table: the operator table (tanh-PI indexed by the warped pressure, or the Hammerstein's MPI).
        ticks_per_step: loop ticks per net step.
        warp_centre, warp_half_range: the operator's input warp ``tanh((p - centre) / half_range)``
            (no warp when ``warp_half_range`` is 0).
    """

    def __init__(
        self, net: StepNet, table: CompiledModel, ticks_per_step: int, warp_centre: float, warp_half_range: float
    ) -> None:
        super().__init__(net, table, ticks_per_step)
        self.kind = net.kind
        self.warp_centre, self.warp_half_range = warp_centre, warp_half_range
        self.input_range = (-math.inf, math.inf) if warp_half_range > 0 else table.input_range

    def step(self, pressure_bar: float) -> float:
        x = pressure_bar
        if self.warp_half_range > 0:
            x = math.tanh((pressure_bar - self.warp_centre) / self.warp_half_range)
        return self._held(pressure_bar, self.table.step(x))
