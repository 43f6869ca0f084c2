"""The neural correction of the feedforward: one ONNX model run by onnxruntime every tick.

The bundle's manifest describes the model (``correction`` entry)::

    {"file": "correction.onnx",
     "features": ["reference_mm", "reference_rate_mm_s", "feedforward_bar"],
     "input": "features", "output": "correction_bar",
     "state": {"input": "h_in", "output": "h_out", "size": 8}}      # optional, recurrent nets

The input is float32 ``[1, len(features)]`` (any normalisation lives inside the graph), the
output float32 ``[1, 1]`` in bar, the optional recurrent state float32 ``[1, size]``: its output is
fed back as the next tick's input and zeroed on re-arm. The session is checked against this
description when it is opened, and refused with the mismatch named. One session, one thread,
I/O bound to preallocated arrays (no allocation per tick), warmed up before the loop starts.

A stateless net that is a chain of affine layers and tanh is also compiled, from the same
verified file, into a fused numpy step (:mod:`edge.control.fused_graph`); it runs the ticks
only if it reproduces the session on probe inputs and is faster on this machine
(:attr:`NeuralCorrection.choice` records which evaluator runs, why, and the timings).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from edge.control.fused_graph import Choice, choose, mlp_from_graph
from edge.control.onnx_graph import GraphFormatError, read_graph
from edge.control.ort_session import tick_session
from edge.errors import BundleError

FEATURES = (
    "reference_mm",
    "reference_rate_mm_s",
    "feedforward_bar",
    "contraction_mm",
    "pressure_bar",
    "previous_command_bar",
)
WARMUP_RUNS = 200
PROBES = 200  # parity probes: normal inputs at scales 1, 10 and 100 (features are in mm, bar, mm/s)


def _shape_matches(declared: list[object], expected: tuple[int, ...]) -> bool:
    if len(declared) != len(expected):
        return False
    # a symbolic dimension (None or a name such as "batch") accepts any size
    return all(not isinstance(d, int) or d == e for d, e in zip(declared, expected))


class NeuralCorrection:
    """An ONNX correction model [bar] with its manifest description (see module docstring).

    Args:
        model_path: the ``.onnx`` file.
        spec: the manifest's ``correction`` entry.
    """

    def __init__(self, model_path: str | Path, spec: Mapping[str, object]) -> None:
        import onnxruntime as ort  # on the SBC only when a bundle has a correction

        self.path = Path(model_path)
        features = list(spec.get("features", []))  # type: ignore[call-overload]
        unknown = [f for f in features if f not in FEATURES]
        if not features or unknown:
            raise BundleError(
                f"{self.path}: correction features {unknown or features} not usable; choose from {', '.join(FEATURES)}"
            )
        self.features = tuple(features)
        self._feature_index = [FEATURES.index(f) for f in features]
        self.input_name = str(spec.get("input", ""))
        self.output_name = str(spec.get("output", ""))
        state = spec.get("state")
        self.state_names: tuple[str, str] | None = None
        state_size = 0
        if state is not None:
            assert isinstance(state, Mapping)
            self.state_names = (str(state.get("input")), str(state.get("output")))
            size = state.get("size", 0)
            state_size = int(size) if isinstance(size, int | float | str) else 0
            if state_size <= 0:
                raise BundleError(f"{self.path}: correction state size must be a positive integer")
        self._session = tick_session(self.path, "the model")
        self._x = np.zeros((1, len(features)), dtype=np.float32)
        self._y = np.zeros((1, 1), dtype=np.float32)
        self._h_in = np.zeros((1, state_size), dtype=np.float32)
        self._h_out = np.zeros((1, state_size), dtype=np.float32)
        self._check_signature()
        self._binding = self._session.io_binding()
        value = ort.OrtValue.ortvalue_from_numpy
        self._binding.bind_ortvalue_input(self.input_name, value(self._x))
        self._binding.bind_ortvalue_output(self.output_name, value(self._y))
        if self.state_names:
            self._binding.bind_ortvalue_input(self.state_names[0], value(self._h_in))
            self._binding.bind_ortvalue_output(self.state_names[1], value(self._h_out))
        self._warm_up()
        self._fused_step = self._fused_or_none(state_size)
        self.choice = self._choose()

    def _fused_or_none(self, state_size: int) -> Callable[[Sequence[float]], float] | None:
        if state_size:
            return None  # recurrent corrections run in onnxruntime (no fused form of a generic cell)
        try:
            return mlp_from_graph(read_graph(self.path), self.input_name, self.output_name, len(self.features)).step
        except GraphFormatError:
            return None

    def _choose(self) -> Choice:
        rng = np.random.default_rng(0)
        n = len(self.features)
        probes = (rng.normal(0.0, 1.0, (PROBES, n)) * 10.0 ** rng.integers(0, 3, (PROBES, 1))).tolist()
        choice = choose(self._onnx_step, self._fused_step, probes, self.reset)
        if choice.evaluator != "numpy-fused":
            self._fused_step = None
        return choice

    def _onnx_step(self, x: Sequence[float]) -> float:
        row = self._x[0]
        for column in range(row.size):
            row[column] = x[column]
        self._session.run_with_iobinding(self._binding)
        if self.state_names:
            np.copyto(self._h_in, self._h_out)
        return float(self._y[0, 0])

    def _check_signature(self) -> None:
        declared_in = {i.name: i for i in self._session.get_inputs()}
        declared_out = {o.name: o for o in self._session.get_outputs()}
        wanted_in = {self.input_name: self._x.shape}
        wanted_out = {self.output_name: self._y.shape}
        if self.state_names:
            wanted_in[self.state_names[0]] = self._h_in.shape
            wanted_out[self.state_names[1]] = self._h_out.shape
        if set(declared_in) != set(wanted_in):
            raise BundleError(
                f"{self.path}: model inputs {sorted(declared_in)} do not match the manifest's {sorted(wanted_in)}; "
                "re-export the bundle"
            )
        missing = set(wanted_out) - set(declared_out)
        if missing:
            raise BundleError(
                f"{self.path}: model has no output {sorted(missing)} (it has {sorted(declared_out)}); "
                "re-export the bundle"
            )
        for kind, declared, wanted in (("input", declared_in, wanted_in), ("output", declared_out, wanted_out)):
            for name, shape in wanted.items():
                arg = declared[name]
                if arg.type != "tensor(float)" or not _shape_matches(list(arg.shape), shape):
                    raise BundleError(
                        f"{self.path}: {kind} {name!r} is {arg.type} {list(arg.shape)}, the manifest needs "
                        f"tensor(float) {list(shape)}; re-export the bundle"
                    )

    def _warm_up(self) -> None:
        for _ in range(WARMUP_RUNS):
            self._session.run_with_iobinding(self._binding)
        self.reset()

    def reset(self) -> None:
        """Zero the recurrent state (on arm)."""
        self._h_in.fill(0.0)
        self._h_out.fill(0.0)

    def step(self, values: tuple[float, ...]) -> float:
        """Correction [bar] for this tick; ``values`` in :data:`FEATURES` order."""
        x = [values[index] for index in self._feature_index]
        result = self._fused_step(x) if self._fused_step is not None else self._onnx_step(x)
        return result if math.isfinite(result) else math.nan
