"""Play (backlash) operators and the classical Prandtl-Ishlinskii (PI) model.

Model (Ai2019 eqs 2-5, with the linear term written as a play of threshold 0)::

    z_i(k) = max(x(k) - r_i, min(x(k) + r_i, z_i(k-1)))      x = u - input_shift
    y(k)   = sum_i w_i z_i(k) + output_offset

with ``0 = r_0 < r_1 < ... < r_{n-1}``. The initial loading curve is
``phi(r) = sum_i w_i (r - r_i)^+``; the model is invertible when every partial sum
``S_i = w_0 + ... + w_i`` is positive. The inverse is again a PI model (derived from
``phi^-1``, Ai2019 eq 14 with the indices checked by composition in the tests)::

    r'_i = phi(r_i) = sum_{j<i} w_j (r_i - r_j)
    w'_0 = 1 / w_0,     w'_i = 1/S_i - 1/S_{i-1} = -w_i / (S_i S_{i-1})

and its input shift and output offset are the forward model's output offset and input shift.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from edge.errors import ModelError
from edge.hysteresis.base import Branch, HysteresisModel, as_signal, check_branch, check_range, clip_signal
from edge.hysteresis.table import LookupTable


def exponential_pi_parameters(
    n: int, beta: float, delta: float, mu: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Ai2019 eq 5: thresholds ``r_i = beta*i`` and weights ``delta*exp(-mu*r_i)``, i=0..n-1."""
    if n < 1 or beta <= 0 or delta <= 0:
        raise ModelError(f"exponential PI needs n>=1, beta>0, delta>0; got {n}, {beta}, {delta}")
    thresholds = beta * np.arange(n, dtype=float)
    return thresholds, delta * np.exp(-mu * thresholds)


def inverse_pi_parameters(thresholds: ArrayLike, weights: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Thresholds and weights of the inverse PI model (see module docstring)."""
    r = np.asarray(thresholds, dtype=float)
    w = np.asarray(weights, dtype=float)
    partial = np.cumsum(w)
    if np.any(partial <= 0):
        bad = int(np.argmax(partial <= 0))
        raise ModelError(
            f"PI model is not invertible: partial weight sum S_{bad}={partial[bad]:.3g} <= 0; "
            "constrain the fit to positive partial sums"
        )
    # r'_i = sum_{j<=i} w_j (r_i - r_j) = S_i r_i - sum_{j<=i} w_j r_j
    r_inv = partial * r - np.cumsum(w * r)
    w_inv = np.empty_like(w)
    w_inv[0] = 1.0 / w[0]
    w_inv[1:] = 1.0 / partial[1:] - 1.0 / partial[:-1]
    return r_inv, w_inv


def play_outputs(
    x: NDArray[np.float64], thresholds: NDArray[np.float64], z0: NDArray[np.float64], chunk: int = 65_536
) -> NDArray[np.float64]:
    """Play-operator outputs for every sample (rows) and threshold (columns).

    Loops over time with numpy work across operators (two calls per sample: the bounds
    ``x -+ r`` are precomputed a chunk at a time); ``z0`` is the state before ``x[0]``.
    """
    out = np.empty((x.size, thresholds.size))
    previous = z0.astype(float).copy()
    for start in range(0, x.size, chunk):
        block = x[start : start + chunk, None]
        lower, upper = block - thresholds, block + thresholds
        rows = out[start : start + chunk]
        for k in range(rows.shape[0]):
            row = rows[k]
            np.maximum(previous, lower[k], out=row)
            np.minimum(row, upper[k], out=row)
            previous = row
    return out


def branch_play_state(x0: float, thresholds: NDArray[np.float64], branch: Branch) -> NDArray[np.float64]:
    """Play outputs at input ``x0`` after arriving from far below / far above / with no memory.

    "Far" means more than twice the largest threshold away: the saturated states used by
    identification at the ends of a recording's range.
    """
    check_branch(branch)
    if branch == "ascending":
        return x0 - thresholds
    if branch == "descending":
        return x0 + thresholds
    return np.full_like(thresholds, x0)


class PlayKernel:
    """Plain-Python play bank + weights: the per-tick form used by the lookup table."""

    stage = "plays"

    def __init__(self, arrays: dict[str, NDArray[np.float64]]) -> None:
        self._pairs = list(zip(arrays["thresholds"].tolist(), arrays["weights"].tolist()))
        self._z = arrays["state"].tolist()
        self._shift = float(arrays["input_shift"])
        self._offset = float(arrays["output_offset"])

    def step(self, x: float) -> float:
        x -= self._shift
        z = self._z
        acc = self._offset
        i = 0
        for r, w in self._pairs:
            zi = z[i]
            lo = x - r
            if zi < lo:
                zi = z[i] = lo
            else:
                hi = x + r
                if zi > hi:
                    zi = z[i] = hi
            acc += w * zi
            i += 1
        return acc


class PIModel(HysteresisModel):
    """Classical PI model (see module docstring for the equations).

    Args:
        thresholds: play thresholds ``r_i`` in input units; ``r_0`` must be 0, strictly increasing.
        weights: play weights ``w_i`` (output units per input unit).
        output_offset: constant added to the output (output units).
        input_shift: constant subtracted from the input before the plays (input units).
        input_range: inputs are clamped to this interval (default: unbounded).
        actuator_range: the physical input range; ``inverse()`` clamps desired outputs to the
            outputs reachable inside it (default: ``input_range``).
    """

    kind = "pi"

    def __init__(
        self,
        thresholds: ArrayLike,
        weights: ArrayLike,
        *,
        output_offset: float = 0.0,
        input_shift: float = 0.0,
        input_range: tuple[float, float] = (-math.inf, math.inf),
        actuator_range: tuple[float, float] | None = None,
    ) -> None:
        self.thresholds = as_signal(thresholds, "thresholds")
        self.weights = as_signal(weights, "weights")
        if self.thresholds.size != self.weights.size or self.thresholds.size == 0:
            raise ModelError(
                f"PI needs as many weights as thresholds (>0); got {self.weights.size} weights "
                f"for {self.thresholds.size} thresholds"
            )
        if self.thresholds[0] != 0.0 or np.any(np.diff(self.thresholds) <= 0):
            raise ModelError("PI thresholds must start at 0 and increase strictly")
        self.output_offset = float(output_offset)
        self.input_shift = float(input_shift)
        self._input_range = check_range(*input_range, "PI input_range")
        self.actuator_range = check_range(*(actuator_range or input_range), "actuator_range")
        self._z = np.zeros_like(self.thresholds)
        self._lo = np.empty_like(self._z)
        self._hi = np.empty_like(self._z)
        self._z[:] = 0.0  # eq 4 with y0 = 0 (memory-free at 0)

    @property
    def input_range(self) -> tuple[float, float]:
        return self._input_range

    @property
    def memory_range(self) -> tuple[float, float]:
        """``actuator_range``, or, if unbounded, far enough that every play saturates."""
        lo, hi = self.actuator_range
        if math.isfinite(lo) and math.isfinite(hi):
            return lo, hi
        reach = 2.0 * float(self.thresholds[-1]) + 1.0
        return -reach + self.input_shift, reach + self.input_shift

    def _saturate(self, positive: bool) -> None:
        lo, hi = self.memory_range
        self._z[:] = branch_play_state(
            (hi if positive else lo) - self.input_shift, self.thresholds, "ascending" if positive else "descending"
        )

    def get_state(self) -> dict[str, NDArray[np.float64]]:
        return {"plays": self._z.copy()}

    def set_state(self, state: dict[str, NDArray[np.float64]]) -> None:
        plays = np.asarray(state["plays"], dtype=float)
        if plays.shape != self._z.shape:
            raise ModelError(f"PI state has {plays.size} plays; this model has {self._z.size}")
        self._z[:] = plays

    def step(self, u: float) -> float:
        x = self._clamp(float(u)) - self.input_shift
        z = self._z
        np.subtract(x, self.thresholds, out=self._lo)
        np.add(x, self.thresholds, out=self._hi)
        np.maximum(z, self._lo, out=z)
        np.minimum(z, self._hi, out=z)
        return float(self.weights @ z) + self.output_offset

    def simulate(self, u: ArrayLike) -> NDArray[np.float64]:
        signal = as_signal(u)
        clipped, self.saturated = clip_signal(signal, *self.input_range)
        plays = play_outputs(clipped - self.input_shift, self.thresholds, self._z)
        if plays.shape[0]:
            self._z[:] = plays[-1]
        return plays @ self.weights + self.output_offset

    def saturation_outputs(self) -> tuple[float, float]:
        """Outputs at the ends of ``actuator_range`` (state independent, output units).

        At the lower end every play sits at ``x + r_i``, at the upper end at ``x - r_i``; a
        finite end is required.
        """
        lo, hi = self.actuator_range
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise ModelError("PI inverse needs a finite actuator_range to know what is reachable")
        y_lo = float(self.weights @ (lo - self.input_shift + self.thresholds))
        y_hi = float(self.weights @ (hi - self.input_shift - self.thresholds))
        return y_lo + self.output_offset, y_hi + self.output_offset

    def inverse(self) -> PIModel:
        """Inverse PI; its ``input_range`` is the reachable output range (clamped + flagged)."""
        r_inv, w_inv = inverse_pi_parameters(self.thresholds, self.weights)
        reachable = self.saturation_outputs()
        return PIModel(
            r_inv,
            w_inv,
            output_offset=self.input_shift,
            input_shift=self.output_offset,
            input_range=reachable,
        )

    def compile(self) -> LookupTable:
        return LookupTable.chain(self.kind, [self.kernel_stage()], self.input_range)

    def kernel_stage(self) -> tuple[str, dict[str, NDArray[np.float64]]]:
        """This model as a ``plays`` stage for a lookup table."""
        return PlayKernel.stage, {
            "thresholds": self.thresholds,
            "weights": self.weights,
            "state": self._z.copy(),
            "input_shift": np.array(self.input_shift),
            "output_offset": np.array(self.output_offset),
        }
