"""Int8 variants of a bundle's nets (forward and inverse step graphs), measured under ``quantise``'s rule.

The step graphs are traced ``LSTMCell``/``Linear`` modules: MatMul/Gemm, Add, Mul, Tanh,
Sigmoid nodes, no ONNX ``LSTM`` op (:mod:`models_export.onnx_step`). Variants, as for the
correction (:mod:`models_export.quantise`):

* ``dynamic_int8`` / ``dynamic_int8_reduce_range``: ``quantize_dynamic`` (int8 MatMul/Gemm
  weights, activations quantised at run time);
* ``static_qdq``: ``quantize_static`` in QDQ format, activations calibrated (MinMax) on the
  float32 net's own inputs and carried state over the first 80 % of the recording.

Accuracy: each variant runs free over the calibration recording, as on the edge (state carried
by the caller, started at the first sample), and is scored on the last 20 % against what the
recording says: the contraction for the forward net, the command for the inverse net (the
recorded contraction as its target, ``preview_s`` ahead). Speed: CPU time per step of one bound
session, median of interleaved rounds. The rule is :data:`models_export.quantise.RULE`
(:func:`models_export.quantise.choose`), against what the edge runs for the float32 net: the
faster of its onnxruntime session and the fused numpy evaluator (which the edge uses when it
passes parity; a quantised graph is not fused). A kept variant replaces the net in a new
release (:func:`models_export.bundle.replace_net`, golden vectors recorded again); when every
net keeps float32 the bundle is not changed.

Measured (emulated rig, rate_dependence seed 1, LSTM-NARMAX hidden 7 and the Hammerstein
2-5-10-1 + ARX, 85 s held-out record at 100 Hz): the dynamic int8 variants are as accurate
(0.998-1.007x) but take 1.3-1.5x float32's CPU time per step, static QDQ 2.5-2.8x (and 1.25x
the RMSE on the Hammerstein); the fused numpy step takes 0.45x. The graphs are a few hundred
multiply-adds: quantising and dequantising activations costs more than the int8 products save.
"""

from __future__ import annotations

import logging
import shutil
import statistics
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.control.fused_graph import narmax_from_graph
from edge.control.net_hammerstein import is_hammerstein
from edge.control.onnx_graph import GraphFormatError, read_graph
from edge.errors import BundleError
from edge.hysteresis.lut import CompiledModel, read_table
from edge.runtime.bundle import Bundle
from models_export.onnx_step import session
from models_export.quantise import CALIBRATION_SHARE, RULE, choose

ROUNDS = 3
TIMING_STEPS = 5_000


@dataclass
class NetTrajectory:
    """A net's per-step inputs ``u``, ``n`` over a recording and the value its output should have."""

    u: NDArray[np.float64]
    n: NDArray[np.float64]
    expected: NDArray[np.float64]


class _Stepper:
    """A step graph's session with bound, preallocated inputs, outputs and carried state."""

    def __init__(self, path: Path) -> None:
        import onnxruntime as ort

        self.session = session(path)
        names = [i.name for i in self.session.get_inputs()]
        shapes = {i.name: int(i.shape[1]) for i in self.session.get_inputs()}
        self.state_names = [name for name in names if name not in ("u", "n")]
        self.u, self.n, self.y = (np.zeros((1, 1), np.float32) for _ in range(3))
        self.state_in = {name: np.zeros((1, shapes[name]), np.float32) for name in self.state_names}
        self.state_out = {name: np.zeros((1, shapes[name]), np.float32) for name in self.state_names}
        self.binding = self.session.io_binding()
        value = ort.OrtValue.ortvalue_from_numpy
        self.binding.bind_ortvalue_input("u", value(self.u))
        self.binding.bind_ortvalue_input("n", value(self.n))
        self.binding.bind_ortvalue_output("y", value(self.y))
        for name in self.state_names:
            self.binding.bind_ortvalue_input(name, value(self.state_in[name]))
            self.binding.bind_ortvalue_output(f"{name}_out", value(self.state_out[name]))

    def _run(self, u: float, n: float) -> None:
        self.u[0, 0], self.n[0, 0] = u, n
        self.session.run_with_iobinding(self.binding)

    def start(self, u0: float, n0: float) -> None:
        """The edge's start: LSTM-NARMAX lags at the first sample, Hammerstein ARX in its steady state."""
        if "v_lags" in self.state_in:
            for array in self.state_in.values():
                array.fill(0.0)
            self._run(u0, n0)
            v0 = float(self.state_out["v_lags"][0, 0])
            for array in self.state_in.values():
                array.fill(v0)
            return
        for name, array in self.state_in.items():
            array.fill(u0 if name == "u_lag" else n0 if name in ("n_lag", "y_lag") else 0.0)

    def step(self, u: float, n: float) -> float:
        self._run(u, n)
        for name, array in self.state_in.items():
            np.copyto(array, self.state_out[name])
        return float(self.y[0, 0])

    def free_run(self, trajectory: NetTrajectory, record_state: bool = False) -> tuple[NDArray[np.float64], list]:
        """Outputs over the trajectory from :meth:`start`; with ``record_state`` every step's feed too."""
        self.start(float(trajectory.u[0]), float(trajectory.n[0]))
        out, feeds = np.empty(trajectory.u.size), []
        for k, (u, n) in enumerate(zip(trajectory.u.tolist(), trajectory.n.tolist())):
            if record_state:
                feeds.append(
                    {"u": np.array([[u]], np.float32), "n": np.array([[n]], np.float32)}
                    | {name: array.copy() for name, array in self.state_in.items()}
                )
            out[k] = self.step(u, n)
        return out, feeds

    def latency(self, trajectory: NetTrajectory, steps: int) -> tuple[float, float]:
        """(wall, CPU) microseconds per step over ``steps`` steps of the trajectory."""
        self.start(float(trajectory.u[0]), float(trajectory.n[0]))
        index = np.arange(steps) % trajectory.u.size
        u, n = trajectory.u[index].tolist(), trajectory.n[index].tolist()
        step = self.step
        wall, cpu = time.perf_counter(), time.process_time()
        for a, b in zip(u, n):
            step(a, b)
        return 1e6 * (time.perf_counter() - wall) / steps, 1e6 * (time.process_time() - cpu) / steps


def trajectories(bundle: Bundle, u: NDArray[np.float64], y: NDArray[np.float64]) -> dict[str, NetTrajectory]:
    """Each net's inputs over one recording (pressure ``u`` [bar], contraction ``y`` [mm]) and its target;
    a state-space forward net (inputs ``u, x``, not ``u, n``) is left out: it stays float32."""
    from host.data import Measurement
    from host.train.net_inverse import inverse_data

    result: dict[str, NetTrajectory] = {}
    step_s = float(bundle.net_spec("forward" if "forward" in bundle.net_paths else "inverse")["step_s"])  # type: ignore[arg-type]
    if "forward" in bundle.net_paths and bundle.net_spec("forward").get("model") != "state-space":
        spec = bundle.net_spec("forward")
        operator = spec["operator"]
        assert isinstance(operator, dict)
        table = CompiledModel(read_table(bundle.path / str(operator["file"])))
        centre, half = float(operator["warp_centre"]), float(operator["warp_half_range"])
        x = np.tanh((u - centre) / half) if half > 0 else u
        result["forward"] = NetTrajectory(u, table.simulate(x), y)
    if "inverse" in bundle.net_paths:
        record = Measurement(np.arange(u.size, dtype=np.float64) * step_s, u, y, source="calibration")
        target, table_n, command = inverse_data(record, CompiledModel(bundle.inverse.table))
        preview = float(bundle.net_spec("inverse").get("preview_s", 0.0))  # type: ignore[arg-type]
        d = int(round(preview / step_s))
        if d:
            target, table_n, command = target[d:], table_n[d:], command[:-d]
        result["inverse"] = NetTrajectory(target, table_n, command)
    return result


def _variants(source: Path, scratch: Path, feeds: list) -> dict[str, Path]:
    from onnxruntime.quantization import (
        CalibrationDataReader,
        QuantFormat,
        QuantType,
        quantize_dynamic,
        quantize_static,
    )

    class Reader(CalibrationDataReader):
        def __init__(self) -> None:
            self.rows = iter(feeds[:: max(1, len(feeds) // 2000)])

        def get_next(self) -> dict[str, NDArray[np.float32]] | None:
            return next(self.rows, None)

    logging.getLogger().setLevel(logging.ERROR)
    paths = {"float32": source}
    quantize_dynamic(source, scratch / "dyn.onnx", weight_type=QuantType.QInt8)
    paths["dynamic_int8"] = scratch / "dyn.onnx"
    quantize_dynamic(source, scratch / "dyn_rr.onnx", weight_type=QuantType.QInt8, reduce_range=True)
    paths["dynamic_int8_reduce_range"] = scratch / "dyn_rr.onnx"
    quantize_static(source, scratch / "qdq.onnx", Reader(), quant_format=QuantFormat.QDQ)
    paths["static_qdq"] = scratch / "qdq.onnx"
    return paths


def _fused_us(path: Path, spec: dict[str, object], trajectory: NetTrajectory, steps: int) -> float | None:
    """CPU microseconds per step of the fused numpy evaluator (``None``: the graph is not fused)."""
    if is_hammerstein(spec):
        return None
    try:
        fused = narmax_from_graph(read_graph(path))
    except GraphFormatError:
        return None
    fused.reset(float(trajectory.u[0]), float(trajectory.n[0]))
    index = np.arange(steps) % trajectory.u.size
    step: Callable[[float, float], float] = fused.step
    cpu = time.process_time()
    for a, b in zip(trajectory.u[index].tolist(), trajectory.n[index].tolist()):
        step(a, b)
    return 1e6 * (time.process_time() - cpu) / steps


def measure_nets(
    bundle: Bundle,
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    scratch_keep: Path,
    kept_paths: dict[str, Path],
) -> dict[str, dict[str, object]]:
    """Per net: every variant's held-out RMSE and step time, the fused evaluator's time, the rule's
    choice; a kept variant's graph is copied to ``scratch_keep`` and named in ``kept_paths``."""
    report: dict[str, dict[str, object]] = {}
    for which, trajectory in trajectories(bundle, u, y).items():
        previous = bundle.net_spec(which).get("quantisation")
        if isinstance(previous, dict) and previous.get("kept") != "float32":
            raise BundleError(
                f"{bundle.path}: the {which} net is already quantised ({previous.get('kept')}); retrain it "
                "(pmactl train --save) to quantise from float32 again"
            )
        split = int(CALIBRATION_SHARE * trajectory.u.size)
        with tempfile.TemporaryDirectory() as scratch_dir:
            scratch = Path(scratch_dir)
            source = scratch / "float32.onnx"
            shutil.copy2(bundle.net_paths[which], source)
            _, feeds = _Stepper(source).free_run(
                NetTrajectory(trajectory.u[:split], trajectory.n[:split], trajectory.expected[:split]), True
            )
            paths = _variants(source, scratch, feeds)
            measured: dict[str, dict[str, float]] = {}
            steppers = {name: _Stepper(path) for name, path in paths.items()}
            for name, stepper in steppers.items():
                out, _ = stepper.free_run(trajectory)
                error = out[split:] - trajectory.expected[split:]
                measured[name] = {"rmse": float(np.sqrt(np.mean(error**2)))}
            timings: dict[str, list[tuple[float, float]]] = {name: [] for name in paths}
            for _ in range(ROUNDS):
                for name, stepper in steppers.items():
                    timings[name].append(stepper.latency(trajectory, TIMING_STEPS))
            base = measured["float32"]
            for name, m in measured.items():
                m["us_per_step_wall"] = statistics.median(t[0] for t in timings[name])
                m["us_per_step_cpu"] = statistics.median(t[1] for t in timings[name])
                m["rmse_ratio"] = m["rmse"] / base["rmse"] if base["rmse"] > 0 else float("inf")
            fused = _fused_us(source, bundle.net_spec(which), trajectory, TIMING_STEPS)
            edge_us = min(base["us_per_step_cpu"], fused if fused is not None else np.inf)
            kept, reasons = choose({**measured, "float32": {**base, "us_per_step_cpu": edge_us}})
            if kept != "float32":
                kept_paths[which] = scratch_keep / f"{which}.onnx"
                shutil.copy2(paths[kept], kept_paths[which])
        report[which] = {
            "model": bundle.net_spec(which).get("model", "lstm-narmax"),
            "kept": kept,
            "reason": "; ".join(reasons) if kept == "float32" else f"{kept} is within 5 % of float32 and faster",
            "variants": measured,
            "fused_numpy_us_per_step_cpu": fused,
            "float32_edge_us_per_step_cpu": edge_us,
            "rule": RULE + " (float32: the faster of onnxruntime and the fused numpy step, as the edge runs it)",
        }
    return report


def quantise_nets(bundle_dir: str | Path, u: NDArray[np.float64], y: NDArray[np.float64]) -> dict[str, object]:
    """Measure every net's variants on one recording (pressure ``u`` [bar], contraction ``y`` [mm],
    sampled at the nets' ``step_s``), apply the rule, write a new release only when a variant is kept."""
    from edge.runtime.bundle import load_bundle
    from models_export.bundle import replace_net

    bundle = load_bundle(bundle_dir)
    if not bundle.net_paths:
        raise BundleError(f"{bundle_dir}: holds no nets; train them with pmactl train --model lstm-narmax --save")
    kept: dict[str, Path] = {}
    with tempfile.TemporaryDirectory() as keep_dir:
        report = measure_nets(bundle, u, y, Path(keep_dir), kept)
        for which, path in kept.items():
            record = {k: v for k, v in report[which].items() if k != "model"}
            replace_net(bundle_dir, which, path, record)
    return {"nets": report, "changed": sorted(kept)}
