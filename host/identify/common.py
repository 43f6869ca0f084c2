"""Shared pieces of the estimators: where the memory is known, bounded least squares."""

from __future__ import annotations

import abc
import time
from dataclasses import dataclass
from typing import Self

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import lsq_linear

from edge.errors import DataError, ModelError
from edge.hysteresis.base import Branch, HysteresisModel, as_signal
from host.identify.threads import blas_threads


@dataclass(frozen=True)
class MemoryStart:
    """First training sample at which the hysteresis memory is known.

    A hysteresis memory is erased by the extremes of the input: once the input reaches the end
    of the range it sweeps (assuming it never left that range before the recording started), the
    state is negative saturation (at the minimum, arrived from above: ``descending``) or
    positive saturation (at the maximum: ``ascending``). Identification starts there, so the
    unknown state at the start of a recording never biases the fit.
    """

    index: int
    branch: Branch


def memory_start(u: NDArray[np.float64], tolerance: float = 0.005) -> MemoryStart:
    """The first sample within ``tolerance`` x range of the input minimum or maximum."""
    lo, hi = float(u.min()), float(u.max())
    band = tolerance * (hi - lo)
    at_min = int(np.argmax(u <= lo + band))
    at_max = int(np.argmax(u >= hi - band))
    if at_min <= at_max:
        return MemoryStart(at_min, "descending")
    return MemoryStart(at_max, "ascending")


def training_signals(
    u: ArrayLike, y: ArrayLike, min_samples: int = 20
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Validate a training pair: finite 1-D arrays of equal length with a moving input."""
    u_arr, y_arr = as_signal(u, "u"), as_signal(y, "y")
    if u_arr.size != y_arr.size:
        raise DataError(f"u has {u_arr.size} samples but y has {y_arr.size}; give equal lengths")
    if u_arr.size < min_samples:
        raise DataError(f"only {u_arr.size} training samples; need at least {min_samples}")
    if np.ptp(u_arr) <= 1e-12 * max(1.0, float(np.abs(u_arr).max())):
        raise DataError("the input u is constant; hysteresis needs a moving input to identify")
    if np.ptp(y_arr) <= 1e-12 * max(1.0, float(np.abs(y_arr).max())):
        raise DataError(
            f"the output y is constant ({float(y_arr[0]):g} throughout) while u moves: nothing to identify; "
            "check that y is the sensor's column and that the sensor was connected"
        )
    return u_arr, y_arr


COMPRESS_FACTOR = 4  # rows per column beyond which bounded_lsq solves the triangular factor
COMPRESS_BLOCK = 65_536  # rows factored at a time: a few MB whatever the record length


def compress_rows(
    design: NDArray[np.float64], target: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(R, r)`` with ``|R x - r|^2 = |design x - target|^2 - const`` for every ``x``.

    QR of ``[design, target]`` accumulated block by block (the previous factor stacked on the
    next rows), so no copy of the whole design is made: at 1e6 samples the bounded solver's own
    copies of the design took ``pmactl fit --model mpi`` to 1.27 GB.
    """
    width = design.shape[1]
    factor = np.zeros((0, width + 1))
    for first in range(0, design.shape[0], COMPRESS_BLOCK):
        block = np.column_stack([design[first : first + COMPRESS_BLOCK], target[first : first + COMPRESS_BLOCK]])
        factor = np.asarray(np.linalg.qr(np.vstack([factor, block]), mode="r"), dtype=np.float64)
    return factor[:width, :width], factor[:width, width]


def bounded_lsq(
    design: NDArray[np.float64],
    target: NDArray[np.float64],
    lower: NDArray[np.float64],
    upper: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """``argmin |design @ x - target|`` subject to ``lower <= x <= upper`` (columns scaled).

    A tall problem is first reduced to its triangular factor (:func:`compress_rows`), which has
    the same minimiser: the bounded solver then never copies a million-row design.
    """
    if design.shape[0] > COMPRESS_FACTOR * design.shape[1]:
        design, target = compress_rows(design, target)
    scale = np.linalg.norm(design, axis=0)
    scale[scale == 0] = 1.0
    upper = np.full(design.shape[1], np.inf) if upper is None else upper
    result = lsq_linear(design / scale, target, bounds=(lower * scale, upper * scale), method="bvls")
    return np.asarray(result.x / scale, dtype=np.float64)


MIN_SLOPE_DOC = (
    "min_slope_ratio: smallest local slope of any branch, as a fraction of the average slope "
    "ptp(y)/ptp(u). Keeps the inverse well conditioned: its gain is at most 1/ratio times the "
    "average, and a flat branch (which the inverse cannot resolve in floating point) is excluded."
)


def average_slope(u: NDArray[np.float64], y: NDArray[np.float64]) -> float:
    """``ptp(y) / ptp(u)``: the scale the slope floors refer to (output units per input unit)."""
    return float(np.ptp(y) / np.ptp(u))


def check_slope_ratio(ratio: float) -> float:
    """Validate ``min_slope_ratio`` (0 < ratio < 1)."""
    if not 0.0 < ratio < 1.0:
        raise ModelError(f"min_slope_ratio must be between 0 and 1; got {ratio}")
    return float(ratio)


class HysteresisEstimator(abc.ABC):
    """Template for the estimators: ``fit`` validates, times, finds where the memory is known,
    calls :meth:`_identify` and records the learned attributes.

    Learned attributes: ``model_`` (the forward model, left in the state it ends the training
    data in), ``train_prediction_`` (its output from ``start_index_`` on), ``start_index_`` and
    ``start_branch_`` (see :class:`MemoryStart`), ``fit_seconds_`` (wall) and
    ``fit_cpu_seconds_`` (this process's CPU time), ``blas_threads_`` (the BLAS threads the fit
    ran with, sized to the problem by :mod:`host.identify.threads`; 0: left at BLAS's default).
    """

    def fit(self, u: ArrayLike, y: ArrayLike) -> Self:
        u_arr, y_arr = training_signals(u, y)
        with Stopwatch() as watch, blas_threads(u_arr.size * self._parameter_count() ** 2) as threads:
            start = memory_start(u_arr)
            model = self._identify(u_arr, y_arr, start)
            model.reset(float(u_arr[start.index]), start.branch)
            self.train_prediction_ = model.simulate(u_arr[start.index :])
        self.model_ = model
        self.start_index_, self.start_branch_ = start.index, start.branch
        self.fit_seconds_, self.fit_cpu_seconds_ = watch.seconds, watch.cpu_seconds
        self.blas_threads_ = threads
        return self

    @abc.abstractmethod
    def _parameter_count(self) -> int:
        """Unknowns of the largest least-squares problem (sizes the BLAS threads)."""

    @abc.abstractmethod
    def _identify(self, u: NDArray[np.float64], y: NDArray[np.float64], start: MemoryStart) -> HysteresisModel:
        """The identified forward model; the fit uses samples from ``start.index`` on."""


class Stopwatch:
    """Wall and process CPU time of a block: ``with Stopwatch() as sw: ...; sw.seconds, sw.cpu_seconds``.

    CPU time counts every thread of this process, so CPU > wall means BLAS threads ran in
    parallel, and CPU << wall on a busy machine means the fit waited for a core.
    """

    def __enter__(self) -> Stopwatch:
        self._start = time.perf_counter()
        self._cpu_start = time.process_time()
        self.seconds = self.cpu_seconds = 0.0
        return self

    def __exit__(self, *exc: object) -> None:
        self.seconds = time.perf_counter() - self._start
        self.cpu_seconds = time.process_time() - self._cpu_start
