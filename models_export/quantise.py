"""Gated int8 quantisation of a bundle's correction net (onnxruntime.quantization).

Variants measured against float32 on the same calibration recording:

* ``dynamic_int8``: ``quantize_dynamic`` (int8 weights, activations quantised at run time);
* ``dynamic_int8_reduce_range``: the same with 7-bit weights (``reduce_range=True``, which
  avoids saturation of the u8 x s8 product on CPUs without VNNI);
* ``static_qdq``: ``quantize_static`` in QDQ format, activations calibrated (MinMax) on the
  first 80 % of the features through a ``CalibrationDataReader``.

Accuracy is the RMSE of the correction against its target (the command the recording says was
needed, minus the feedforward) on the last 20 %, which calibration never saw. Latency is the
per-step time of one session (one thread, no spinning, inputs and outputs bound to
preallocated arrays), median of interleaved rounds, wall and CPU time.

Rule: an int8 variant is kept only if its RMSE is within 5 % of float32 AND its median CPU time
per step is at least 10 % below float32's (CPU time, not wall time, so other processes' load does
not decide; the margin, so run-to-run noise does not); the lowest CPU time of those wins,
otherwise float32 stays and the reason names the test each variant failed. Both measurements
and the choice go into the manifest's ``correction.quantisation`` (the bundle is rewritten
beside the old one and swapped in).
"""

from __future__ import annotations

import logging
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import BundleError
from edge.runtime.bundle import load_bundle
from models_export.bundle import add_correction
from models_export.onnx_step import session

RMSE_TOLERANCE = 0.05
MIN_SPEEDUP = 0.10  # a variant must save at least this share of float32's CPU time per step
CALIBRATION_SHARE = 0.8
RULE = (
    "int8 only if RMSE <= 1.05x float32 and its median CPU time per step is at least 10 % below float32's; "
    "the lowest CPU time of those wins"
)


def choose(measured: dict[str, dict[str, float]]) -> tuple[str, list[str]]:
    """The variant to keep under :data:`RULE` and, per rejected variant, the test it failed.

    CPU time (``us_per_step_cpu``), not wall time: on a shared machine wall time carries other
    processes' load; the 10 % margin keeps run-to-run noise from deciding between near-equal models.
    """
    base = measured["float32"]
    kept, reasons = "float32", []
    for name, m in measured.items():
        if name == "float32":
            continue
        accurate = m["rmse_ratio"] <= 1.0 + RMSE_TOLERANCE
        faster = m["us_per_step_cpu"] <= (1.0 - MIN_SPEEDUP) * base["us_per_step_cpu"]
        if accurate and faster:
            if kept == "float32" or m["us_per_step_cpu"] < measured[kept]["us_per_step_cpu"]:
                kept = name
            continue
        failed = [
            test
            for test, ok in (
                ("accuracy: RMSE > 1.05x float32", accurate),
                ("speed: not 10 % less CPU time per step", faster),
            )
            if not ok
        ]
        reasons.append(f"{name} failed {' and '.join(failed)}")
    return kept, reasons


def _outputs(path: Path, input_name: str, features: NDArray[np.float32]) -> NDArray[np.float64]:
    sess = session(path)
    output = sess.get_outputs()[0].name
    return np.array([float(sess.run([output], {input_name: row[None, :]})[0][0, 0]) for row in features])


def step_latency(
    path: Path, input_name: str, output_name: str, features: NDArray[np.float32], steps: int
) -> tuple[float, float]:
    """(wall, CPU) microseconds per step of a bound session over ``steps`` steps."""
    import onnxruntime as ort

    sess = session(path)
    x = np.zeros((1, features.shape[1]), np.float32)
    y = np.zeros((1, 1), np.float32)
    binding = sess.io_binding()
    binding.bind_ortvalue_input(input_name, ort.OrtValue.ortvalue_from_numpy(x))
    binding.bind_ortvalue_output(output_name, ort.OrtValue.ortvalue_from_numpy(y))
    for _ in range(200):
        sess.run_with_iobinding(binding)
    rows = features[np.arange(steps) % features.shape[0]]
    wall, cpu = time.perf_counter(), time.process_time()
    for row in rows:
        x[0] = row
        sess.run_with_iobinding(binding)
    return 1e6 * (time.perf_counter() - wall) / steps, 1e6 * (time.process_time() - cpu) / steps


def _variants(source: Path, scratch: Path, input_name: str, calibration: NDArray[np.float32]) -> dict[str, Path]:
    from onnxruntime.quantization import (
        CalibrationDataReader,
        QuantFormat,
        QuantType,
        quantize_dynamic,
        quantize_static,
    )

    class Reader(CalibrationDataReader):
        def __init__(self) -> None:
            self.rows = iter(calibration[:: max(1, calibration.shape[0] // 2000)])

        def get_next(self) -> dict[str, NDArray[np.float32]] | None:
            row = next(self.rows, None)
            return None if row is None else {input_name: row[None, :]}

    paths = {"float32": source}
    logging.getLogger().setLevel(logging.ERROR)  # onnxruntime's "consider pre-processing" notice
    quantize_dynamic(source, scratch / "dyn.onnx", weight_type=QuantType.QInt8)
    paths["dynamic_int8"] = scratch / "dyn.onnx"
    quantize_dynamic(source, scratch / "dyn_rr.onnx", weight_type=QuantType.QInt8, reduce_range=True)
    paths["dynamic_int8_reduce_range"] = scratch / "dyn_rr.onnx"
    quantize_static(source, scratch / "qdq.onnx", Reader(), quant_format=QuantFormat.QDQ)
    paths["static_qdq"] = scratch / "qdq.onnx"
    return paths


def quantise_bundle(
    bundle_dir: str | Path,
    features: NDArray[np.float64],
    target: NDArray[np.float64],
    *,
    steps: int = 20_000,
    rounds: int = 3,
) -> dict[str, object]:
    """Measure the variants on ``(features, target)``, apply the rule, record it (module docstring)."""
    bundle = Path(bundle_dir)
    loaded = load_bundle(bundle)  # verified, format_version checked, ``current`` resolved once
    release, manifest = loaded.path, loaded.manifest
    spec = manifest.get("correction")
    if not isinstance(spec, dict):
        raise BundleError(f"{bundle}: no correction to quantise; train one with pmactl train --model correction")
    previous = spec.get("quantisation")
    if isinstance(previous, dict) and previous.get("kept") != "float32":
        raise BundleError(
            f"{bundle}: the correction is already quantised ({previous.get('kept')}); retrain it "
            "(pmactl train --model correction) to quantise from float32 again"
        )
    input_name, output_name = str(spec["input"]), str(spec["output"])
    x = features.astype(np.float32)
    split = int(CALIBRATION_SHARE * x.shape[0])
    with tempfile.TemporaryDirectory() as scratch_dir:
        scratch = Path(scratch_dir)
        source = scratch / "float32.onnx"
        shutil.copy2(release / str(spec["file"]), source)
        paths = _variants(source, scratch, input_name, x[:split])
        measured: dict[str, dict[str, float]] = {}
        for name, path in paths.items():
            error = _outputs(path, input_name, x[split:]) - target[split:]
            measured[name] = {"rmse_bar": float(np.sqrt(np.mean(error**2)))}
        timings: dict[str, list[tuple[float, float]]] = {name: [] for name in paths}
        for _ in range(rounds):  # interleaved, so machine load hits every variant alike
            for name, path in paths.items():
                timings[name].append(step_latency(path, input_name, output_name, x, steps))
        base = measured["float32"]
        for name, m in measured.items():
            m["us_per_step_wall"] = statistics.median(t[0] for t in timings[name])
            m["us_per_step_cpu"] = statistics.median(t[1] for t in timings[name])
            m["rmse_ratio"] = m["rmse_bar"] / base["rmse_bar"] if base["rmse_bar"] > 0 else float("inf")
        kept, reasons = choose(measured)
        reason = "; ".join(reasons) if kept == "float32" else f"{kept} is within 5 % of float32 and faster"
        record: dict[str, object] = {
            "kept": kept,
            "reason": reason,
            "variants": measured,
            "rule": RULE,
        }
        new_spec = {k: v for k, v in spec.items() if k != "file"}
        new_spec["quantisation"] = record
        add_correction(bundle, paths[kept], new_spec)
    return record
