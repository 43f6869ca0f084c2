"""The lookup-table form of a hysteresis model: fixed arrays plus a small description.

A :class:`LookupTable` is a chain of stages (play bank, piecewise-linear map, DPI digit
register, Preisach Everett grid), each stored as plain float arrays. It is what a bundle holds
on disk (``.npz`` + JSON manifest, see :mod:`edge.hysteresis.lut`) and what the edge runs with
numpy alone.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray


@dataclass
class LookupTable:
    """Compiled model.

    Attributes:
        kind: model family (``pi``, ``mpi``, ``dpi``, ``preisach``) plus ``-inverse`` for an
            inverse model.
        stages: stage type names in evaluation order.
        arrays: every array, keyed ``"<stage index>.<name>"``.
        input_range: inputs are clamped to this interval (model input units).
        meta: free-form JSON-serialisable description (units, fit provenance).
    """

    kind: str
    stages: list[str]
    arrays: dict[str, NDArray[np.float64]]
    input_range: tuple[float, float]
    meta: dict[str, object] = field(default_factory=dict)

    def stage_arrays(self, index: int) -> dict[str, NDArray[np.float64]]:
        """The arrays of stage ``index`` without their prefix."""
        prefix = f"{index}."
        return {k[len(prefix) :]: v for k, v in self.arrays.items() if k.startswith(prefix)}

    @staticmethod
    def chain(
        kind: str,
        stages: list[tuple[str, dict[str, NDArray[np.float64]]]],
        input_range: tuple[float, float],
        meta: dict[str, object] | None = None,
    ) -> LookupTable:
        """Build a table from ``(stage type, arrays)`` pairs in evaluation order."""
        arrays = {
            f"{i}.{name}": np.asarray(value, dtype=float)
            for i, (_, stage_arrays) in enumerate(stages)
            for name, value in stage_arrays.items()
        }
        return LookupTable(kind, [s for s, _ in stages], arrays, input_range, dict(meta or {}))
