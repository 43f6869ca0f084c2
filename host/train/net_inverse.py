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

Validation: the record's last ``tail_fraction`` (20 %) is held out from the weights' training;
early stopping keeps the weights whose free run reproduces the held-out commands best, and the
result reports that held-out RMSE [bar] beside the table's alone. The closed-loop number
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


@dataclass
class InverseNet:
    """A trained inverse net and how well it reproduces the held-out commands.

    Attributes:
        weights: the LSTM-NARMAX weights (``u`` = desired contraction, ``n`` = table inverse).
        curve: the training curve.
        tail_rmse_bar: held-out free-run RMSE of the net's command [bar].
        tail_rmse_table_bar: the same for the table inverse alone [bar].
        target_range, table_range: ranges of the net's inputs ``r`` [mm] and ``n`` [bar] in training.
    """

    weights: NarmaxWeights
    curve: Curve
    tail_rmse_bar: float
    tail_rmse_table_bar: float
    target_range: tuple[float, float]
    table_range: tuple[float, float]


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
    )
