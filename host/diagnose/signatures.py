"""Discriminating signatures in the baseline's residual, each with a surrogate null distribution.

A signature is a cheap test on the full-record baseline residual ``r = y - simulated`` that one
cause leaves and the others do not. Each returns a :class:`Signature` with a p-value from
surrogates of the same residual (so the test's false-alarm rate is that p-value's level, whatever
the plant's structural error looks like), or ``None`` when the record cannot show it (no holds,
too few reversals, no column).

* ``creep``: the output keeps moving during holds *in the direction of the step before the hold*
  (a warming drift or a wandering room moves one way regardless of the step). Null: random signs
  of the steps (sign-flip surrogates).
* ``transport_delay``: at every input reversal the measured output turns later than the
  baseline's own simulation by the same time, whatever the speed (an actuator lag is already in
  the baseline; a speed-dependent lag grows with speed). Null: random signs of the per-reversal
  extra lags.

Measured columns (load, temperature) are tested on the held-out gain itself, against shifted
copies of the column (:func:`host.diagnose.candidates.shifted_copies`), not here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import binom

Array = NDArray[np.float64]
SURROGATES = 400
MIN_HOLDS = 4
HOLD_S = 4.0
MIN_REVERSALS = 6
MIN_LAG_SAMPLES = 2


@dataclass
class Signature:
    cause: str
    statistic: float
    p_value: float
    detail: str

    def as_json(self) -> dict[str, object]:
        return {"statistic": self.statistic, "p_value": self.p_value, "detail": self.detail}


def _sign_flip_p(values: Array, rng: np.random.Generator) -> tuple[float, float]:
    """One-sided p-value of ``mean(values) > 0`` against random signs, and the t-like statistic."""
    scale = float(np.sqrt(np.mean(values**2))) or 1.0
    observed = float(values.mean()) / scale
    flips = rng.choice((-1.0, 1.0), size=(SURROGATES, values.size))
    null = (flips * values).mean(axis=1) / scale
    return observed, float((1 + np.sum(null >= observed)) / (1 + SURROGATES))


def _holds(u: Array, dt: float) -> list[tuple[int, int]]:
    """(start, stop) of stretches where the input is still for at least :data:`HOLD_S`."""
    still = np.abs(np.diff(u, prepend=u[0])) <= 1e-6 * (float(np.ptp(u)) or 1.0)
    out, start = [], None
    for i, flag in enumerate(np.append(still, False)):
        if flag and start is None:
            start = i
        elif not flag and start is not None:
            if (i - start) * dt >= HOLD_S:
                out.append((start, i))
            start = None
    return out


def creep_signature(
    residual: Array, u: Array, dt: float, settle_s: float, rng: np.random.Generator
) -> Signature | None:
    """Drift of the residual during holds, signed by the step before each hold."""
    holds = _holds(u, dt)
    drifts, signs = [], []
    skip = int(round(max(1.0, settle_s) / dt))
    for start, stop in holds:
        seg = residual[start + skip : stop]
        if seg.size < 20 or start < 2:
            continue
        step = u[start] - u[max(0, start - int(round(2.0 / dt)))]
        if abs(step) <= 0.02 * float(np.ptp(u)):
            continue
        third = seg.size // 3
        drifts.append(float(seg[-third:].mean() - seg[:third].mean()))
        signs.append(float(np.sign(step)))
    if len(drifts) < MIN_HOLDS:
        return None
    signed = np.array(drifts) * np.array(signs)
    stat, p = _sign_flip_p(signed, rng)
    return Signature(
        "creep",
        stat,
        p,
        f"{len(drifts)} holds; the residual drifts with the step before the hold by "
        f"{np.median(signed):+.3g} (median), sign-flip p = {p:.2g}",
    )


def _reversals(u: Array, dt: float) -> list[int]:
    """Indices where the (lightly smoothed) input turns, between moves of >= 10 % of its range."""
    width = max(1, int(round(0.05 / dt)))
    us = np.convolve(u, np.ones(width) / width, mode="same")
    threshold = 0.1 * float(np.ptp(u))
    out: list[int] = []
    hi_i = lo_i = 0
    direction = 0  # 0 until the first move of a threshold
    for i, value in enumerate(us.tolist()):
        if value > us[hi_i]:
            hi_i = i
        if value < us[lo_i]:
            lo_i = i
        if direction >= 0 and value < us[hi_i] - threshold:
            if direction > 0:
                out.append(hi_i)
            direction, lo_i = -1, i
        elif direction <= 0 and value > us[lo_i] + threshold:
            if direction < 0:
                out.append(lo_i)
            direction, hi_i = 1, i
    return out


def reversal_lags(y: Array, simulated: Array, u: Array, dt: float, max_shift_s: float = 0.5) -> tuple[Array, Array]:
    """Extra lag [s] of the measured output behind the simulation around each input reversal
    (least-squares alignment over the turn), and the input speed before the reversal [units/s]."""
    shifts = np.arange(-int(round(max_shift_s / dt)), int(round(max_shift_s / dt)) + 1)
    lags, speeds = [], []
    half = int(round(min(1.0, 0.25 * u.size * dt) / dt))
    for i in _reversals(u, dt):
        a, b = i - half, i + half
        if a - shifts.max() < 0 or b + shifts.max() >= y.size:
            continue
        target = y[a:b] - y[a:b].mean()
        errors = []
        for s in shifts:
            sim = simulated[a - s : b - s]
            errors.append(float(np.sum((target - (sim - sim.mean())) ** 2)))
        best = int(np.argmin(errors))
        if best in (0, shifts.size - 1):
            continue  # no minimum inside the search: a flat turn, no timing
        lags.append(shifts[best] * dt)
        speeds.append(abs(u[i] - u[max(0, i - half)]) / (half * dt))
    return np.array(lags), np.array(speeds)


def dead_time_signature(y: Array, simulated: Array, u: Array, dt: float, rng: np.random.Generator) -> Signature | None:
    """A lag that every reversal shows and that does not shrink at slow reversals."""
    lags, speeds = reversal_lags(y, simulated, u, dt)
    if lags.size < MIN_REVERSALS:
        return None
    later, earlier = int(np.sum(lags > 0)), int(np.sum(lags < 0))
    # sign test: a dead time the baseline's actuator lag did not absorb makes the output turn late
    # at (nearly) every reversal; ties (no shift at the sample resolution) say nothing either way
    p = float(binom.sf(later - 1, later + earlier, 0.5)) if later + earlier else 1.0
    slow = speeds <= np.median(speeds)
    slow_lag = float(np.median(lags[slow]))
    fast_lag = float(np.median(lags[~slow])) if (~slow).any() else slow_lag
    median = float(np.median(lags))
    if median < MIN_LAG_SAMPLES * dt or slow_lag < MIN_LAG_SAMPLES * dt:
        # no lag at the sample resolution, or it vanishes at slow turns (speed-dependent, not dead)
        p = max(p, 0.5)
    return Signature(
        "transport_delay",
        median,
        p,
        f"{lags.size} reversals; the output turns {median * 1e3:+.0f} ms (median) after the baseline's "
        f"simulation ({slow_lag * 1e3:+.0f} ms at slow turns, {fast_lag * 1e3:+.0f} ms at fast ones; later at "
        f"{later}, earlier at {earlier}), sign test p = {p:.2g}",
    )


def signatures(
    residual: Array,
    y: Array,
    simulated: Array,
    u: Array,
    dt: float,
    settle_s: float,
    seed: int = 0,
) -> dict[str, Signature]:
    """Every signature the record can show, keyed by cause."""
    rng = np.random.default_rng(seed)
    out: dict[str, Signature | None] = {
        "creep": creep_signature(residual, u, dt, settle_s, rng),
        "transport_delay": dead_time_signature(y, simulated, u, dt, rng),
    }
    return {c: s for c, s in out.items() if s is not None}
