"""Verify a release and check it as the edge would run it (edge extra only: numpy, onnxruntime,
cryptography).

``verify_release``: signature (against trusted keys, or at least self-consistent), plain files,
checksums, table roles, golden vectors of the tables and of the ONNX correction.
``health_check``: the same, plus the edge's units, the correction opened the way the edge opens
it, and the per-tick evaluation (inverse table + correction) timed against a limit.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from edge.errors import BundleError
from edge.runtime.bundle import (
    SIGNATURE,
    Bundle,
    golden_mismatch,
    load_release,
    read_signature,
    resolve_release,
    verify_signature,
)

EDGE_UNITS = ("bar", "mm")  # what edge.runtime.run.EdgeRuntime requires
DEFAULT_TICK_LIMIT_US = 200.0  # a fifth of a 1 kHz period for the model; the rest is I/O and PID
TIMED_TICKS = 2000
CORRECTION_RTOL = 1e-4  # float32 ONNX kernels differ between CPUs in the last bits, not by 1e-4


@dataclass
class HealthReport:
    """What the checks found; times in microseconds of wall time per tick."""

    release_id: str
    signer: str | None
    golden_samples: int
    tick_median_us: float | None = None
    tick_p99_us: float | None = None
    tick_limit_us: float | None = None

    def as_dict(self) -> dict[str, object]:
        return asdict(self)


def verify_release(
    directory: str | Path, trusted: Sequence[tuple[str, bytes]] | None = None
) -> tuple[Bundle, HealthReport]:
    """Load and verify everything in the release; an unsigned release passes only without ``trusted``."""
    bundle = load_release(directory, trusted)
    signer = bundle.signer
    if signer is None and read_signature(bundle.path) is not None:
        signer = verify_signature(bundle.path, (bundle.path / "manifest.json").read_bytes(), None)
    samples = _golden_table_samples(bundle) + replay_correction_golden(bundle) + bundle.net_golden_samples
    return bundle, HealthReport(bundle.release_id, signer, samples)


def _golden_table_samples(bundle: Bundle) -> int:
    path = _golden_path(bundle)
    if path is None:
        return 0
    with np.load(path, allow_pickle=False) as data:
        return int(data["forward_input"].size + data["inverse_input"].size)


def _golden_path(bundle: Bundle) -> Path | None:
    files = bundle.manifest.get("files")
    assert isinstance(files, dict)
    names = [name for name, entry in files.items() if entry.get("role") == "golden"]
    return bundle.path / names[0] if names else None


def replay_correction_golden(bundle: Bundle) -> int:
    """Run the recorded feature rows through the correction; returns the samples replayed."""
    if bundle.correction_path is None:
        return 0
    from edge.control.neural import NeuralCorrection

    path = _golden_path(bundle)
    if path is None:
        return 0
    with np.load(path, allow_pickle=False) as data:
        if "correction_features" not in data.files:
            raise BundleError(f"{bundle.path}: no golden vectors for the correction; re-export the bundle")
        features, expected = data["correction_features"], data["correction_output"]
    correction = NeuralCorrection(bundle.correction_path, bundle.correction_spec or {})
    got = np.array([correction.step(tuple(row)) for row in features.tolist()])
    mismatch = golden_mismatch(got, expected, CORRECTION_RTOL)
    if mismatch:
        raise BundleError(
            f"{bundle.path}: the correction does not reproduce its golden vectors ({mismatch}): "
            "it was changed after export; re-export the bundle"
        )
    return int(expected.size)


def time_ticks(bundle: Bundle, ticks: int = TIMED_TICKS) -> tuple[float, float]:
    """(median, 99th percentile) wall time [us] of one tick's model evaluation: the inverse
    (the net when the bundle holds one, else the table) on a reference sweeping its range,
    plus the correction when the bundle has one."""
    correction = None
    if bundle.correction_path is not None:
        from edge.control.neural import NeuralCorrection

        correction = NeuralCorrection(bundle.correction_path, bundle.correction_spec or {})
    lo, hi = bundle.inverse.input_range
    reference = (lo + (hi - lo) * (0.5 + 0.45 * np.sin(np.linspace(0.0, 8 * np.pi, ticks)))).tolist()
    elapsed = np.empty(ticks)
    clock = time.perf_counter_ns
    # a net feedforward is timed with the net stepping every tick: the worst tick of any loop rate
    step_s = float(bundle.net_spec("inverse").get("step_s", 0.0) or 0.0)  # type: ignore[arg-type]
    inverse = bundle.feedforward("net", step_s) if "inverse" in bundle.net_paths else bundle.inverse
    inverse.reset()
    previous = 0.0
    for i, y_ref in enumerate(reference):
        start = clock()
        u_ff = inverse.step(y_ref)
        if correction is not None:
            u_ff += correction.step((y_ref, 0.0, u_ff, y_ref, u_ff, previous))
        elapsed[i] = clock() - start
        previous = u_ff
    inverse.reset()
    return float(np.median(elapsed)) / 1e3, float(np.percentile(elapsed, 99)) / 1e3


def health_check(
    directory: str | Path,
    trusted: Sequence[tuple[str, bytes]] | None = None,
    *,
    tick_limit_us: float = DEFAULT_TICK_LIMIT_US,
    units: tuple[str, str] = EDGE_UNITS,
) -> HealthReport:
    """Everything :func:`verify_release` checks, plus the edge's units and the tick time.

    The median tick is held against ``tick_limit_us`` (the 99th percentile is reported): on a
    shared machine single ticks are delayed by others, the median is what the model costs.
    """
    bundle, report = verify_release(directory, trusted)
    bundle.require_units(*units)
    median, p99 = time_ticks(bundle)
    report.tick_median_us, report.tick_p99_us, report.tick_limit_us = median, p99, tick_limit_us
    if median > tick_limit_us:
        raise BundleError(
            f"{bundle.path}: one tick of the model takes {median:.1f} us (median of {TIMED_TICKS}), over the "
            f"{tick_limit_us:g} us limit; use a smaller model or raise the limit"
        )
    return report


__all__ = ["SIGNATURE", "HealthReport", "health_check", "resolve_release", "time_ticks", "verify_release"]
