"""Golden vectors: inputs and the outputs the exported tables (and correction) gave at export.

A checksum proves a file is the one the manifest names; it cannot tell that a table was scaled
and the manifest re-hashed. Replaying recorded inputs and comparing the outputs can: the edge
does it for the tables on every load (``edge.runtime.bundle.replay_table_golden``) and the
health check does it for the ONNX correction (``host.deploy.health``).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.control.neural import FEATURES, NeuralCorrection
from edge.hysteresis.lut import CompiledModel

GOLDEN_FILE = "golden.npz"
TABLE_SAMPLES = 256
CORRECTION_SAMPLES = 64


def _walk(rng: np.random.Generator, n: int, lo: float, hi: float) -> NDArray[np.float64]:
    """A bounded random walk from ``lo`` that also leaves the range by 5 % (saturation is tested)."""
    span = hi - lo
    steps = rng.normal(0.0, 0.15 * span, n)
    u = np.empty(n)
    value = lo
    for i, step in enumerate(steps):
        value = min(max(value + step, lo - 0.05 * span), hi + 0.05 * span)
        u[i] = value
    return u


def finite_range(table: CompiledModel, other: CompiledModel) -> tuple[float, float]:
    """``table``'s input range, or (when unbounded) the outputs ``other`` gives at its range ends."""
    lo, hi = table.input_range
    if math.isfinite(lo) and math.isfinite(hi):
        return lo, hi
    ends = other.simulate(np.array(other.input_range))
    other.reset()
    return float(ends.min()), float(ends.max())


def table_vectors(forward: CompiledModel, inverse: CompiledModel, seed: int = 0) -> dict[str, NDArray[np.float64]]:
    """Inputs and outputs of both tables from their stored states (both are reset afterwards)."""
    rng = np.random.default_rng(seed)
    vectors = {}
    for role, table, other in (("forward", forward, inverse), ("inverse", inverse, forward)):
        u = _walk(rng, TABLE_SAMPLES, *finite_range(table, other))
        table.reset()
        vectors[f"{role}_input"] = u
        vectors[f"{role}_output"] = table.simulate(u)
        table.reset()
    return vectors


def correction_vectors(
    model_path: Path, spec: Mapping[str, object], inverse: CompiledModel, seed: int = 1
) -> dict[str, NDArray[np.float64]]:
    """Feature rows (in :data:`edge.control.neural.FEATURES` order) along a plausible trajectory
    and the correction [bar] the model gives for them, one tick after another from reset."""
    rng = np.random.default_rng(seed)
    lo, hi = inverse.input_range
    t = np.arange(CORRECTION_SAMPLES) * 1e-3
    reference = lo + (hi - lo) * (0.5 + 0.4 * np.sin(2 * np.pi * 5.0 * t))
    rate = np.gradient(reference, t)
    feedforward = inverse.simulate(reference)
    inverse.reset()
    contraction = reference + rng.normal(0.0, 0.02 * (hi - lo), reference.size)
    pressure = feedforward + rng.normal(0.0, 0.01, reference.size)
    previous = np.concatenate([[feedforward[0]], feedforward[:-1]])
    columns = {
        "reference_mm": reference,
        "reference_rate_mm_s": rate,
        "feedforward_bar": feedforward,
        "contraction_mm": contraction,
        "pressure_bar": pressure,
        "previous_command_bar": previous,
    }
    features = np.column_stack([columns[name] for name in FEATURES])
    correction = NeuralCorrection(model_path, spec)
    output = np.array([correction.step(tuple(row)) for row in features.tolist()])
    return {"correction_features": features, "correction_output": output}


def net_vectors(
    release: Path, nets: Mapping[str, Mapping[str, object]], inverse: CompiledModel, seed: int = 2
) -> dict[str, NDArray[np.float64]]:
    """Inputs and outputs of each net (``forward``: pressure -> contraction, ``inverse``: target
    -> command), run by the edge's own evaluators one net step per input from reset."""
    from edge.control.net_roles import net_forward, net_inverse

    rng = np.random.default_rng(seed)
    vectors: dict[str, NDArray[np.float64]] = {}
    for which, spec in sorted(nets.items()):
        path = release / str(spec["file"])
        step_s = float(spec["step_s"])  # type: ignore[arg-type]
        if which == "inverse":
            model = net_inverse(path, spec, inverse, step_s)
            lo, hi = finite_range(inverse, inverse)
        else:
            model = net_forward(path, spec, release, step_s)  # type: ignore[assignment]
            lo, hi = (float(v) for v in spec["u_range"])  # type: ignore[attr-defined]
        u = _walk(rng, TABLE_SAMPLES, lo, hi)
        model.reset()
        vectors[f"{which}_net_input"] = u
        vectors[f"{which}_net_output"] = model.simulate(u)
        model.reset()
    return vectors


def write_golden(path: Path, vectors: Mapping[str, NDArray[np.float64]]) -> Path:
    """Write the vectors as an ``.npz`` (loaded without pickle)."""
    with path.open("wb") as handle:
        np.savez(handle, **dict(vectors))  # type: ignore[arg-type]
    return path
