"""The correction the edge adds to the lookup-table feedforward, trained by direct inverse learning.

Method. A recording of the open-loop plant (command ``u`` [bar], contraction ``y`` [mm]) is read
backwards: had ``y`` been the reference, ``u`` is a command that produced it. The edge's
features are rebuilt from it exactly as the tick computes them (``reference_mm`` = the smoothed
``y``, ``reference_rate_mm_s`` its derivative, ``feedforward_bar`` = the bundle's own inverse
lookup table run over it from the vented rest state it arms in) and a small tanh MLP (3-16-16-1)
learns ``u - feedforward``. What it learns is what the rate-independent table cannot know:
the valve lag and the speed-dependent friction, both functions of the reference's rate.

Why this and not the alternatives: the correction acts on the reference only (no measured
feature), so it cannot destabilise the PID loop and needs no plant model; it is static, so
training is one small regression (seconds: full-batch L-BFGS from scipy on a hand-written
gradient, one BLAS thread) instead of back-propagation through a closed loop (specialised
inverse learning), and needs no torch (the graph is written with onnx's helper API); and it
reuses the bundle's table, so it corrects the feedforward the edge really runs. Its limit: a
recording's ``(y, dy/dt)`` must cover the references it will meet (record sines over the
working range and rates: ``pmactl edge record --protocol sines``, the HIL's ``sines``
scenario). What the training data covered (:func:`coverage_of`) goes into the manifest's
correction entry; the edge warns before arming when a run's reference leaves it
(:mod:`edge.runtime.coverage`).

The y signal is smoothed (Savitzky-Golay, ``SMOOTHING_S``) before differentiating: the edge's
reference is smooth, a measured contraction carries sensor noise.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from edge.errors import DataError
from edge.runtime.bundle import load_bundle
from host.data import Measurement
from host.train.common import Curve, EarlyStopping, normaliser, progress

FEATURES = ("reference_mm", "reference_rate_mm_s", "feedforward_bar")
HIDDEN = (16, 16)
SMOOTHING_S = 0.15
MIN_SAMPLES = 500


@dataclass
class CorrectionMLP:
    """The trained tanh MLP: ``features`` [N, 3] -> correction [bar].

    Attributes:
        mean, inv_std: input normalisation (per feature, in the features' units).
        scale: output scale [bar]; the last layer's output times ``scale`` is the correction.
        layers: weights [out, in] and biases [out], alternating, first layer first.
    """

    mean: NDArray[np.float64]
    inv_std: NDArray[np.float64]
    scale: float
    layers: list[NDArray[np.float64]]

    def predict(self, features: NDArray[np.float64]) -> NDArray[np.float64]:
        """Correction [bar] for each row of ``features``, in float32 as onnxruntime computes it."""
        h = (np.asarray(features, np.float32) - self.mean.astype(np.float32)) * self.inv_std.astype(np.float32)
        for k in range(0, len(self.layers), 2):
            h = h @ self.layers[k].T.astype(np.float32) + self.layers[k + 1].astype(np.float32)
            if k < len(self.layers) - 2:
                h = np.tanh(h)
        return (h[:, 0] * np.float32(self.scale)).astype(np.float64)

    def to_onnx(self, path: str | Path) -> Path:
        """Write the net as an opset-18 ONNX graph, input ``features`` [1, 3], output ``correction_bar`` [1, 1]."""
        import onnx
        from onnx import TensorProto, helper, numpy_helper

        from models_export.onnx_step import OPSET

        def constant(name: str, value: NDArray[np.float64] | float) -> onnx.TensorProto:
            return numpy_helper.from_array(np.asarray(value, np.float32), name)

        initialisers = [constant("mean", self.mean[None, :]), constant("inv_std", self.inv_std[None, :])]
        nodes = [
            helper.make_node("Sub", ["features", "mean"], ["centred"]),
            helper.make_node("Mul", ["centred", "inv_std"], ["h0"]),
        ]
        count = len(self.layers) // 2
        for i in range(count):
            initialisers += [constant(f"w{i}", self.layers[2 * i]), constant(f"b{i}", self.layers[2 * i + 1])]
            out = f"a{i}" if i < count - 1 else "net_out"
            nodes.append(helper.make_node("Gemm", [f"h{i}", f"w{i}", f"b{i}"], [out], transB=1))
            if i < count - 1:
                nodes.append(helper.make_node("Tanh", [out], [f"h{i + 1}"]))
        initialisers.append(constant("scale", self.scale))
        nodes.append(helper.make_node("Mul", ["net_out", "scale"], ["correction_bar"]))
        graph = helper.make_graph(
            nodes,
            "pmactl_correction",
            [helper.make_tensor_value_info("features", TensorProto.FLOAT, [1, len(self.mean)])],
            [helper.make_tensor_value_info("correction_bar", TensorProto.FLOAT, [1, 1])],
            initialisers,
        )
        model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", OPSET)], producer_name="pmactl")
        model.ir_version = 9  # what onnxruntime >= 1.17 reads
        onnx.checker.check_model(model)
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        onnx.save(model, str(path))
        return path


@dataclass
class CorrectionResult:
    """What the training did: held-out tail RMSE with and without the correction [bar]."""

    features: tuple[str, ...]
    fit_seconds: float
    tail_rmse_bar: float
    tail_rmse_ff_bar: float
    samples: int
    curve: Curve
    coverage: dict[str, list[float]]
    model_path: Path | None = None

    def as_dict(self) -> dict[str, object]:
        return {
            "model": "correction",
            "features": list(self.features),
            "fit_seconds": self.fit_seconds,
            "samples": self.samples,
            "tail_rmse_bar": self.tail_rmse_bar,
            "feedforward_only_tail_rmse_bar": self.tail_rmse_ff_bar,
            "coverage": self.coverage,
        }

    def coverage_line(self, unit: str = "mm") -> str:
        """What the training data covers, in words (the references the correction has seen)."""
        (lo, hi), (rlo, rhi) = self.coverage["reference_mm"], self.coverage["reference_rate_mm_s"]
        return f"covers references {lo:.1f}..{hi:.1f} {unit} at rates {rlo:.1f}..{rhi:.1f} {unit}/s"


def coverage_of(features: NDArray[np.float64]) -> dict[str, list[float]]:
    """The references a correction's training data covers: the range [mm] of its smoothed
    contraction and the range [mm/s] of its rate (features in :data:`FEATURES` order), as the
    manifest's ``correction.coverage`` records them (read by :mod:`edge.runtime.coverage`)."""
    reference, rate = features[:, 0], features[:, 1]
    return {
        "reference_mm": [float(reference.min()), float(reference.max())],
        "reference_rate_mm_s": [float(rate.min()), float(rate.max())],
    }


def correction_features(bundle_dir: str | Path, record: Measurement) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """(features [N, 3] in :data:`FEATURES` order, target correction [bar]) of one recording."""
    if len(record) < MIN_SAMPLES:
        raise DataError(f"{record.source}: only {len(record)} samples; the correction needs at least {MIN_SAMPLES}")
    bundle = load_bundle(bundle_dir)
    window = max(5, int(round(SMOOTHING_S / record.dt)) | 1)
    reference = savgol_filter(record.y, window, 3)
    rate = savgol_filter(record.y, window, 3, deriv=1, delta=record.dt)
    inverse = bundle.inverse
    inverse.reset()
    feedforward = inverse.simulate(reference)
    return np.column_stack([reference, rate, feedforward]), record.u - feedforward


def _initial_weights(sizes: tuple[int, ...], rng: np.random.Generator) -> list[NDArray[np.float64]]:
    """Uniform +-1/sqrt(fan-in) weights and biases (the usual default of a dense layer)."""
    params = []
    for fan_in, fan_out in zip(sizes, sizes[1:]):
        bound = 1.0 / np.sqrt(fan_in)
        params += [rng.uniform(-bound, bound, (fan_out, fan_in)), rng.uniform(-bound, bound, fan_out)]
    return params


def train_correction(
    features: NDArray[np.float64],
    target: NDArray[np.float64],
    *,
    seed: int = 0,
    epochs: int = 300,
    quiet: bool = True,
    tail_fraction: float = 0.2,
    patience: int = 60,
) -> tuple[CorrectionMLP, Curve, float, int]:
    """Fit the MLP by full-batch L-BFGS with early stopping on the last ``tail_fraction``.

    ``epochs`` is the number of L-BFGS iterations (each one pass over the data with its
    gradient, written out by hand below). Returns (the net with the best held-out tail,
    the curve, that tail's RMSE [bar], the number of training samples).
    """
    from scipy.optimize import minimize
    from threadpoolctl import threadpool_limits

    n_train = int((1 - tail_fraction) * target.size)
    stats = [normaliser(features[:n_train, j]) for j in range(features.shape[1])]
    mean = np.array([s[0] for s in stats])
    inv_std = 1.0 / np.array([s[1] for s in stats])
    scale = float(normaliser(target[:n_train])[1])
    x = (features - mean) * inv_std
    x_train, x_tail = x[:n_train], x[n_train:]
    t_train = target[:n_train] / scale
    sizes = (features.shape[1], *HIDDEN, 1)
    start = _initial_weights(sizes, np.random.default_rng(seed))
    shapes = [p.shape for p in start]
    splits = np.cumsum([p.size for p in start])[:-1]

    def unpack(theta: NDArray[np.float64]) -> list[NDArray[np.float64]]:
        return [part.reshape(shape) for part, shape in zip(np.split(theta, splits), shapes)]

    def loss_and_gradient(theta: NDArray[np.float64]) -> tuple[float, NDArray[np.float64]]:
        params = unpack(theta)
        activations = [x_train]
        for k in range(0, len(params) - 2, 2):
            activations.append(np.tanh(activations[-1] @ params[k].T + params[k + 1]))
        residual = activations[-1] @ params[-2].T + params[-1] - t_train[:, None]
        delta = 2.0 * residual / t_train.size
        gradients: list[NDArray[np.float64]] = []
        for k in range(len(params) - 2, -1, -2):
            gradients[:0] = [delta.T @ activations[k // 2], delta.sum(axis=0)]
            if k:
                delta = (delta @ params[k]) * (1.0 - activations[k // 2] ** 2)
        return float(np.mean(residual**2)), np.concatenate([g.ravel() for g in gradients])

    curve, stopper = Curve(), EarlyStopping(patience)
    bar = progress(epochs, "correction", quiet)

    def after_iteration(intermediate_result: object) -> None:
        theta = np.asarray(intermediate_result.x)  # type: ignore[attr-defined]
        net = CorrectionMLP(mean, inv_std, scale, unpack(theta))
        tail = float(np.sqrt(np.mean((net.predict(features[n_train:]) - target[n_train:]) ** 2)))
        iteration = next(bar, epochs)
        curve.add("L-BFGS, full batch", iteration, float(intermediate_result.fun), tail)  # type: ignore[attr-defined]
        if stopper.update(tail, {"theta": theta}):
            raise StopIteration

    del x_tail  # the tail is scored through CorrectionMLP.predict, exactly as exported
    # one BLAS thread: the matrices are [N, 16]; more threads cost 8x the CPU time here
    with threadpool_limits(1):
        minimize(
            loss_and_gradient,
            np.concatenate([p.ravel() for p in start]),
            jac=True,
            method="L-BFGS-B",
            callback=after_iteration,
            options={"maxiter": epochs, "maxfun": 2 * epochs},
        )
    for _ in bar:  # close the progress bar when L-BFGS converged early
        pass
    if stopper.best_state is None:
        raise DataError("the correction did not train: the held-out tail error was never finite; check the recording")
    best = unpack(np.asarray(stopper.best_state["theta"]))
    return CorrectionMLP(mean, inv_std, scale, best), curve, stopper.best, n_train


def train_correction_into(
    bundle_dir: str | Path, records: list[Measurement], *, seed: int = 0, epochs: int = 300, quiet: bool = True
) -> CorrectionResult:
    """Train the correction on ``records`` and add it to the bundle at ``bundle_dir``."""
    import tempfile

    from models_export.bundle import add_correction

    start = time.perf_counter()
    pairs = [correction_features(bundle_dir, r) for r in records]
    features = np.concatenate([p[0] for p in pairs])
    target = np.concatenate([p[1] for p in pairs])
    model, curve, tail_rmse, n_train = train_correction(features, target, seed=seed, epochs=epochs, quiet=quiet)
    fit_seconds = time.perf_counter() - start
    coverage = coverage_of(features)
    with tempfile.TemporaryDirectory() as scratch:
        path = model.to_onnx(Path(scratch) / "correction.onnx")
        spec: dict[str, object] = {
            "features": list(FEATURES),
            "input": "features",
            "output": "correction_bar",
            "coverage": coverage,
            "training": {
                "method": "direct inverse learning, L-BFGS (host/train/correction.py)",
                "records": [Path(r.source).name for r in records],
                "seed": seed,
                "tail_rmse_bar": tail_rmse,
            },
        }
        add_correction(bundle_dir, path, spec)
    ff_only = float(np.sqrt(np.mean(target[n_train:] ** 2)))
    return CorrectionResult(FEATURES, fit_seconds, tail_rmse, ff_only, int(target.size), curve, coverage)


WORKING_RANGE_BAR = (0.1, 5.9)
WORKING_FREQUENCIES_HZ = (0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)


def working_range_recording(seed: int = 11, duration_s: float = 140.0, rate_hz: float = 100.0) -> Measurement:
    """Open-loop sines over the emulated rig's whole working range, 0.1-5.9 bar at 0.05-1 Hz.

    The correction can only correct references its training covered. The HIL's ``sines``
    protocol stays within 0.2-3.8 bar (about 58 mm), while Ai2019's tracking test asks for
    70 mm (about 5.8 bar), so this drives the emulated plant (``hil.plant``, default rig) with
    whole sine cycles over the rig's pressure limits, in a seeded random order, sampled with
    the sensor noise of ``pmactl hil record``.
    """
    from hil.plant import PlantParams, initial_state, output, update

    params = PlantParams()
    rng = np.random.default_rng(seed)
    lo, hi = WORKING_RANGE_BAR
    segment = duration_s / len(WORKING_FREQUENCIES_HZ)
    pieces = []
    for index in rng.permutation(len(WORKING_FREQUENCIES_HZ)):
        frequency = WORKING_FREQUENCIES_HZ[index]
        cycles = max(1, int(round(segment * frequency)))
        local = np.arange(int(round(cycles / frequency / params.dt_s))) * params.dt_s
        pieces.append(lo + (hi - lo) * 0.5 * (1.0 - np.cos(2 * np.pi * frequency * local)))
    commands = np.concatenate(pieces)
    decimation = int(round(1.0 / (rate_hz * params.dt_s)))
    x = initial_state(params, float(commands[0]))
    t_out, u_out, y_out = [], [], []
    for i, command in enumerate(commands.tolist()):
        t = i * params.dt_s
        if i % decimation == 0:
            t_out.append(t)
            u_out.append(command)
            y_out.append(output(t, x, params)[0])
        x = update(t, x, command, params)
    y = np.asarray(y_out) + rng.normal(0.0, 0.03, len(y_out))
    return Measurement(
        np.asarray(t_out), np.asarray(u_out), y, source=f"emulated rig, working-range sines, seed {seed}"
    )


def correction_bundle(
    bundle_dir: str | Path, recording: Measurement | None = None, *, seed: int = 0
) -> CorrectionResult:
    """Equip the bundle at ``bundle_dir`` with a trained correction (for ``pmactl demo``).

    Without ``recording``, the emulated rig is driven over its working range
    (:func:`working_range_recording`), in-process, about 140 s of simulated time.
    """
    if recording is None:
        recording = working_range_recording()
    return train_correction_into(bundle_dir, [recording], seed=seed)
