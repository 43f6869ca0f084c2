"""The trainer's parts: lanes of free runs equal one run each, the smoothed early stopping."""

from __future__ import annotations

import numpy as np

from host.train.common import EarlyStopping
from host.train.lstm_narmax import NarmaxWeights, _regressors, fused


def weights(seed: int = 0) -> NarmaxWeights:
    rng = np.random.default_rng(seed)
    return NarmaxWeights(
        rng.normal(0, 0.5, (28, 5)).astype(np.float32),
        rng.normal(0, 0.5, (28, 7)).astype(np.float32),
        rng.normal(0, 0.5, 28).astype(np.float32),
        rng.normal(0, 0.5, 7).astype(np.float32),
        0.1,
        rng.normal(0, 1, 5).astype(np.float32),
        rng.uniform(0.5, 2, 5).astype(np.float32),
        0.3,
    )


def test_lanes_run_teacher_forced_then_free_as_one_step_at_a_time_would():
    w = weights()
    rng = np.random.default_rng(1)
    u = np.cumsum(rng.normal(0, 0.05, 600))
    n = np.tanh(u)
    y = n + 0.1 * np.sin(np.arange(600) / 20)
    x = _regressors(u, n, y)
    starts, length, free_from = np.array([0, 150, 300]), 250, np.array([40, 10, 100])
    index = starts[None, :] + np.arange(length)[:, None]
    lanes = fused(w).free_run_lanes(x[index], n[index], y[index], free_from)
    step = fused(w)
    for lane, (start, free) in enumerate(zip(starts, free_from)):
        step.reset(0.0, 0.0)
        step._lags = tuple(float(v) for v in x[start, [1, 3, 4]])  # the lane's first lags, teacher-forced
        expected = []
        for k in range(length):
            if k > 0 and k <= free:
                step._lags = (step._lags[0], step._lags[1], float(y[start + k - 1]))  # measured lag until free
            expected.append(step.step(float(u[start + k]), float(n[start + k])))
        assert np.max(np.abs(lanes[:, lane] - expected)) <= 1e-5 * np.ptp(expected)


def test_the_smoothed_score_decides_when_to_stop_and_the_best_raw_score_what_is_kept():
    stopper = EarlyStopping(patience=3, smoothing=0.5)
    decisions = [stopper.update(score, {"epoch": i}) for i, score in enumerate([1.0, 0.9, 0.9, 0.5, 1.3, 1.3, 1.3])]
    assert stopper.best_state == {"epoch": 3}  # the best epoch is still the one kept
    assert decisions.index(True) == 6  # smoothed: 1.0 .95 .925 .71 1.01 1.15 1.23


def test_without_smoothing_early_stopping_is_the_raw_score():
    stopper = EarlyStopping(patience=2)
    decisions = [stopper.update(score, {"epoch": i}) for i, score in enumerate([1.0, 0.8, 0.9, 0.85])]
    assert decisions == [False, False, False, True] and stopper.best_state == {"epoch": 1}
