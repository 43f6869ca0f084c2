"""The neural state-space model (host/train/state_space.py): seeds, learning, export parity, errors."""

from __future__ import annotations

import numpy as np
import pytest

from edge.errors import DataError
from host.train.common import seed_everything, split_record
from host.train.state_space import (
    StateSpaceSettings,
    export_onnx,
    simulate_numpy,
    simulate_onnx,
    train_state_space,
)

TINY = StateSpaceSettings(
    state_order=2,  # the plant's order
    hidden=8,
    encoder_lags=6,
    encoder_hidden=8,
    window=32,
    batch=16,
    steps_per_epoch=15,
    score_horizon=400,
    patience=50,
)


def plant(u: np.ndarray) -> np.ndarray:
    """A plant we did not fit anything to: a lightly damped resonance with a hardening (Duffing) spring."""
    y = np.zeros_like(u)
    x1 = x2 = 0.0
    for k in range(u.size - 1):
        y[k] = x1
        for _ in range(4):  # semi-implicit Euler at a quarter of the sample period
            x2 += 0.025 * (u[k] - x1 - x1**3 - 0.3 * x2)
            x1 += 0.025 * x2
    y[-1] = x1
    return y


@pytest.fixture(scope="module")
def record():
    rng = np.random.default_rng(7)
    u = np.convolve(rng.normal(0, 1.5, 3200), np.ones(4) / 4, mode="same")
    return u, plant(u)


def train(u, y, seed=0, epochs=6, settings=TINY):
    seed_everything(seed)
    return train_state_space(
        u, y, lambda s: split_record(len(u), s, 0.2, "test"), seed=seed, epochs=epochs, settings=settings
    )[0]


def test_the_same_seed_gives_the_same_model(record):
    u, y = record
    a, b = train(u, y, seed=3, epochs=2), train(u, y, seed=3, epochs=2)
    assert np.array_equal(a.simulate(u[:300]), b.simulate(u[:300]))
    c = train(u, y, seed=4, epochs=2)
    assert not np.array_equal(a.simulate(u[:300]), c.simulate(u[:300]))


def test_training_beats_the_linear_start_on_a_held_out_input(record):
    u, y = record
    start = train(u, y, epochs=1, settings=StateSpaceSettings(**{**TINY.__dict__, "steps_per_epoch": 1, "lr": 1e-9}))
    trained = train(u, y, epochs=25)
    u_new = np.convolve(np.random.default_rng(99).normal(0, 1.5, 1500), np.ones(4) / 4, mode="same")
    y_new = plant(u_new)
    rmse = lambda m: float(np.sqrt(np.mean((m.simulate(u_new) - y_new) ** 2)))  # noqa: E731
    assert rmse(trained) < 0.6 * rmse(start)


def test_rest_stays_at_rest(record):
    u, y = record
    model = train(u, y, epochs=1)
    assert np.all(model.simulate(np.zeros(200)) == 0.0)


def test_the_onnx_step_matches_the_numpy_and_torch_free_run(record, tmp_path):
    import torch

    u, y = record
    model = train(u, y, epochs=3)
    w = model.weights
    u_new = np.convolve(np.random.default_rng(5).normal(0, 1.5, 600), np.ones(4) / 4, mode="same")
    path = export_onnx(w, tmp_path / "step.onnx")
    onnx_run = simulate_onnx(path, u_new, w.state_order)
    numpy_run = simulate_numpy(w, u_new)
    t = lambda a: torch.as_tensor(a, dtype=torch.float32)  # noqa: E731
    x = torch.zeros(1, w.state_order)
    torch_run = []
    for uk in u_new / w.u_scale:
        torch_run.append(float((x @ t(w.c))[0]) * w.y_scale)
        h = torch.tanh(x @ t(w.w1[:, :-1]).T + float(uk) * t(w.w1[:, -1]) + t(w.b1)) - torch.tanh(t(w.b1))
        x = x @ t(w.a).T + float(uk) * t(w.b) + h @ t(w.w2).T
    span = float(np.ptp(numpy_run))
    assert np.max(np.abs(onnx_run - np.array(torch_run))) < 1e-4 * span
    assert np.max(np.abs(numpy_run - np.array(torch_run))) < 1e-4 * span


def test_a_record_too_short_is_refused_with_the_fix(record):
    u, y = record
    with pytest.raises(DataError, match="record longer"):
        train(u[:600], y[:600], settings=StateSpaceSettings(**{**TINY.__dict__, "window": 500}))


def test_a_saved_model_reloads_to_the_same_free_run(record, tmp_path):
    import json

    from host.train.state_space import StateSpaceWeights, save_state_space

    u, y = record
    model = train(u, y, epochs=2)
    folder = save_state_space(model, tmp_path / "ss", {"seed": 0})
    saved = json.loads((folder / "model.json").read_text())["weights"]
    weights = StateSpaceWeights(**{k: (np.array(v) if isinstance(v, list) else v) for k, v in saved.items()})
    assert np.array_equal(simulate_numpy(weights, u[:400]), model.simulate(u[:400]))
    onnx_run = simulate_onnx(folder / "step.onnx", u[:400], weights.state_order)
    assert np.max(np.abs(onnx_run - model.simulate(u[:400]))) < 1e-4 * float(np.ptp(model.simulate(u[:400])))
