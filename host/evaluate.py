"""Scoring a model on a recording that starts from an unknown hysteresis state.

A real rig's recording rarely starts in a known memory state, and sensors drift, so a model
identified elsewhere is off by a constant until both are estimated. The rule used everywhere
in pmactl (``fit``, ``demo``, README tables):

1. The *calibration window* is the first ``calibration_fraction`` (default 10 %) of the
   samples after the input starts to move (moves by more than 1 % of its range). An idle
   lead-in before the move is excluded from the window: on the real piezo runs it is ~90 % of
   what the window used to hold, and an offset fitted on a resting output says little about
   the moving one (a PI model went from 2.62 % to ~1.8 % of p-p when this was fixed).
2. For each candidate initial state at ``u[0]`` (arrived from below, from above, demagnetised)
   the model is simulated over the whole record and the output offset is the mean residual in
   the window. The candidate with the smallest window RMSE is kept.
3. Errors are reported on the samples *after* the window only: no sample that informed the
   state or offset (nor the idle lead-in) is scored.

:func:`predict_unknown_start` takes a hysteresis model; :func:`predict_with_candidates` takes
any simulator ``simulate(u, branch) -> y`` (the trained neural models use it).
"""

from __future__ import annotations

from collections.abc import Callable
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
    window_start: int = 0


def first_move(u: NDArray[np.float64]) -> int:
    """Index of the first sample where ``u`` has moved by more than 1 % of its range from ``u[0]``."""
    span = float(np.ptp(u))
    moving = np.flatnonzero(np.abs(u - u[0]) > 0.01 * span)
    return int(moving[0]) if moving.size else 0


def calibration_window(u: NDArray[np.float64], fraction: float) -> tuple[int, int]:
    """``(start, end)`` (end exclusive) of the calibration window; see module docstring."""
    start = first_move(u)
    return start, start + max(1, int(fraction * (u.size - start)))


def calibration_end(u: NDArray[np.float64], fraction: float) -> int:
    """End index (exclusive) of the calibration window; see module docstring."""
    return calibration_window(u, fraction)[1]


Simulator = Callable[[NDArray[np.float64], str], NDArray[np.float64]]


def predict_with_candidates(
    simulate: Simulator,
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    calibration_fraction: float = 0.1,
    branches: tuple[str, ...] = BRANCHES,
) -> Prediction:
    """Simulate from each candidate start ``branch`` and keep the one the window fits best.

    ``simulate(u, branch)`` returns the model output for the whole record from a start in
    ``branch`` at ``u[0]``; the offset is fitted and the start chosen on the calibration window
    only, and the score is taken after it (see module docstring).
    """
    start, end = calibration_window(u, calibration_fraction)
    if end >= u.size - 10:
        raise DataError(
            f"record too short to score: the calibration window ends at sample {end} of {u.size}; "
            "record more samples after the input starts moving"
        )
    window = slice(start, end)
    best: Prediction | None = None
    for branch in branches:
        shape = simulate(u, branch)
        offset = float(np.mean(y[window] - shape[window]))
        window_rmse = float(np.sqrt(np.mean((shape[window] + offset - y[window]) ** 2)))
        if best is None or window_rmse < best.score.rmse:
            best = Prediction(shape + offset, branch, offset, end, Score(window_rmse, 0.0, 0.0, end - start), start)
    assert best is not None
    best.score = score(y[end:], best.y[end:])
    return best


def predict_unknown_start(
    model: HysteresisModel,
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    calibration_fraction: float = 0.1,
) -> Prediction:
    """Simulate ``model`` on ``u`` with the initial state and offset estimated from the window."""

    def simulate(signal: NDArray[np.float64], branch: str) -> NDArray[np.float64]:
        model.reset(float(signal[0]), branch)  # type: ignore[arg-type]
        return model.simulate(signal)

    return predict_with_candidates(simulate, u, y, calibration_fraction=calibration_fraction)
