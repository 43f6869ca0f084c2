"""Regressors of the diagnosis models, all computed once per record.

* Hysteresis: Preisach rows (``y_static = rows @ E + y_min``, see host.identify.preisach) on a
  coarse grid, from the first sample where the memory is known.
* Rate: smoothed central differences [units / s]; a velocity-squared lag element.
* Creep: the hysteresis output minus its slow first-order low-pass, for a time constant.
* Load / temperature: the column, centred, and its product with the hysteresis output.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from host.identify.common import MemoryStart
from host.identify.preisach import EverettGrid, regressor_chunks


def preisach_rows(u: NDArray[np.float64], start: MemoryStart, levels: int) -> NDArray[np.float32]:
    """Dense Preisach regressors (rows from ``start.index`` on), float32 to keep memory low."""
    grid = EverettGrid(float(u.min()), float(u.max()), levels)
    rows = np.zeros((u.size - start.index, grid.size), dtype=np.float32)
    offset = 0
    for block in regressor_chunks(u, grid, start, capacity=128):
        rows[offset : offset + len(block)] = block
        offset += len(block)
    return rows


def smoothed_rate(u: NDArray[np.float64], dt: float, window_s: float = 0.05) -> NDArray[np.float64]:
    """Rate of ``u`` [units/s]: central difference, then a moving average over ``window_s``."""
    rate = np.gradient(u, dt)
    width = max(1, int(round(window_s / dt)))
    kernel = np.ones(width) / width
    return np.convolve(rate, kernel, mode="same")


def first_order(u: NDArray[np.float64], dt: float, tau_s: float) -> NDArray[np.float64]:
    """``u`` through a unit-gain first-order lag of ``tau_s`` (0: unchanged), starting settled.

    Filters along the first axis, so a 2-D array is filtered column by column.
    """
    if tau_s <= 0:
        return u
    alpha = 1.0 - np.exp(-dt / tau_s)
    return lfilter([alpha], [1.0, alpha - 1.0], u, axis=0, zi=u[:1] * (1 - alpha))[0]


def actuator_input(u: NDArray[np.float64], dt: float, lag_s: float) -> NDArray[np.float64]:
    """What drives the hysteresis for a recorded input ``u``: ``u`` through a first-order
    actuator lag of ``lag_s`` >= 0 [s]; for ``lag_s`` < 0 the inverse of a first-order lag of
    ``-lag_s`` (the recorded input is the driving pressure read through a lag of its own: a
    snubber or an RC filter on the transducer, the exact inverse of :func:`first_order`'s
    discretisation; it amplifies the input's noise by up to ``2 / alpha``)."""
    if lag_s >= 0:
        return first_order(u, dt, lag_s)
    alpha = 1.0 - np.exp(dt / lag_s)
    previous = np.concatenate([u[:1], u[:-1]])
    return (u - (1.0 - alpha) * previous) / alpha


# a smoothed input rate below this share of its 95th percentile is a hold, not a move
HOLD_RATE_SHARE = 0.05


def direction_delayed(u: NDArray[np.float64], dt: float, rise_s: float, fall_s: float) -> NDArray[np.float64]:
    """``u`` through a dead time that depends on where it is going [s]: a value sent while the
    input rises arrives ``rise_s`` later, one sent while it falls ``fall_s`` later (a valve that
    opens late and exhausts early, or the reverse). Nothing overtakes what was sent before it:
    a value that would arrive earlier waits for its predecessor. A hold (a smoothed rate under
    :data:`HOLD_RATE_SHARE` of its 95th percentile, so noise does not flip its direction) takes
    the direction of the move that ends it, so that move starts after its own dead time; a hold
    at the end takes the last move's. The arrival times are kept strictly increasing by 1e-9
    samples a step, exact for records under ~4 million samples."""
    rising = _move_directions(smoothed_rate(u, dt)) > 0
    index = np.arange(u.size, dtype=np.float64)
    arrival = np.maximum.accumulate(index + np.where(rising, rise_s, fall_s) / dt)
    arrival += index * 1e-9  # strictly increasing for the interpolation
    return np.interp(index, arrival, u, left=u[0])


def _move_directions(rate: NDArray[np.float64]) -> NDArray[np.float64]:
    """+1 rising, -1 falling per sample; a hold gets the sign of the next move (the last move's
    at the end of the record; -1 when the input never moves)."""
    speed = np.abs(rate)
    moving = speed > HOLD_RATE_SHARE * float(np.percentile(speed, 95))
    if not moving.any():
        return -np.ones_like(rate)
    n = rate.size
    next_move = np.minimum.accumulate(np.where(moving, np.arange(n), n)[::-1])[::-1]
    last_move = np.maximum.accumulate(np.where(moving, np.arange(n), -1))
    source = np.where(next_move < n, next_move, last_move)
    return np.sign(rate[source])


def slow_part(x: NDArray[np.float64], dt: float, tau_s: float) -> NDArray[np.float64]:
    """``lowpass(x, tau) - x``: what a first-order creep element with time constant ``tau`` adds
    (column by column for a 2-D array)."""
    return first_order(x, dt, tau_s) - x


def branch_offset(u: NDArray[np.float64], start: MemoryStart, share: float = 0.1) -> NDArray[np.float64]:
    """Which branch the memory is on: a play operator's output minus the input, scaled to +-1.

    The play's threshold is ``share`` of the input range; -1 on a rising branch, +1 on a
    falling one, in between after a reversal.
    """
    from edge.hysteresis.pi import branch_play_state, play_outputs

    threshold = share * float(np.ptp(u))
    thresholds = np.array([threshold])
    z0 = branch_play_state(float(u[0]), thresholds, start.branch)
    # the play came from the end of the record's range, not from beyond it: an input that starts
    # just above its minimum on an ascending branch has not yet moved the play off the bottom
    if start.branch == "ascending":
        z0 = np.maximum(z0, float(u.min()) + thresholds)
    elif start.branch == "descending":
        z0 = np.minimum(z0, float(u.max()) - thresholds)
    return (play_outputs(u, thresholds, z0)[:, 0] - u) / threshold


def velocity_squared_lag(target: NDArray[np.float64], dt: float, alpha: float) -> NDArray[np.float64]:
    """The output of an element that trails ``target`` by ``alpha * v * |v|`` (``v`` its own rate):
    velocity-squared friction between the rate-independent value and what is measured.

    Each step solves ``y_k = target_k - alpha * v_k |v_k|`` with ``v_k = (y_k - y_{k-1}) / dt``
    exactly (a quadratic in the step), so it is stable for any ``alpha >= 0`` [s^2 / unit].
    """
    if alpha <= 0:
        return target.copy()
    beta = alpha / dt**2
    out = np.empty_like(target)
    y = float(target[0])
    for k, value in enumerate(target.tolist()):
        error = value - y
        step = (-1.0 + (1.0 + 4.0 * beta * abs(error)) ** 0.5) / (2.0 * beta)
        y += step if error > 0 else -step
        out[k] = y
    return out
