"""Scoring a model on a recording that starts from an unknown hysteresis state.

A real rig's recording rarely starts in a known memory state, and sensors drift, so a model
identified elsewhere is off by a constant until both are estimated. The rule used everywhere
in pmactl (``fit``, ``demo``, README tables):

1. The *calibration window* is the start of the record: any idle lead-in plus the first
   ``calibration_fraction`` (default 10 %) of the samples after the input starts to move
   (moves by more than 1 % of its range).
2. For each candidate initial state at ``u[0]`` (arrived from below, from above, demagnetised)
   the model is simulated over the whole record and the output offset is the mean residual in
   the window. The candidate with the smallest window RMSE is kept.
3. Errors are reported on the samples *after* the window only: no sample that informed the
   state or offset is scored.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError
from edge.hysteresis.base import BRANCHES, HysteresisModel


@dataclass
class Score:
    """Errors in output units; ``rmse_pct_pp`` is RMSE / peak-to-peak of the measured output x 100."""

    rmse: float
    rmse_pct_pp: float
    max_error: float
    samples: int

    def as_dict(self) -> dict[str, float | int]:
        return {
            "rmse": self.rmse,
            "rmse_pct_pp": self.rmse_pct_pp,
            "max_error": self.max_error,
            "samples": self.samples,
        }


def score(measured: NDArray[np.float64], predicted: NDArray[np.float64]) -> Score:
    """RMSE, RMSE as % of peak-to-peak of ``measured``, and max absolute error."""
    error = predicted - measured
    rmse = float(np.sqrt(np.mean(error**2)))
    span = float(np.ptp(measured))
    return Score(rmse, 100.0 * rmse / span if span > 0 else float("nan"), float(np.abs(error).max()), int(error.size))


@dataclass
class Prediction:
    """A model's output on a record, with how its start was estimated."""

    y: NDArray[np.float64]
    branch: str
    offset: float
    window_end: int
    score: Score


def calibration_end(u: NDArray[np.float64], fraction: float) -> int:
    """End index (exclusive) of the calibration window; see module docstring."""
    span = float(np.ptp(u))
    moving = np.flatnonzero(np.abs(u - u[0]) > 0.01 * span)
    first_move = int(moving[0]) if moving.size else 0
    return first_move + max(1, int(fraction * (u.size - first_move)))


def predict_unknown_start(
    model: HysteresisModel,
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    calibration_fraction: float = 0.1,
) -> Prediction:
    """Simulate ``model`` on ``u`` with the initial state and offset estimated from the window."""
    window = calibration_end(u, calibration_fraction)
    if window >= u.size - 10:
        raise DataError(
            f"record too short to score: the calibration window takes {window} of {u.size} samples; "
            "record more samples after the input starts moving"
        )
    best: Prediction | None = None
    for branch in BRANCHES:
        model.reset(float(u[0]), branch)  # type: ignore[arg-type]
        shape = model.simulate(u)
        offset = float(np.mean(y[:window] - shape[:window]))
        window_rmse = float(np.sqrt(np.mean((shape[:window] + offset - y[:window]) ** 2)))
        if best is None or window_rmse < best.score.rmse:
            best = Prediction(shape + offset, branch, offset, window, Score(window_rmse, 0.0, 0.0, window))
    assert best is not None
    best.score = score(y[best.window_end :], best.y[best.window_end :])
    return best
