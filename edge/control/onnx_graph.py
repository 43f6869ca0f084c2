"""An ONNX file's nodes and constant tensors as numpy arrays, read with the ``onnx`` package.

Building a fused evaluator (:mod:`edge.control.fused_graph`) needs the graph's nodes (operator,
inputs, outputs, attributes) and its initializers and ``Constant`` values. ``onnx`` parses the
protocol buffer (one dependency of the ``edge`` extra, rather than a hand-written reader of the
wire format). Anything the fused evaluators do not understand makes them raise
:class:`GraphFormatError`; the caller then keeps onnxruntime, which runs every graph. The file is
what the bundle checksums, so the weights read here are the verified weights.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray


class GraphFormatError(ValueError):
    """The file is not an ONNX graph the fused evaluators understand (onnxruntime still may)."""


@dataclass
class Node:
    op: str
    inputs: list[str]
    outputs: list[str]
    attributes: dict[str, object] = field(default_factory=dict)


@dataclass
class Graph:
    nodes: list[Node]
    constants: dict[str, NDArray[np.generic]]  # initializers and Constant-node values by name


def _attribute_value(attribute: object) -> object:
    """An attribute as a Python number, a list of them, or a numpy array (a tensor)."""
    from onnx import AttributeProto, helper, numpy_helper

    value = helper.get_attribute_value(attribute)  # type: ignore[arg-type]
    if attribute.type == AttributeProto.TENSOR:  # type: ignore[attr-defined]
        return numpy_helper.to_array(value)
    if isinstance(value, bytes):
        return value.decode()
    return list(value) if isinstance(value, (list, tuple)) else value


def read_graph(path: str | Path) -> Graph:
    """The nodes and constants of the ONNX model at ``path`` (see module docstring)."""
    try:
        import onnx
        from onnx import numpy_helper
    except ImportError as exc:  # an install without it still runs every graph on onnxruntime
        raise GraphFormatError(f"the onnx package is not installed ({exc}); pip install 'pmactl[edge]'") from exc
    try:
        model = onnx.load(str(path), load_external_data=False)
    except Exception as exc:  # noqa: BLE001 - onnx raises protobuf's DecodeError and others
        raise GraphFormatError(f"{path}: not an ONNX model ({exc})") from exc
    constants: dict[str, NDArray[np.generic]] = {}
    for tensor in model.graph.initializer:
        if tensor.data_location == onnx.TensorProto.EXTERNAL:
            raise GraphFormatError(f"{path}: tensor {tensor.name!r} keeps its data in an external file")
        constants[tensor.name] = numpy_helper.to_array(tensor)
    nodes: list[Node] = []
    for proto in model.graph.node:
        attributes = {a.name: _attribute_value(a) for a in proto.attribute}
        if proto.op_type == "Constant" and isinstance(attributes.get("value"), np.ndarray):
            constants[proto.output[0]] = attributes["value"]  # type: ignore[assignment]
            continue
        nodes.append(Node(proto.op_type, list(proto.input), list(proto.output), attributes))
    return Graph(nodes, constants)
