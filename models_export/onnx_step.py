"""ONNX export of the trained nets: one graph per step, recurrent state as explicit inputs/outputs.

onnxruntime is stateless by design, so every quantity a step carries to the next (LSTM ``h``
and ``c``, every lag buffer, the ARX's past outputs and net outputs) is a graph input and the
matching ``*_out`` a graph output; the caller copies outputs to inputs between steps and zeroes
them on arming. Shapes are static, batch 1, float32, opset 18.

Exported with torch's TorchScript-based exporter (``dynamo=False``): the dynamo exporter of
torch 2.13 needs ``onnxscript``, which is not a dependency of pmactl, and a fixed-shape
single-step graph is exactly what tracing captures. The graph is checked with
``onnx.checker`` after export.

The hysteresis operator itself is not in the graph: its output ``n`` is an input, computed by
the same numpy operator (lookup table on the edge) that produced it in training.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from host.train.hammerstein import HammersteinWeights
    from host.train.lstm_narmax import NarmaxWeights

OPSET = 18


@dataclass(frozen=True)
class StateSpec:
    """One carried tensor: graph input name, output name, shape."""

    input: str
    output: str
    size: int


@dataclass(frozen=True)
class StepSpec:
    """The signature of a step graph: per-step inputs (each [1, 1]), output, carried state."""

    inputs: tuple[str, ...]
    output: str
    state: tuple[StateSpec, ...]

    def as_dict(self) -> dict[str, object]:
        return {
            "inputs": list(self.inputs),
            "output": self.output,
            "state": [{"input": s.input, "output": s.output, "size": s.size} for s in self.state],
            "opset": OPSET,
        }


NARMAX_SPEC = StepSpec(
    ("u", "n"),
    "y",
    (
        StateSpec("u_lag", "u_lag_out", 1),
        StateSpec("n_lag", "n_lag_out", 1),
        StateSpec("y_lag", "y_lag_out", 1),
        StateSpec("h", "h_out", 7),
        StateSpec("c", "c_out", 7),
    ),
)
HAMMERSTEIN_SPEC = StepSpec(
    ("u", "n"), "y", (StateSpec("y_lags", "y_lags_out", 3), StateSpec("v_lags", "v_lags_out", 2))
)


def _narmax_module(w: NarmaxWeights):  # noqa: ANN202 (torch is imported lazily)
    import torch
    from torch import nn

    hidden = w.w_hh.shape[1]

    class NarmaxStep(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.cell = nn.LSTMCell(w.w_ih.shape[1], hidden)
            self.head = nn.Linear(hidden, 1)
            with torch.no_grad():
                self.cell.weight_ih.copy_(torch.from_numpy(w.w_ih))
                self.cell.weight_hh.copy_(torch.from_numpy(w.w_hh))
                self.cell.bias_ih.copy_(torch.from_numpy(w.bias))
                self.cell.bias_hh.zero_()
                self.head.weight.copy_(torch.from_numpy(w.head_w[None, :] * np.float32(w.y_std)))
                self.head.bias.fill_(float(np.float32(w.head_b) * np.float32(w.y_std)))
            self.mean = torch.from_numpy(w.mean[None, :])
            self.inv_std = torch.from_numpy((1.0 / w.std).astype(np.float32)[None, :])

        def forward(self, u, n, u_lag, n_lag, y_lag, h, c):  # noqa: ANN001, ANN202
            x = (torch.cat([u, u_lag, n, n_lag, y_lag], dim=1) - self.mean) * self.inv_std
            h_out, c_out = self.cell(x, (h, c))
            y = n + self.head(h_out)
            return y, u + 0.0, n + 0.0, y + 0.0, h_out, c_out

    return NarmaxStep().eval()


def _hammerstein_module(w: HammersteinWeights):  # noqa: ANN202
    import torch
    from torch import nn

    class HammersteinStep(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            linears = []
            for weight, bias in w.layers:
                layer = nn.Linear(weight.shape[1], weight.shape[0])
                with torch.no_grad():
                    layer.weight.copy_(torch.from_numpy(weight))
                    layer.bias.copy_(torch.from_numpy(bias))
                linears.append(layer)
            self.layers = nn.ModuleList(linears)
            f32 = lambda a: torch.tensor(np.asarray(a, np.float32))  # noqa: E731
            self.mean, self.std = f32(w.mean[None, :]), f32(w.std[None, :])
            self.y_std = f32(w.y_std)
            self.a, self.b = f32(w.a[:, None]), f32(w.b[:, None])

        def forward(self, u, n, y_lags, v_lags):  # noqa: ANN001, ANN202
            x = (torch.cat([u, n], dim=1) - self.mean) / self.std
            for i, layer in enumerate(self.layers):
                x = layer(x)
                if i < len(self.layers) - 1:
                    x = torch.tanh(x)
            v = n + x * self.y_std
            vs = torch.cat([v, v_lags], dim=1)
            y = y_lags @ self.a + vs @ self.b
            return y, torch.cat([y, y_lags[:, :2]], dim=1), torch.cat([v, v_lags[:, :1]], dim=1)

    return HammersteinStep().eval()


def step_module(kind: str, weights: object):  # noqa: ANN201
    """The torch step module of a trained model's weights (``kind``: lstm-narmax | hammerstein)."""
    if kind == "lstm-narmax":
        return _narmax_module(weights)  # type: ignore[arg-type]
    return _hammerstein_module(weights)  # type: ignore[arg-type]


def spec_of(kind: str) -> StepSpec:
    return NARMAX_SPEC if kind == "lstm-narmax" else HAMMERSTEIN_SPEC


def export_module(
    module: object, example: tuple[object, ...], path: str | Path, inputs: list[str], outputs: list[str]
) -> Path:
    """Trace ``module`` at batch 1 and write an opset-18 ONNX graph with static shapes."""
    import onnx
    import torch

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the legacy-exporter notice (see module docstring)
        torch.onnx.export(
            module,  # type: ignore[arg-type]
            example,
            str(path),
            input_names=inputs,
            output_names=outputs,
            opset_version=OPSET,
            dynamo=False,
        )
    onnx.checker.check_model(onnx.load(str(path)))
    return path


def export_step(kind: str, weights: object, path: str | Path) -> tuple[Path, StepSpec]:
    """Export a trained model's step graph; returns the path and its signature."""
    import torch

    spec = spec_of(kind)
    example = tuple(torch.zeros(1, 1) for _ in spec.inputs) + tuple(torch.zeros(1, s.size) for s in spec.state)
    outputs = [spec.output] + [s.output for s in spec.state]
    return export_module(
        step_module(kind, weights), example, path, [*spec.inputs, *(s.input for s in spec.state)], outputs
    ), spec


def session(path: str | Path):  # noqa: ANN201
    """An onnxruntime session as the edge opens it: one thread, sequential, no spinning."""
    import onnxruntime as ort

    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    options.execution_mode = ort.ExecutionMode.ORT_SEQUENTIAL
    options.add_session_config_entry("session.intra_op.allow_spinning", "0")
    options.add_session_config_entry("session.inter_op.allow_spinning", "0")
    return ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])


class OnnxStepper:
    """Runs a step graph in free run with preallocated, bound inputs and outputs."""

    def __init__(self, path: str | Path, spec: StepSpec) -> None:
        import onnxruntime as ort

        self.spec = spec
        self.session = session(path)
        self.inputs = {name: np.zeros((1, 1), np.float32) for name in spec.inputs}
        self.state_in = {s.input: np.zeros((1, s.size), np.float32) for s in spec.state}
        self.state_out = {s.output: np.zeros((1, s.size), np.float32) for s in spec.state}
        self.output = np.zeros((1, 1), np.float32)
        self.binding = self.session.io_binding()
        value = ort.OrtValue.ortvalue_from_numpy
        for name, array in (*self.inputs.items(), *self.state_in.items()):
            self.binding.bind_ortvalue_input(name, value(array))
        for name, array in ((spec.output, self.output), *self.state_out.items()):
            self.binding.bind_ortvalue_output(name, value(array))

    def set_state(self, values: dict[str, NDArray[np.float32]]) -> None:
        for name, array in self.state_in.items():
            array[...] = values.get(name, 0.0)

    def step(self, *values: float) -> float:
        for array, value in zip(self.inputs.values(), values):
            array[0, 0] = value
        self.session.run_with_iobinding(self.binding)
        for s in self.spec.state:
            np.copyto(self.state_in[s.input], self.state_out[s.output])
        return float(self.output[0, 0])


def initial_state(kind: str, weights: object, u0: float, n0: float) -> dict[str, NDArray[np.float32]]:
    """The start every evaluator uses: zero LSTM state, lags at the first sample (steady state)."""
    if kind == "lstm-narmax":
        return {
            "u_lag": np.full((1, 1), u0, np.float32),
            "n_lag": np.full((1, 1), n0, np.float32),
            "y_lag": np.full((1, 1), n0, np.float32),
        }
    v0 = float(weights.static(np.array([u0]), np.array([n0]))[0])  # type: ignore[attr-defined]
    return {"y_lags": np.full((1, 3), v0, np.float32), "v_lags": np.full((1, 2), v0, np.float32)}


def simulate_onnx(
    path: str | Path, kind: str, weights: object, u: NDArray[np.float64], n: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Free run of the exported graph over a record (onnxruntime)."""
    stepper = OnnxStepper(path, spec_of(kind))
    stepper.set_state(initial_state(kind, weights, float(u[0]), float(n[0])))
    return np.array([stepper.step(float(a), float(b)) for a, b in zip(u, n)])


def simulate_torch(kind: str, weights: object, u: NDArray[np.float64], n: NDArray[np.float64]) -> NDArray[np.float64]:
    """Free run of the torch step module over a record (the reference for parity)."""
    import torch

    module = step_module(kind, weights)
    spec = spec_of(kind)
    start = initial_state(kind, weights, float(u[0]), float(n[0]))
    state = [torch.from_numpy(start.get(s.input, np.zeros((1, s.size), np.float32))) for s in spec.state]
    out = np.empty(u.size)
    with torch.no_grad():
        for k in range(u.size):
            y, *state = module(
                torch.tensor([[u[k]]], dtype=torch.float32), torch.tensor([[n[k]]], dtype=torch.float32), *state
            )
            out[k] = float(y[0, 0])
    return out
