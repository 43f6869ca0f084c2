"""The scoring rule: the start state and offset come from data after the input moves; never scored."""

from __future__ import annotations

import numpy as np

from host.evaluate import calibration_window, predict_with_candidates


def test_an_idle_lead_in_is_neither_calibrated_on_nor_scored():
    t = np.arange(3000) * 0.001
    u = np.where(t < 1.0, 0.0, np.sin(2 * np.pi * 3 * (t - 1.0)))
    y = 2.0 * u + 0.5
    y[t < 1.0] = -3.0  # a resting sensor that reads something else entirely
    start, end = calibration_window(u, 0.1)
    assert start == int(np.argmax(np.abs(u) > 0.02)) and end == start + int(0.1 * (u.size - start))
    prediction = predict_with_candidates(lambda s, branch: 2.0 * s, u, y)
    assert prediction.window_start == start and prediction.offset == np.float64(0.5)
    assert prediction.score.rmse < 1e-12 and prediction.score.samples == u.size - end
