"""Training the neural hysteresis models (torch, CPU): Hammerstein, LSTM-NARMAX, the correction.

:func:`train_model` fits ``hammerstein`` or ``lstm-narmax`` on measured records,
:func:`score_model` scores it on held-out records with the scoring rule of
:mod:`host.evaluate`, :func:`save_model` writes the ONNX step graph, its description, the
operator's lookup table and the training curve. The correction the edge runs is in
:mod:`host.train.correction` (:func:`~host.train.correction.correction_bundle`).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from edge.errors import ModelError
from edge.hysteresis.lut import write_table
from host.data import Measurement
from host.evaluate import Prediction, predict_with_candidates
from host.train.common import Split, seed_everything, split_record
from host.train.hammerstein import Hammerstein, train_hammerstein
from host.train.lstm_narmax import LSTMNarmax, train_lstm_narmax
from host.train.state_space import NeuralStateSpace, save_state_space, train_state_space

MODELS = ("hammerstein", "lstm-narmax", "state-space")
TrainedModel = Hammerstein | LSTMNarmax | NeuralStateSpace
TRAINERS: dict[str, Callable[..., tuple[TrainedModel, Split]]] = {
    "hammerstein": train_hammerstein,
    "lstm-narmax": train_lstm_narmax,
    "state-space": train_state_space,
}


def join(records: list[Measurement]) -> Measurement:
    """Records joined in order, time made continuous (one long record to train on)."""
    if len(records) == 1:
        return records[0]
    t, u, y = [], [], []
    offset = 0.0
    for m in records:
        t.append(m.t - m.t[0] + offset)
        u.append(m.u)
        y.append(m.y)
        offset = float(t[-1][-1]) + m.dt
    return Measurement(
        np.concatenate(t), np.concatenate(u), np.concatenate(y), source=" + ".join(m.source for m in records)
    )


@dataclass
class Trained:
    """A trained model with how it was trained."""

    model: TrainedModel
    fit_seconds: float
    samples: int
    memory_start: int
    tail_start: int
    seed: int


def train_model(
    kind: str,
    records: list[Measurement],
    *,
    seed: int = 0,
    epochs: int = 60,
    quiet: bool = True,
    tail_fraction: float = 0.2,
) -> Trained:
    """Train ``kind`` on ``records`` (joined); the last ``tail_fraction`` is for early stopping."""
    if kind not in MODELS:
        raise ModelError(f"model {kind!r} unknown; choose one of {', '.join(MODELS)}")
    if epochs < 1:
        raise ModelError(f"--epochs {epochs} must be at least 1")
    record = join(records)
    seed_everything(seed)
    start = time.perf_counter()

    def split_fn(memory_start: int):  # noqa: ANN202
        return split_record(len(record), memory_start, tail_fraction, record.source)

    model, split = TRAINERS[kind](record.u, record.y, split_fn, seed=seed, epochs=epochs, quiet=quiet)
    return Trained(model, time.perf_counter() - start, len(record), split.start, split.tail, seed)


@dataclass
class ModelScore:
    """A held-out score with MAE and the time one free run of the record took."""

    name: str
    prediction: Prediction
    mae: float
    ms_per_run: float


def score_model(model: TrainedModel, records: list[Measurement], calibration_fraction: float = 0.1) -> list[ModelScore]:
    """Score on each record: start state and offset from the calibration window (see host.evaluate)."""
    results = []
    for m in records:
        start = time.perf_counter()
        model.simulate(m.u, "descending")
        ms = 1e3 * (time.perf_counter() - start)
        prediction = predict_with_candidates(model.simulate, m.u, m.y, calibration_fraction=calibration_fraction)
        mae = float(np.mean(np.abs(prediction.y[prediction.window_end :] - m.y[prediction.window_end :])))
        results.append(ModelScore(Path(m.source).name, prediction, mae, ms))
    return results


def save_model(trained: Trained, directory: str | Path, record: dict[str, object]) -> Path:
    """Write ``step.onnx``, ``model.json``, ``operator.npz`` and ``training_curve.png`` to ``directory``."""
    from models_export.onnx_step import export_step

    if isinstance(trained.model, NeuralStateSpace):
        return save_state_space(trained.model, directory, record)
    model = trained.model
    directory = Path(directory)
    directory.mkdir(exist_ok=True)  # its parent must exist: a typo should not grow a tree
    _, spec = export_step(model.kind, model.weights, directory / "step.onnx")
    operator = model.operator.operator
    write_table(operator.model.compile(), directory / "operator.npz")
    curve_png = model.curve.save_png(directory / "training_curve.png", f"{model.kind} training")
    description = {
        "kind": model.kind,
        "step": {"file": "step.onnx", **spec.as_dict()},
        # the memory range lets ``pmactl simulate`` start on the same outer branches as training scored
        "operator": {"file": "operator.npz", **operator.describe(), "memory_range": list(operator.model.memory_range)},
        "training": {**record, "curve": model.curve.as_dict(), "curve_png": curve_png.name},
    }
    if isinstance(model, Hammerstein):
        w = model.weights
        description["arx"] = {"orders": list(w.orders), "a": w.a.tolist(), "b": w.b.tolist(), "selection": model.aic}
    (directory / "model.json").write_text(json.dumps(description, indent=2) + "\n")
    return directory
