"""The identified hysteresis operators the neural models are built on.

* Hammerstein (Ai2019): the MPI model (play operators + dead-zone shaper), identified by
  :class:`host.identify.MPIEstimator` exactly as ``pmactl fit --model mpi`` does.
* LSTM-NARMAX (Wu2025): a PI operator on the *tanh-warped* input
  ``s = tanh((u - centre) / half_range)``: the warp compresses the ends of the input range, so
  the plays' loops narrow where the actuator saturates. Its weights are identified by the same
  constrained least squares as ``pmactl fit --model pi``, on ``(s, y)``.

Both give ``simulate(u, branch)``: the operator output [output units] from a start in ``branch``
at ``u[0]`` (the candidates :mod:`host.evaluate` tries on a record whose start is unknown).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from edge.hysteresis.base import HysteresisModel
from host.identify import MPIEstimator, PIEstimator


@dataclass
class Operator:
    """An identified hysteresis operator, optionally on a tanh-warped input."""

    model: HysteresisModel
    kind: str
    centre: float = 0.0
    half_range: float = 0.0  # 0: no warp

    def warp(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        """The operator's input for ``u`` (identity without a warp)."""
        if self.half_range <= 0:
            return u
        return np.tanh((u - self.centre) / self.half_range)

    def simulate(self, u: NDArray[np.float64], branch: str) -> NDArray[np.float64]:
        """Output for ``u`` starting in ``branch`` at ``u[0]``."""
        x = self.warp(np.asarray(u, dtype=float))
        self.model.reset(float(x[0]), branch)  # type: ignore[arg-type]
        return self.model.simulate(x)

    def describe(self) -> dict[str, object]:
        return {"kind": self.kind, "warp_centre": self.centre, "warp_half_range": self.half_range}


@dataclass
class IdentifiedOperator:
    """An operator with the training record's known memory start (index, branch)."""

    operator: Operator
    start_index: int
    start_branch: str
    fit_seconds: float


def identify_mpi(u: NDArray[np.float64], y: NDArray[np.float64]) -> IdentifiedOperator:
    """Ai2019's MPI, as ``pmactl fit --model mpi``."""
    estimator = MPIEstimator().fit(u, y)
    operator = Operator(estimator.model_, "mpi")
    return IdentifiedOperator(operator, estimator.start_index_, estimator.start_branch_, estimator.fit_seconds_)


WARP_GAINS = (0.5, 1.0, 1.5, 2.0)
WARP_SHIFTS = (-0.75, -0.5, -0.25, 0.0, 0.25, 0.5)


def identify_tanh_pi(u: NDArray[np.float64], y: NDArray[np.float64], n_operators: int = 10) -> IdentifiedOperator:
    """Wu2025's tanh-input PI operator (see module docstring).

    The warp ``tanh(gain * (u - centre) / half_range)`` has its gain and centre chosen on a small
    grid by the training fit (RMSE from the memory start): where the warp's knee sits decides
    how much of the actuator's saturation the Masing-type PI can follow (on the HIL muscle the
    held-out RMSE spans 2.1-8.8 mm over this grid).
    """
    mid = 0.5 * float(u.max() + u.min())
    half = 0.5 * float(np.ptp(u)) or 1.0
    best: tuple[float, IdentifiedOperator] | None = None
    for gain in WARP_GAINS:
        for shift in WARP_SHIFTS:
            centre, half_range = mid + shift * half, half / gain
            estimator = PIEstimator(n_operators=n_operators).fit(np.tanh((u - centre) / half_range), y)
            rmse = float(np.sqrt(np.mean((estimator.train_prediction_ - y[estimator.start_index_ :]) ** 2)))
            if best is None or rmse < best[0]:
                operator = Operator(estimator.model_, "tanh_pi", centre, half_range)
                best = (
                    rmse,
                    IdentifiedOperator(
                        operator, estimator.start_index_, estimator.start_branch_, estimator.fit_seconds_
                    ),
                )
    assert best is not None
    return best[1]
