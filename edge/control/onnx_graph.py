"""Read an ONNX file's nodes and constant tensors with numpy alone (the edge has no ``onnx`` package).

An ONNX model is a protocol-buffer message; this reads just what building a fused evaluator
needs (:mod:`edge.control.fused`): the graph's nodes (operator, inputs, outputs, attributes) and
its initializers and ``Constant`` values as numpy arrays. Anything it does not understand makes
it raise :class:`GraphFormatError`; the caller then keeps onnxruntime, which runs every graph.
The file itself is what the bundle checksums, so weights read here are the verified weights.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

# TensorProto.DataType -> numpy
DTYPES = {1: np.float32, 6: np.int32, 7: np.int64, 11: np.float64}


class GraphFormatError(ValueError):
    """The file is not an ONNX graph this reader understands (onnxruntime still may)."""


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


def _varint(buf: bytes, pos: int) -> tuple[int, int]:
    result, shift = 0, 0
    while True:
        if pos >= len(buf):
            raise GraphFormatError("truncated varint")
        byte = buf[pos]
        pos += 1
        result |= (byte & 0x7F) << shift
        if byte < 0x80:
            return result, pos
        shift += 7


def _fields(buf: bytes) -> Iterator[tuple[int, int, int | bytes]]:
    """(field number, wire type, value) of one message: int for varints, bytes otherwise."""
    pos = 0
    while pos < len(buf):
        key, pos = _varint(buf, pos)
        number, wire = key >> 3, key & 7
        if wire == 0:
            value, pos = _varint(buf, pos)
            yield number, wire, value
        elif wire == 2:
            size, pos = _varint(buf, pos)
            if pos + size > len(buf):
                raise GraphFormatError("truncated field")
            yield number, wire, buf[pos : pos + size]
            pos += size
        elif wire in (1, 5):
            size = 8 if wire == 1 else 4
            yield number, wire, buf[pos : pos + size]
            pos += size
        else:
            raise GraphFormatError(f"unsupported wire type {wire}")


def _signed(value: int) -> int:
    return value - (1 << 64) if value >= 1 << 63 else value


def _tensor(buf: bytes) -> tuple[str, NDArray[np.generic]]:
    dims: list[int] = []
    dtype_code, name, raw = 0, "", b""
    floats: list[float] = []
    ints: list[int] = []
    for number, _, value in _fields(buf):
        if number == 1:  # dims, packed or not
            if isinstance(value, bytes):
                pos = 0
                while pos < len(value):
                    dim, pos = _varint(value, pos)
                    dims.append(_signed(dim))
            else:
                dims.append(_signed(value))
        elif number == 2 and isinstance(value, int):
            dtype_code = value
        elif number == 4 and isinstance(value, bytes):  # float_data
            floats += list(struct.unpack(f"<{len(value) // 4}f", value))  # packed (wire 2) or one (wire 5)
        elif number in (5, 7):  # int32_data / int64_data
            if isinstance(value, bytes):
                pos = 0
                while pos < len(value):
                    item, pos = _varint(value, pos)
                    ints.append(_signed(item))
            else:
                ints.append(_signed(value))
        elif number == 8 and isinstance(value, bytes):
            name = value.decode()
        elif number == 9 and isinstance(value, bytes):
            raw = value
        elif number == 13:
            raise GraphFormatError("external tensor data")
    if dtype_code not in DTYPES:
        raise GraphFormatError(f"tensor {name!r}: data type {dtype_code} not supported")
    dtype = DTYPES[dtype_code]
    if raw:
        array = np.frombuffer(raw, dtype=np.dtype(dtype).newbyteorder("<")).astype(dtype)
    else:
        array = np.asarray(floats if floats else ints, dtype=dtype)
    return name, array.reshape(dims) if dims else array.reshape(())


def _attribute(buf: bytes) -> tuple[str, object]:
    name, value_out = "", None
    ints: list[int] = []
    for number, _, value in _fields(buf):
        if number == 1 and isinstance(value, bytes):
            name = value.decode()
        elif number == 2 and isinstance(value, bytes):
            value_out = struct.unpack("<f", value)[0]
        elif number == 3 and isinstance(value, int):
            value_out = _signed(value)
        elif number == 5 and isinstance(value, bytes):
            value_out = _tensor(value)[1]
        elif number == 8:
            if isinstance(value, bytes):
                pos = 0
                while pos < len(value):
                    item, pos = _varint(value, pos)
                    ints.append(_signed(item))
            else:
                ints.append(_signed(value))
    return name, ints if ints and value_out is None else value_out


def _node(buf: bytes) -> Node:
    node = Node("", [], [])
    for number, _, value in _fields(buf):
        if not isinstance(value, bytes):
            continue
        if number == 1:
            node.inputs.append(value.decode())
        elif number == 2:
            node.outputs.append(value.decode())
        elif number == 4:
            node.op = value.decode()
        elif number == 5:
            key, attribute = _attribute(value)
            node.attributes[key] = attribute
    return node


def read_graph(path: str | Path) -> Graph:
    """The nodes and constants of the ONNX model at ``path`` (see module docstring)."""
    model = Path(path).read_bytes()
    graph_bytes = next((v for n, _, v in _fields(model) if n == 7 and isinstance(v, bytes)), None)
    if graph_bytes is None:
        raise GraphFormatError(f"{path}: no graph")
    nodes: list[Node] = []
    constants: dict[str, NDArray[np.generic]] = {}
    for number, _, value in _fields(graph_bytes):
        if number == 1 and isinstance(value, bytes):
            nodes.append(_node(value))
        elif number == 5 and isinstance(value, bytes):
            name, array = _tensor(value)
            constants[name] = array
    for node in nodes:
        if node.op == "Constant" and isinstance(node.attributes.get("value"), np.ndarray):
            constants[node.outputs[0]] = node.attributes["value"]  # type: ignore[assignment]
    return Graph([n for n in nodes if n.op != "Constant"], constants)
