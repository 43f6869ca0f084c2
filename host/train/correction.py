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
training is one small regression (seconds) instead of back-propagation through a closed loop
(specialised inverse learning); and it reuses the bundle's table, so it corrects the
feedforward the edge really runs. Its limit: a recording's ``(y, dy/dt)`` must cover the
references it will meet (record sines over the working range and rates, e.g. the HIL's
``sines`` scenario).

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
from host.train.common import Curve, EarlyStopping, normaliser, progress, seed_everything

FEATURES = ("reference_mm", "reference_rate_mm_s", "feedforward_bar")
HIDDEN = (16, 16)
SMOOTHING_S = 0.15
MIN_SAMPLES = 500


@dataclass
class CorrectionResult:
    """What the training did: held-out tail RMSE with and without the correction [bar]."""

    features: tuple[str, ...]
    fit_seconds: float
    tail_rmse_bar: float
    tail_rmse_ff_bar: float
    samples: int
    curve: Curve
    model_path: Path | None = None

    def as_dict(self) -> dict[str, object]:
        return {
            "model": "correction",
            "features": list(self.features),
            "fit_seconds": self.fit_seconds,
            "samples": self.samples,
            "tail_rmse_bar": self.tail_rmse_bar,
            "feedforward_only_tail_rmse_bar": self.tail_rmse_ff_bar,
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


def train_correction(
    features: NDArray[np.float64],
    target: NDArray[np.float64],
    *,
    seed: int = 0,
    epochs: int = 300,
    quiet: bool = True,
    tail_fraction: float = 0.2,
    patience: int = 40,
):  # noqa: ANN201 (returns a torch module)
    """Fit the MLP (Adam, full batch) with early stopping on the last ``tail_fraction``."""
    import torch
    from torch import nn

    seed_everything(seed)
    n_train = int((1 - tail_fraction) * target.size)
    stats = [normaliser(features[:n_train, j]) for j in range(features.shape[1])]
    mean = np.array([s[0] for s in stats], np.float32)
    std = np.array([s[1] for s in stats], np.float32)
    scale = float(normaliser(target[:n_train])[1])

    class Correction(nn.Module):
        def __init__(self) -> None:
            super().__init__()
            sizes = (features.shape[1], *HIDDEN, 1)
            layers: list[nn.Module] = []
            for i, (a, b) in enumerate(zip(sizes, sizes[1:])):
                layers.append(nn.Linear(a, b))
                if i < len(sizes) - 2:
                    layers.append(nn.Tanh())
            self.net = nn.Sequential(*layers)
            self.register_buffer("mean", torch.from_numpy(mean[None, :]))
            self.register_buffer("inv_std", torch.from_numpy((1.0 / std)[None, :]))
            self.register_buffer("scale", torch.tensor(scale, dtype=torch.float32))

        def forward(self, x):  # noqa: ANN001, ANN202
            return self.net((x - self.mean) * self.inv_std) * self.scale

    model = Correction()
    x = torch.as_tensor(features, dtype=torch.float32)
    y = torch.as_tensor(target[:, None], dtype=torch.float32)
    optimiser = torch.optim.Adam(model.parameters(), lr=1e-2)
    curve, stopper = Curve(), EarlyStopping(patience)
    for epoch in progress(epochs, "correction", quiet):
        loss = torch.mean(((model(x[:n_train]) - y[:n_train]) / scale) ** 2)
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        with torch.no_grad():
            tail = float(torch.sqrt(torch.mean((model(x[n_train:]) - y[n_train:]) ** 2)))
        curve.add("Adam, full batch", epoch, float(loss.detach()), tail)
        if stopper.update(tail, {"model": model.state_dict()}):
            break
    if stopper.best_state is not None:
        model.load_state_dict(stopper.best_state["model"])  # type: ignore[arg-type]
    return model.eval(), curve, stopper.best, n_train


def train_correction_into(
    bundle_dir: str | Path, records: list[Measurement], *, seed: int = 0, epochs: int = 300, quiet: bool = True
) -> CorrectionResult:
    """Train the correction on ``records`` and add it to the bundle at ``bundle_dir``."""
    import tempfile

    import torch

    from models_export.bundle import add_correction
    from models_export.onnx_step import export_module

    start = time.perf_counter()
    pairs = [correction_features(bundle_dir, r) for r in records]
    features = np.concatenate([p[0] for p in pairs])
    target = np.concatenate([p[1] for p in pairs])
    model, curve, tail_rmse, n_train = train_correction(features, target, seed=seed, epochs=epochs, quiet=quiet)
    fit_seconds = time.perf_counter() - start
    with tempfile.TemporaryDirectory() as scratch:
        path = export_module(
            model, (torch.zeros(1, len(FEATURES)),), Path(scratch) / "correction.onnx", ["features"], ["correction_bar"]
        )
        spec: dict[str, object] = {
            "features": list(FEATURES),
            "input": "features",
            "output": "correction_bar",
            "training": {
                "method": "direct inverse learning (host/train/correction.py)",
                "records": [Path(r.source).name for r in records],
                "seed": seed,
                "tail_rmse_bar": tail_rmse,
            },
        }
        add_correction(bundle_dir, path, spec)
    ff_only = float(np.sqrt(np.mean(target[n_train:] ** 2)))
    return CorrectionResult(FEATURES, fit_seconds, tail_rmse, ff_only, int(target.size), curve)


WORKING_RANGE_BAR = (0.1, 5.9)
WORKING_FREQUENCIES_HZ = (0.05, 0.1, 0.2, 0.35, 0.5, 0.75, 1.0)


def working_range_recording(seed: int = 11, duration_s: float = 140.0, rate_hz: float = 100.0) -> Measurement:
    """Open-loop sines over the emulated rig's whole working range, 0.1-5.9 bar at 0.05-1 Hz.

    The correction can only correct references its training covered. The HIL's ``sines``
    protocol stays within 0.2-3.8 bar (about 58 mm), while seed 000's tracking test asks for
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
