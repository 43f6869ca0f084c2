"""The steps behind ``pmactl fit`` and ``pmactl demo``: fit, score, bundle."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import ModelError
from edge.hysteresis.base import HysteresisModel
from host.data import Measurement
from host.evaluate import Prediction, predict_unknown_start
from host.identify import ESTIMATORS, DPIEstimator, MPIEstimator, PIEstimator, PreisachEstimator
from host.operator_ranges import OPERATORS
from models_export.bundle import write_bundle

Estimator = PIEstimator | MPIEstimator | DPIEstimator | PreisachEstimator


class ConstantOutputWarning(UserWarning):
    """A held-out recording whose output y never moves."""


def make_estimator(
    model: str,
    *,
    operators: int | None = None,
    parameterisation: str = "free",
    preisach_method: str = "lsq",
) -> Estimator:
    """An unfitted estimator for ``model`` (``pi``, ``mpi``, ``dpi``, ``preisach``).

    ``operators`` is the number of play operators / digits, or grid intervals for Preisach
    (``None``: the model's default); outside the model's range (:data:`OPERATORS`) it is refused.
    """
    if model not in ESTIMATORS:
        raise ModelError(f"model {model!r} unknown; choose one of {', '.join(ESTIMATORS)}")
    default, lowest, highest = OPERATORS[model]
    if operators is None:
        operators = default
    elif not lowest <= operators <= highest:
        raise ModelError(
            f"--operators {operators} is outside {lowest}-{highest} for {model} (default {default}); "
            "choose a count in that range"
        )
    if model == "preisach":
        return PreisachEstimator(n_levels=operators, method=preisach_method)  # type: ignore[arg-type]
    if model == "pi":
        return PIEstimator(n_operators=operators, parameterisation=parameterisation)  # type: ignore[arg-type]
    if model == "mpi":
        return MPIEstimator(n_operators=operators, parameterisation=parameterisation)  # type: ignore[arg-type]
    if parameterisation != "free":
        raise ModelError(f"--parameterisation {parameterisation} applies to the pi and mpi models only")
    return DPIEstimator(n_operators=operators)


@dataclass
class TestResult:
    """A model's prediction on one held-out recording."""

    name: str
    prediction: Prediction


def score_on(
    model: HysteresisModel, recordings: list[Measurement], calibration_fraction: float = 0.1
) -> list[TestResult]:
    """Predict each recording from an estimated initial state (see :mod:`host.evaluate`).

    A recording whose output never moves is scored, with a warning: its error as a percentage
    of the peak-to-peak output is undefined, and a flat sensor is more often unplugged than right.
    """
    for m in recordings:
        if np.ptp(m.y) <= 1e-12 * max(1.0, float(np.abs(m.y).max())):
            warnings.warn(
                f"{m.source}: the output y is constant ({float(m.y[0]):g}), so % of peak-to-peak is undefined; "
                "check that y is the sensor's column and that the sensor was connected",
                ConstantOutputWarning,
                stacklevel=2,
            )
    return [
        TestResult(
            Path(m.source).name,
            predict_unknown_start(model, m.u, m.y, calibration_fraction=calibration_fraction),
        )
        for m in recordings
    ]


def rest_state(model: HysteresisModel, lowest_input: float) -> tuple[HysteresisModel, HysteresisModel]:
    """Forward model and its inverse, both at the vented rest state (lowest input, from above).

    This is the state the edge arms in (valve vented, pressure at its minimum), so the tables
    written to a bundle start consistent with each other and with the rig.
    """
    model.reset(lowest_input, "descending")
    inverse = model.inverse()
    inverse.reset(inverse.input_range[0], "descending")
    return model, inverse


def save_bundle(
    estimator: Estimator,
    train: Measurement,
    directory: str | Path,
    units: tuple[str, str],
    record: dict[str, object],
) -> Path:
    """Write the fitted model and its inverse as a bundle at ``directory``."""
    forward, inverse = rest_state(estimator.model_, float(train.u.min()))
    source = Path(train.source)
    training_data = [source] if source.is_file() else []
    return write_bundle(directory, forward, inverse, units=units, fit_record=record, training_data=training_data)


class ExtrapolationWarning(UserWarning):
    """A held-out recording whose input leaves the range the model was trained on."""


EXTRAPOLATION_MARGIN = 0.01  # share of the training input's span tolerated beyond its ends (sensor noise)


def warn_extrapolation(train_u: NDArray[np.float64], tests: list[Measurement], unit: str = "") -> list[str]:
    """Warn for each test whose input goes outside ``train_u``'s range; the messages said.

    A hysteresis model or a net identified on ``min..max`` of the training input has no data
    beyond it, so its score there measures extrapolation, not the fit.
    """
    low, high = float(train_u.min()), float(train_u.max())
    margin = EXTRAPOLATION_MARGIN * max(high - low, 1e-12)
    messages = []
    for m in tests:
        outside = (m.u < low - margin) | (m.u > high + margin)
        if not outside.any():
            continue
        suffix = f" {unit}" if unit else ""
        span = f"{float(m.u.min()):.4g}..{float(m.u.max()):.4g}{suffix}"
        message = (
            f"{m.source}: {outside.mean():.0%} of the test input ({span}) "
            f"lies outside the training range {low:.4g}..{high:.4g}{suffix}: the model extrapolates there; train on a "
            "record that covers the test's range"
        )
        warnings.warn(message, ExtrapolationWarning, stacklevel=2)
        messages.append(message)
    return messages
