"""Lookup-table form on disk and its per-tick evaluator, with numpy alone.

A table file is an ``.npz`` holding the stage arrays plus one JSON string ``__table__``
(kind, stage order, input range, meta), loaded with ``allow_pickle=False``.
:class:`CompiledModel` runs a table: it clamps the input to the table's input range (setting
``saturated``), then passes it through each stage kernel.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import BundleError
from edge.hysteresis.base import as_signal, clamp_and_flag
from edge.hysteresis.dpi import DPIKernel
from edge.hysteresis.pi import PlayKernel
from edge.hysteresis.preisach import PreisachKernel
from edge.hysteresis.shaper import PiecewiseLinearKernel
from edge.hysteresis.table import LookupTable

KERNELS = {k.stage: k for k in (PlayKernel, PiecewiseLinearKernel, DPIKernel, PreisachKernel)}

_TABLE_KEY = "__table__"


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None


def _none_to_inf(value: float | None, sign: float) -> float:
    return sign * math.inf if value is None else float(value)


def write_table(table: LookupTable, path: str | Path) -> Path:
    """Write ``table`` to ``path`` (``.npz``) and return the path."""
    path = Path(path)
    header = {
        "kind": table.kind,
        "stages": table.stages,
        "input_range": [_finite_or_none(v) for v in table.input_range],
        "meta": table.meta,
    }
    # Typed Any: numpy's stub would let a ``**`` mapping of arrays fill savez's bool
    # ``allow_pickle``; our keys are "<stage>.<name>" and ``__table__``, never that name.
    payload: dict[str, Any] = {**table.arrays, _TABLE_KEY: np.array(json.dumps(header))}
    with path.open("wb") as handle:
        np.savez(handle, **payload)
    return path


def read_table(path: str | Path) -> LookupTable:
    """Read a table written by :func:`write_table`; one clear error if it is not one."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as data:
            header = json.loads(str(data[_TABLE_KEY]))
            arrays = {k: data[k] for k in data.files if k != _TABLE_KEY}
    except (OSError, KeyError, ValueError) as exc:
        raise BundleError(f"{path}: not a pmactl lookup table ({exc}); re-export it with pmactl fit --save") from exc
    unknown = [s for s in header["stages"] if s not in KERNELS]
    if unknown:
        raise BundleError(f"{path}: unknown stage types {unknown}; upgrade pmactl on this machine")
    lo, hi = header["input_range"]
    return LookupTable(
        header["kind"],
        list(header["stages"]),
        arrays,
        (_none_to_inf(lo, -1), _none_to_inf(hi, 1)),
        dict(header.get("meta", {})),
    )


class CompiledModel:
    """Runs a :class:`LookupTable` one tick at a time.

    ``step(u)`` clamps ``u`` to the table's input range (``saturated`` tells whether it did),
    evaluates the stages in order and returns the output. ``reset()`` returns to the state the
    table was compiled in.
    """

    def __init__(self, table: LookupTable) -> None:
        self.table = table
        self.kind = table.kind
        self.input_range = table.input_range
        self.saturated = False
        self.reset()

    def reset(self) -> None:
        """Back to the state stored in the table."""
        self._kernels = [
            KERNELS[stage]({k: v.copy() for k, v in self.table.stage_arrays(i).items()})
            for i, stage in enumerate(self.table.stages)
        ]
        self._steps = [k.step for k in self._kernels]

    def step(self, u: float) -> float:
        lo, hi = self.input_range
        if lo <= u <= hi:
            self.saturated = False
        else:
            u, self.saturated = clamp_and_flag(u, lo, hi)
        for stage_step in self._steps:
            u = stage_step(u)
        return u

    def simulate(self, u: ArrayLike) -> NDArray[np.float64]:
        """``step`` over every sample from the current state."""
        step = self.step
        return np.array([step(v) for v in as_signal(u).tolist()])


def load_compiled(path: str | Path) -> CompiledModel:
    """Read a table file and return its evaluator."""
    return CompiledModel(read_table(path))
