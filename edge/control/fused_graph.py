"""Build the fused evaluators from the ONNX graph itself, and keep the faster evaluator that agrees.

The ONNX file is the artefact the bundle checksums; the fused numpy evaluator is compiled from
its weights (:func:`mlp_from_graph`, :func:`narmax_from_graph`), never from a second copy, and
is used only when it reproduces the onnxruntime session on probe inputs (:func:`choose`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from edge.control.fused import FusedMLP, FusedNarmax
from edge.control.onnx_graph import Graph, GraphFormatError

PARITY_RTOL = 1e-4  # of the probe outputs' range: float32 with a different summation order
PARITY_ATOL = 1e-6
TIMING_STEPS = 300


def _vector(value: NDArray[np.generic], size: int) -> NDArray[np.float64]:
    flat = np.asarray(value, np.float64).reshape(-1)
    if flat.size not in (1, size):
        raise GraphFormatError(f"constant of {flat.size} values where {size} are needed")
    return np.broadcast_to(flat, (size,)).astype(np.float64)


def mlp_from_graph(graph: Graph, input_name: str, output_name: str, n_inputs: int) -> FusedMLP:
    """A chain of affine nodes (MatMul, Gemm, Add, Sub, Mul, Div) and tanh as a :class:`FusedMLP`.

    Every node must take the previous node's output and constants only; any other graph (a
    branch, a recurrent state, another activation) raises :class:`GraphFormatError`.
    """
    current, a, b = input_name, np.eye(n_inputs), np.zeros(n_inputs)
    layers: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
    for node in graph.nodes:
        if current not in node.inputs:
            raise GraphFormatError(f"node {node.op} is not on the chain from {input_name!r}")
        others = [graph.constants.get(name) for name in node.inputs if name != current]
        if any(c is None for c in others) or len(node.outputs) != 1:
            raise GraphFormatError(f"node {node.op} takes a non-constant input")
        consts = [np.asarray(c, np.float64) for c in others if c is not None]
        if node.op in ("MatMul", "Gemm"):
            if node.inputs[0] != current or node.attributes.get("transA", 0):
                raise GraphFormatError(f"{node.op} with the input second is not supported")
            weight = consts[0].T if node.attributes.get("transB", 0) else consts[0]  # (in, out)
            alpha = float(node.attributes.get("alpha", 1.0))  # type: ignore[arg-type]
            a, b = alpha * weight.T @ a, alpha * weight.T @ b
            if node.op == "Gemm" and len(consts) > 1:
                b = b + float(node.attributes.get("beta", 1.0)) * _vector(consts[1], b.size)  # type: ignore[arg-type]
        elif node.op in ("Add", "Sub", "Mul", "Div") and len(consts) == 1:
            c = _vector(consts[0], b.size)
            first = node.inputs[0] == current
            if node.op == "Add":
                b = b + c
            elif node.op == "Sub":
                a, b = (a, b - c) if first else (-a, c - b)
            elif node.op == "Mul":
                a, b = a * c[:, None], b * c
            elif first:
                a, b = a / c[:, None], b / c
            else:
                raise GraphFormatError("division by the input is not affine")
        elif node.op == "Tanh":
            layers.append((a, b))
            a, b = np.eye(b.size), np.zeros(b.size)
        elif node.op != "Identity":
            raise GraphFormatError(f"operator {node.op} is not fused")
        current = node.outputs[0]
    if current != output_name:
        raise GraphFormatError(f"the chain ends at {current!r}, not at the output {output_name!r}")
    layers.append((a, b))
    return FusedMLP(layers)


def narmax_from_graph(graph: Graph) -> FusedNarmax:
    """The LSTM-NARMAX step graph of ``models_export.onnx_step`` (its weight names) as :class:`FusedNarmax`."""
    c = graph.constants
    names = ("cell.weight_ih", "cell.weight_hh", "cell.bias_ih", "cell.bias_hh", "head.weight", "head.bias")
    if any(name not in c for name in names):
        raise GraphFormatError("not an LSTM-NARMAX step graph (weights missing)")
    concat = next((n for n in graph.nodes if n.op == "Concat"), None)
    sub = next((n for n in graph.nodes if n.op == "Sub" and concat and n.inputs[0] == concat.outputs[0]), None)
    mul = next((n for n in graph.nodes if n.op == "Mul" and sub and n.inputs[0] == sub.outputs[0]), None)
    if sub is None or mul is None or sub.inputs[1] not in c or mul.inputs[1] not in c:
        raise GraphFormatError("not an LSTM-NARMAX step graph (normalisation missing)")
    inv_std = np.asarray(c[mul.inputs[1]], np.float64).reshape(-1)
    return FusedNarmax(
        np.asarray(c["cell.weight_ih"]),
        np.asarray(c["cell.weight_hh"]),
        np.asarray(c["cell.bias_ih"], np.float64) + np.asarray(c["cell.bias_hh"], np.float64),
        np.asarray(c["head.weight"]).reshape(-1),
        float(np.asarray(c["head.bias"]).reshape(-1)[0]),
        np.asarray(c[sub.inputs[1]], np.float64).reshape(-1),
        1.0 / inv_std,
        1.0,
    )


@dataclass
class Choice:
    """Which evaluator runs a net, why, and the timings [us per step] it was chosen on."""

    evaluator: str  # "numpy-fused" | "onnxruntime"
    reason: str
    onnxruntime_us: float = math.nan
    fused_us: float = math.nan
    max_abs_diff: float = math.nan


def _per_step_us(step: Callable[[Sequence[float]], float], probes: Sequence[Sequence[float]], steps: int) -> float:
    rows = [probes[i % len(probes)] for i in range(steps)]
    start = time.perf_counter()
    for row in rows:
        step(row)
    return 1e6 * (time.perf_counter() - start) / steps


def choose(
    onnx_step: Callable[[Sequence[float]], float],
    fused_step: Callable[[Sequence[float]], float] | None,
    probes: Sequence[Sequence[float]],
    reset: Callable[[], None] = lambda: None,
) -> Choice:
    """Keep the fused step if it matches onnxruntime on ``probes`` and is faster (best of 3 timings)."""
    if fused_step is None:
        return Choice("onnxruntime", "no fused form of this graph")
    reset()
    expected = np.array([onnx_step(p) for p in probes])
    reset()
    got = np.array([fused_step(p) for p in probes])
    reset()
    diff = float(np.max(np.abs(got - expected)))
    tolerance = PARITY_ATOL + PARITY_RTOL * max(float(np.ptp(expected)), float(np.max(np.abs(expected))))
    if not np.all(np.isfinite(got)) or not diff <= tolerance:
        return Choice("onnxruntime", f"fused step differs by {diff:.3g} (tolerance {tolerance:.3g})", max_abs_diff=diff)
    ort_us = min(_per_step_us(onnx_step, probes, TIMING_STEPS) for _ in range(3))
    fused_us = min(_per_step_us(fused_step, probes, TIMING_STEPS) for _ in range(3))
    reset()
    name = "numpy-fused" if fused_us < ort_us else "onnxruntime"
    return Choice(name, "parity passed; the faster one", ort_us, fused_us, diff)
