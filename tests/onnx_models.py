"""Small hand-built ONNX models with numpy twins: edge-side tests that need a known net and no
training (trained nets are exported by ``models_export.onnx_step``, tested in test_export.py)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

OPSET = 17


def _save(graph: onnx.GraphProto, path: Path) -> Path:
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)])
    model.ir_version = 9
    onnx.checker.check_model(model)
    onnx.save(model, str(path))
    return path


def mlp(path: Path, sizes: Sequence[int] = (2, 5, 10, 1), seed: int = 0, scale: float = 0.3, name: str = "features"):
    """A tanh MLP (Ai2019's BP net shape by default); returns (path, numpy forward)."""
    rng = np.random.default_rng(seed)
    weights = [rng.normal(0, scale, (a, b)).astype(np.float32) for a, b in zip(sizes, sizes[1:])]
    biases = [rng.normal(0, scale, b).astype(np.float32) for b in sizes[1:]]
    nodes, inits, current = [], [], name
    for i, (w, b) in enumerate(zip(weights, biases)):
        inits += [numpy_helper.from_array(w, f"W{i}"), numpy_helper.from_array(b, f"b{i}")]
        nodes += [
            helper.make_node("MatMul", [current, f"W{i}"], [f"m{i}"]),
            helper.make_node("Add", [f"m{i}", f"b{i}"], [f"a{i}"]),
        ]
        current = f"a{i}"
        if i < len(weights) - 1:
            nodes.append(helper.make_node("Tanh", [current], [f"t{i}"]))
            current = f"t{i}"
    nodes.append(helper.make_node("Identity", [current], ["correction_bar"]))
    graph = helper.make_graph(
        nodes,
        "mlp",
        [helper.make_tensor_value_info(name, TensorProto.FLOAT, ["batch", sizes[0]])],
        [helper.make_tensor_value_info("correction_bar", TensorProto.FLOAT, ["batch", 1])],
        inits,
    )

    def forward(x: np.ndarray) -> float:
        a = np.asarray(x, dtype=np.float32).reshape(1, -1)
        for i, (w, b) in enumerate(zip(weights, biases)):
            a = a @ w + b
            if i < len(weights) - 1:
                a = np.tanh(a)
        return float(a[0, 0])

    return _save(graph, path), forward


def rnn(path: Path, n_in: int = 2, hidden: int = 4, seed: int = 1, scale: float = 0.5):
    """An Elman cell: h' = tanh(x W + h U + b), y = h' V. Returns (path, numpy step(x, h) -> (y, h'))."""
    rng = np.random.default_rng(seed)
    w = rng.normal(0, scale, (n_in, hidden)).astype(np.float32)
    u = rng.normal(0, scale, (hidden, hidden)).astype(np.float32)
    b = rng.normal(0, scale, hidden).astype(np.float32)
    v = rng.normal(0, scale, (hidden, 1)).astype(np.float32)
    nodes = [
        helper.make_node("MatMul", ["features", "W"], ["xw"]),
        helper.make_node("MatMul", ["h_in", "U"], ["hu"]),
        helper.make_node("Add", ["xw", "hu"], ["s0"]),
        helper.make_node("Add", ["s0", "b"], ["s1"]),
        helper.make_node("Tanh", ["s1"], ["h_out"]),
        helper.make_node("MatMul", ["h_out", "V"], ["correction_bar"]),
    ]
    graph = helper.make_graph(
        nodes,
        "rnn",
        [
            helper.make_tensor_value_info("features", TensorProto.FLOAT, [1, n_in]),
            helper.make_tensor_value_info("h_in", TensorProto.FLOAT, [1, hidden]),
        ],
        [
            helper.make_tensor_value_info("correction_bar", TensorProto.FLOAT, [1, 1]),
            helper.make_tensor_value_info("h_out", TensorProto.FLOAT, [1, hidden]),
        ],
        [numpy_helper.from_array(a, n) for a, n in ((w, "W"), (u, "U"), (b, "b"), (v, "V"))],
    )

    def step(x: np.ndarray, h: np.ndarray) -> tuple[float, np.ndarray]:
        h_new = np.tanh(np.asarray(x, np.float32).reshape(1, -1) @ w + h @ u + b)
        return float((h_new @ v)[0, 0]), h_new

    return _save(graph, path), step


def nan_model(path: Path, n_in: int = 2) -> Path:
    """Outputs NaN whatever the input (log of a negative number): a broken export."""
    nodes = [
        helper.make_node("ReduceSum", ["features"], ["s"], keepdims=1),
        helper.make_node("Abs", ["s"], ["a"]),
        helper.make_node("Neg", ["a"], ["n"]),
        helper.make_node("Sub", ["n", "one"], ["m"]),
        helper.make_node("Log", ["m"], ["correction_bar"]),
    ]
    graph = helper.make_graph(
        nodes,
        "nan",
        [helper.make_tensor_value_info("features", TensorProto.FLOAT, [1, n_in])],
        [helper.make_tensor_value_info("correction_bar", TensorProto.FLOAT, [1, 1])],
        [numpy_helper.from_array(np.array(1.0, np.float32), "one")],
    )
    return _save(graph, path)
