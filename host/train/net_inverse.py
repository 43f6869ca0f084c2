"""The inverse LSTM-NARMAX the edge runs as feedforward, trained by direct inverse learning.

Method (direct inverse learning, as the correction of :mod:`host.train.correction`): an
open-loop recording (pressure command ``u`` [bar], contraction ``y`` [mm]) is read backwards.
Had the smoothed ``y`` been the reference, ``u`` is a command that produced it. The net has the
forward LSTM-NARMAX's structure (:mod:`host.train.lstm_narmax`) with the roles swapped:

    regressors  [r(k), r(k-1), n(k), n(k-1), u(k-1)]      output  u(k) = n(k) + head(h(k))

with ``r`` the desired contraction, ``n`` the bundle's own rate-independent inverse table run
over ``r`` from the vented rest state the edge arms in, and ``u(k-1)`` the net's previous
command (teacher-forced first, then its own, as on the edge). So the net starts from the table
feedforward (head at zero) and learns what the table cannot know: the valve lag and the
friction that grows with speed, both functions of the reference's recent course.

Preview: the contraction answers a command late, so the command that makes the muscle follow a
reference must anticipate it. :func:`identify_preview` finds, in the recording, the shift ``d``
at which the table inverse of the later contraction best matches the command; the net is trained
on target ``r(k + d)`` for command ``u(k)``, and the edge gives it the reference ``d`` net steps
ahead (``preview_s`` in the manifest; the reference is a known function of time on the edge).

Validation: the record's last ``tail_fraction`` (20 %) is held out from the weights' training;
early stopping keeps the weights whose free run reproduces the held-out commands best, and the
result reports that held-out RMSE [bar] beside the table's alone. Recordings never trained on
(``train --test``) are scored the same way by :func:`score_inverse`: the net, run free from its
start over the record's contraction, against the command that produced it. The closed-loop number
(tracking RMS with the net feedforward against the table's on the HIL) is in
``bench/net_feedforward_bench.py``. Limit: the recording must cover the references' range and
rates (``pmactl edge record --protocol sines --range`` over the working range).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from edge.errors import DataError
from edge.hysteresis.lut import CompiledModel
from host.data import Measurement
from host.train.common import Curve, split_record
from host.train.lstm_narmax import NarmaxWeights, fit_narmax_net, fused

SMOOTHING_S = 0.05  # Savitzky-Golay window on the measured contraction [s]: sensor noise off, lag kept
MAX_PREVIEW_S = 0.5  # the longest preview tried [s]: far beyond a valve's and a muscle's lag


@dataclass
class InverseNet:
    """A trained inverse net and how well it reproduces the held-out commands.

    Attributes:
        weights: the LSTM-NARMAX weights (``u`` = desired contraction, ``n`` = table inverse).
        curve: the training curve.
        tail_rmse_bar: held-out free-run RMSE of the net's command [bar].
        tail_rmse_table_bar: the same for the table inverse alone [bar].
        target_range, table_range: ranges of the net's inputs ``r`` [mm] and ``n`` [bar] in training.
        preview_steps: how many net steps ahead of the command its target is taken (see
            :func:`identify_preview`); the edge feeds it the reference that far ahead.
    """

    weights: NarmaxWeights
    curve: Curve
    tail_rmse_bar: float
    tail_rmse_table_bar: float
    target_range: tuple[float, float]
    table_range: tuple[float, float]
    preview_steps: int = 0


def inverse_data(
    record: Measurement, table_inverse: CompiledModel
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(desired contraction [mm], table inverse [bar], command [bar]) of one open-loop recording."""
    window = max(5, int(round(SMOOTHING_S / record.dt)) | 1)
    if len(record) < 4 * window:
        raise DataError(f"{record.source}: only {len(record)} samples; too short to train an inverse net on")
    target = savgol_filter(record.y, window, 3)
    table_inverse.reset()
    table = table_inverse.simulate(target)
    table_inverse.reset()
    return target, table, np.asarray(record.u, np.float64)


def identify_preview(table: NDArray[np.float64], command: NDArray[np.float64], n_train: int, dt: float) -> int:
    """Samples ``d`` by which the contraction lags the command: the shift that makes the table
    inverse of the contraction ``d`` samples later closest (RMS) to the command, on the training part.

    A muscle behind a valve answers a command late (valve lag, line volume, rate friction); a
    feedforward that is to make the contraction follow a known reference must command what the
    reference asks ``d`` samples ahead. Identified from the recording, not set by hand.
    """
    best, best_rmse = 0, np.inf
    for d in range(int(MAX_PREVIEW_S / dt) + 1):
        rmse = float(np.sqrt(np.mean((table[d:n_train] - command[: n_train - d]) ** 2)))
        if rmse < best_rmse:
            best, best_rmse = d, rmse
    return best


def train_inverse_net(
    record: Measurement,
    table_inverse: CompiledModel,
    *,
    seed: int = 0,
    epochs: int = 150,
    quiet: bool = True,
    tail_fraction: float = 0.2,
) -> InverseNet:
    """Train the inverse on ``record`` (see module docstring); torch seeded by the caller."""
    target, table, command = inverse_data(record, table_inverse)
    split = split_record(len(record), 0, tail_fraction, record.source)
    preview = identify_preview(table, command, split.tail, record.dt)
    if preview:  # the command at k is learned from the target at k + preview (the edge previews the reference)
        target, table, command = target[preview:], table[preview:], command[:-preview]
        split = split_record(len(command), 0, tail_fraction, record.source)
    weights, curve = fit_narmax_net(
        target, command, table, split.tail, seed=seed, epochs=epochs, quiet=quiet, label="inverse net"
    )
    predicted = fused(weights).simulate(target, table)
    tail = slice(split.tail, None)
    rmse = float(np.sqrt(np.mean((predicted[tail] - command[tail]) ** 2)))
    rmse_table = float(np.sqrt(np.mean((table[tail] - command[tail]) ** 2)))
    return InverseNet(
        weights,
        curve,
        rmse,
        rmse_table,
        (float(target.min()), float(target.max())),
        (float(table.min()), float(table.max())),
        preview,
    )


@dataclass
class InverseScore:
    """The inverse on one held-out recording: command RMSE [bar] of the net and of the table alone."""

    name: str
    samples: int
    rmse_bar: float
    table_rmse_bar: float

    def as_dict(self) -> dict[str, object]:
        return {
            "file": self.name,
            "samples": self.samples,
            "rmse_bar": self.rmse_bar,
            "table_rmse_bar": self.table_rmse_bar,
        }


def score_inverse(
    inverse: InverseNet, record: Measurement, table_inverse: CompiledModel, skip_fraction: float = 0.1
) -> InverseScore:
    """Replay ``record``'s (smoothed) contraction through the inverse from its start, as the edge
    does (the target ``preview_steps`` ahead of the command), and score the commands it gives
    against the recorded ones after the first ``skip_fraction`` (the net's state settling)."""
    target, table, command = inverse_data(record, table_inverse)
    d = inverse.preview_steps
    if d:
        target, table, command = target[d:], table[d:], command[:-d]
    predicted = fused(inverse.weights).simulate(target, table)
    scored = slice(int(skip_fraction * command.size), None)
    rms = lambda e: float(np.sqrt(np.mean(e[scored] ** 2)))  # noqa: E731
    name = str(record.source).rsplit("/", 1)[-1]
    return InverseScore(name, command[scored].size, rms(predicted - command), rms(table - command))
