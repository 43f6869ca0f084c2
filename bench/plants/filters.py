"""Signal blocks the plant families share: a first-order lag, a second-order resonance and a
variable transport delay (each family's cores and effects had its own copy of them)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.signal import cont2discrete, lfilter

Array = NDArray[np.float64]


def lowpass(x: Array, dt_s: float, tau_s: float) -> Array:
    """First-order lag with time constant ``tau_s`` [s], starting at rest on ``x[0]``."""
    a = 1.0 - np.exp(-dt_s / tau_s)
    return np.asarray(lfilter([a], [1.0, a - 1.0], x, zi=[x[0] * (1 - a)])[0], dtype=np.float64)


def resonance(x: Array, dt_s: float, f_hz: float, zeta: float) -> Array:
    """``y'' + 2 zeta wn y' + wn^2 y = wn^2 x`` (``wn = 2 pi f_hz``, zero-order hold), starting at
    rest on ``x[0]``."""
    wn = 2.0 * math.pi * f_hz
    num, den, _ = cont2discrete(([wn * wn], [1.0, 2.0 * zeta * wn, wn * wn]), dt_s, method="zoh")
    b, a = np.asarray(num, dtype=np.float64).ravel(), np.asarray(den, dtype=np.float64)
    return np.asarray(lfilter(b, a, x - x[0]) + x[0], dtype=np.float64)


def variable_delay(x: Array, lag_samples: Array) -> Array:
    """``x`` read ``lag_samples`` back, never going back in time (the read index only advances)."""
    idx = np.arange(x.size, dtype=np.float64)
    src = np.maximum.accumulate(np.clip(idx - lag_samples, 0.0, x.size - 1.0))
    return np.asarray(np.interp(src, idx, x), dtype=np.float64)
