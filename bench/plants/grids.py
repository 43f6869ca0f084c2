"""The time grid every protocol samples on, written once."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def time_grid(duration_s: float, dt_s: float) -> NDArray[np.float64]:
    """Sample times [s] of a record of ``duration_s`` at a step of ``dt_s``, from 0."""
    return np.arange(int(round(duration_s / dt_s)), dtype=np.float64) * dt_s


def knotted(duration_s: float, dt_s: float, knots_t: list[float], knots_u: list[float]) -> NDArray[np.float64]:
    """The piecewise-linear signal through the knots ``(knots_t [s], knots_u)`` on :func:`time_grid`."""
    return np.asarray(np.interp(time_grid(duration_s, dt_s), knots_t, knots_u), dtype=np.float64)
