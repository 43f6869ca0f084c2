"""A payload on the muscle's pressure-dependent stiffness: mechanics after the hysteresis.

A mass hanging on (or pushed by) a muscle follows the muscle's quasi-static stroke ``x`` as a
damped oscillator whose spring is the muscle itself::

    m y'' + c y' + K(p) (y - x) = 0

A McKibben muscle's stiffness grows about linearly with its pressure (the braid's share) from a
floor (the rubber's), so with ``p_n`` the pressure over its recorded range and ``floor`` the
stiffness at no pressure as a share of the stiffness at the top (``floor / (1 + floor)``)::

    w(p)^2 = K(p) / m = w_top^2 s(p),      s(p) = (p_n + floor) / (1 + floor)

and, with the damping a fixed share of critical (the rubber's loss factor), ``c / m = 2 zeta
w(p)``. A stiffer muscle rings faster: the loop's dynamic part changes with the pressure, which no
fixed linear dynamics after the hysteresis (the baseline's ARX, a first-order lag) can follow.
``floor = None`` is the same element with a fixed stiffness (``s = 1``): a payload resonance that
does not depend on the pressure, linear mechanics that the diagnosis treats as a yardstick.

Identification, cheap enough for every record (``python bench/diagnose_bench.py --quick``: 40 000
samples took 9.8 s of CPU against 8.3 s without the element):

1. Equation error: ``y = x - (1 / w_top^2) y'' / s - (2 zeta / w_top) y' / sqrt(s)`` is linear in
   the Preisach masses and the two coefficients once ``y'``, ``y''`` are taken from the measured
   output (Savitzky-Golay, :data:`DERIVATIVE_WINDOW_S`); fitted jointly with the hysteresis for
   each stiffness floor, it starts ``w_top`` and ``zeta`` (a negative coefficient: no such element).
2. Output error: the start's hysteresis output is simulated through the element for a small grid
   around each start (:data:`FREQUENCY_STEPS` x :data:`DAMPING_STEPS` at the start's floor and on
   a fixed stiffness, every trial in one vectorised pass), then for finer grids (:data:`ZOOMS`)
   around the best; the RMSE of a gain and an offset (on at most :data:`RANK_SAMPLES` from the
   middle of the record) picks the best pressure-dependent setting and the best fixed one.
   Equation error alone is biased by the derivatives' noise and smoothing (a 2.4 Hz payload of
   blind9 came out at 2.7-6.0 Hz, depending on the floor).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import savgol_filter

from host.diagnose.hammerstein import fit_hammerstein, rmse

# stiffness floors: the muscle's stiffness at no pressure is floor / (1 + floor) of the top's
# (0.15: a braid-dominated muscle, ~13 %; 0.5: a thick bladder, 33 %); None: a fixed stiffness
STIFFNESS_FLOORS: tuple[float | None, ...] = (0.15, 0.5, None)
DERIVATIVE_WINDOW_S = 0.06  # Savitzky-Golay window for y' and y'' (a quarter period at ~4 Hz)
FREQUENCY_STEPS = (0.6, 0.8, 1.0, 1.25, 1.6)  # around the equation-error start
DAMPING_STEPS = (0.5, 1.0, 2.0)
# then finer grids around the best: factors of the frequency, the damping ratio and the
# stiffness floor (the floor only where it is pressure-dependent)
ZOOMS: tuple[tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]], ...] = (
    (tuple(np.linspace(0.9, 1.1, 9)), (0.7, 1.0, 1.4), (0.6, 1.0, 1.6)),
    (tuple(np.linspace(0.975, 1.025, 9)), (0.85, 1.0, 1.18), (0.8, 1.0, 1.25)),
    (tuple(np.linspace(0.994, 1.006, 5)), (0.93, 1.0, 1.07), (1.0,)),
)
# damping ratios tried: a payload that rings. Up to 1.5 (a pressure-dependent lag) the element
# also fitted the filling dynamics of blind's valve-fed chamber (a false alarm, +33.7 %, on
# valve_chamber/none forc_sweeps@450Hz; none at 0.7)
ZETA_RANGE = (0.03, 0.7)
MAX_FREQUENCY_SHARE = 0.25  # w_top / (2 pi) at most this share of the sample rate
# trials are ranked on this many samples from the middle of the record (each pass over the
# samples is a Python loop: on 40 000 samples the search cost 5 s of CPU)
RANK_SAMPLES = 8000


def _highest_w(dt: float) -> float:
    """The highest natural frequency tried [rad/s]: :data:`MAX_FREQUENCY_SHARE` of the sample rate."""
    return 2.0 * np.pi * MAX_FREQUENCY_SHARE / dt


@dataclass(frozen=True)
class PayloadSetting:
    """One element: the actuator lag of the rows it follows [s], the stiffness floor (None: fixed
    stiffness), the natural frequency at the top of the pressure range [rad/s] and the damping ratio."""

    lag_s: float
    floor: float | None
    w_top: float
    zeta: float

    @property
    def frequency_hz(self) -> float:
        return self.w_top / (2.0 * np.pi)


def stiffness_ratio(p: NDArray[np.float64], floor: float | None) -> NDArray[np.float64]:
    """``s(p)``: the muscle's stiffness over its value at the top of ``p``'s range (1 for ``floor`` None)."""
    if floor is None:
        return np.ones_like(p)
    p_n = (p - p.min()) / (float(np.ptp(p)) or 1.0)
    return (p_n + floor) / (1.0 + floor)


def _transition(
    w: NDArray[np.float64], zeta: NDArray[np.float64], h: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``a``, ``b`` of the exact transition over ``h`` [s] of ``e'' + 2 zeta w e' + w^2 e = 0``:
    ``e(h) = a e + b e'``, ``e'(h) = -w^2 b e + (a - 2 zeta w b) e'`` (``e^{A h} = a I + b A``, from
    the two roots; critical damping is nudged off its double root)."""
    zeta = np.where(np.abs(zeta - 1.0) < 1e-3, 1.0 - 1e-3, zeta)
    w = np.maximum(w, 1e-9)
    root = w * np.sqrt((zeta * zeta - 1.0).astype(np.complex128))
    high, low = -zeta * w + root, -zeta * w - root
    e_high, e_low = np.exp(high * h), np.exp(low * h)
    a = ((high * e_low - low * e_high) / (high - low)).real
    b = ((e_high - e_low) / (high - low)).real
    return a, b


BLOCK_SAMPLES = 2048  # transition coefficients are computed for this many samples at a time


def payload_follow(
    x: NDArray[np.float64],
    dt: float,
    stiffness: NDArray[np.float64],
    w_top: float | NDArray[np.float64],
    zeta: float | NDArray[np.float64],
) -> NDArray[np.float64]:
    """The payload's stroke following ``x`` [units of x] from rest on ``x[0]``:
    ``y'' = w^2 (x - y) - 2 zeta w y'`` with ``w = w_top sqrt(stiffness)``.

    ``x``: (n,) or (n, k) (each column filtered: Preisach rows, or one signal per trial);
    ``stiffness``: (n,) or (n, k); ``w_top`` [rad/s] and ``zeta``: scalars or (k,). Each sample's
    step is the exact solution with the stiffness of its end and ``x`` held at the mean of its two
    ends: exact for a fixed stiffness and a held input; against an input joined linearly it is
    4.4 % of a step off at 8 Hz sampled at 60 Hz (``w dt`` = 0.84; at most 1.57 is used).
    """
    flat = x.ndim == 1
    xs = x[:, None] if flat else x
    s = stiffness[:, None] if stiffness.ndim == 1 else stiffness
    w_top_row = np.atleast_1d(np.asarray(w_top, dtype=np.float64))[None, :]
    zeta_row = np.atleast_1d(np.asarray(zeta, dtype=np.float64))[None, :]
    width = max(xs.shape[1], s.shape[1], w_top_row.shape[1], zeta_row.shape[1])
    out = np.empty((xs.shape[0], width))
    y = np.broadcast_to(xs[0].astype(np.float64), (width,)).copy()
    speed = np.zeros(width)
    out[0] = y
    for begin in range(1, xs.shape[0], BLOCK_SAMPLES):
        stop = min(begin + BLOCK_SAMPLES, xs.shape[0])
        w = w_top_row * np.sqrt(np.maximum(s[begin:stop], 0.0))
        zeta_block = np.broadcast_to(zeta_row, w.shape)
        a, b = _transition(w, zeta_block, dt)
        settle = -(w * w) * b  # speed from the offset
        damp = a - 2.0 * zeta_block * w * b  # speed from the speed
        held = 0.5 * (xs[begin - 1 : stop - 1] + xs[begin:stop])
        a, b, settle, damp, held = (np.broadcast_to(v, (stop - begin, width)) for v in (a, b, settle, damp, held))
        for i in range(stop - begin):
            offset = y - held[i]
            y, speed = held[i] + a[i] * offset + b[i] * speed, settle[i] * offset + damp[i] * speed
            out[begin + i] = y
    return out[:, 0] if flat and width == 1 else out


def _derivatives(y: NDArray[np.float64], dt: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``y'`` [units/s] and ``y''`` [units/s^2], Savitzky-Golay (cubic) over :data:`DERIVATIVE_WINDOW_S`."""
    window = max(5, int(round(DERIVATIVE_WINDOW_S / dt)) | 1)
    return savgol_filter(y, window, 3, deriv=1, delta=dt), savgol_filter(y, window, 3, deriv=2, delta=dt)


def equation_error_starts(
    rows_by_lag: dict[float, NDArray[np.float32]], p: NDArray[np.float64], y: NDArray[np.float64], dt: float
) -> tuple[list[PayloadSetting], dict[float, NDArray[np.float64]]]:
    """Starting settings from the equation-error fits (module docstring, step 1), one per actuator
    lag and stiffness floor whose two coefficients both come out positive, and per lag the
    hysteresis output of its first fit (what step 2 simulates through the element)."""
    every = np.ones(y.size, dtype=bool)
    speed, acceleration = _derivatives(y, dt)
    w_max = _highest_w(dt)
    starts: list[PayloadSetting] = []
    outputs: dict[float, NDArray[np.float64]] = {}
    for lag_s, rows in rows_by_lag.items():
        for floor in STIFFNESS_FLOORS:
            s = stiffness_ratio(p, floor)
            columns = np.column_stack([acceleration / s, speed / np.sqrt(s)])
            model, x = fit_hammerstein("payload", rows, y, every, dt, 1, columns=columns)
            outputs.setdefault(lag_s, x)
            gain = float(model.exogenous[0]) or 1.0
            inertia, damping = -model.exogenous[model.nb : model.nb + 2] / gain
            if inertia > 0 and damping > 0:
                w_top = min(1.0 / float(np.sqrt(inertia)), w_max)
                zeta = float(np.clip(0.5 * damping * w_top, *ZETA_RANGE))
                starts.append(PayloadSetting(lag_s, floor, w_top, zeta))
    return starts, outputs


def _window(n: int) -> slice:
    """The samples trials are ranked on: at most :data:`RANK_SAMPLES` from the middle of the record."""
    begin = max(0, (n - RANK_SAMPLES) // 2)
    return slice(begin, min(n, begin + RANK_SAMPLES))


def _ranked(
    trials: list[PayloadSetting],
    outputs: dict[float, NDArray[np.float64]],
    p: NDArray[np.float64],
    y: NDArray[np.float64],
    dt: float,
) -> dict[bool, tuple[float, PayloadSetting]]:
    """The best of ``trials`` by the RMSE of a gain and an offset on its lag's hysteresis output
    through the element (every trial in one pass, on :func:`_window`'s samples, the first tenth of
    them left to settle): under key True the best with a pressure-dependent stiffness, under False
    the best fixed one."""
    trials = [t for t in dict.fromkeys(trials) if t.lag_s in outputs]
    if not trials:
        return {}
    window = _window(y.size)
    y_w = y[window]
    stiffness = {floor: stiffness_ratio(p, floor)[window] for floor in {t.floor for t in trials}}
    simulated = payload_follow(
        np.column_stack([outputs[t.lag_s][window] for t in trials]),
        dt,
        np.column_stack([stiffness[t.floor] for t in trials]),
        np.array([t.w_top for t in trials]),
        np.array([t.zeta for t in trials]),
    )
    scored = slice(y_w.size // 10, None)
    regressors = np.ones((y_w.size - y_w.size // 10, 2))
    best: dict[bool, tuple[float, PayloadSetting]] = {}
    for j, trial in enumerate(trials):
        regressors[:, 0] = simulated[scored, j]
        theta = np.linalg.lstsq(regressors, y_w[scored], rcond=None)[0]
        error = rmse(regressors @ theta, y_w[scored])
        key = trial.floor is not None
        if np.isfinite(error) and (key not in best or error < best[key][0]):
            best[key] = (error, trial)
    return best


def _around(
    setting: PayloadSetting, steps: tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]], dt: float
) -> list[PayloadSetting]:
    """Settings around ``setting``: its frequency, damping ratio and floor times each factor of ``steps``."""
    w_max = _highest_w(dt)
    frequency_steps, damping_steps, floor_steps = steps
    floors = [None] if setting.floor is None else [setting.floor * f for f in floor_steps]
    return [
        PayloadSetting(
            setting.lag_s, floor, min(setting.w_top * fw, w_max), float(np.clip(setting.zeta * fz, *ZETA_RANGE))
        )
        for fw in frequency_steps
        for fz in damping_steps
        for floor in floors
    ]


def zoomed(
    best: dict[bool, tuple[float, PayloadSetting]],
    outputs: dict[float, NDArray[np.float64]],
    p: NDArray[np.float64],
    y: NDArray[np.float64],
    dt: float,
) -> dict[bool, tuple[float, PayloadSetting]]:
    """``best`` (per key: error and setting) improved on the finer grids of :data:`ZOOMS` in turn."""
    best = dict(best)
    for steps in ZOOMS:
        finer = _ranked(
            [t for _error, setting in best.values() for t in _around(setting, steps, dt)], outputs, p, y, dt
        )
        for key, found in finer.items():
            if key in best and found[0] < best[key][0]:
                best[key] = found
    return best


def refined(
    starts: list[PayloadSetting],
    outputs: dict[float, NDArray[np.float64]],
    p: NDArray[np.float64],
    y: NDArray[np.float64],
    dt: float,
) -> dict[bool, PayloadSetting]:
    """The best setting around the starts (module docstring, step 2): a coarse grid around every
    start, then :data:`ZOOMS` finer grids around the best pressure-dependent and the best fixed
    setting. A lightly damped payload has to be matched closely: on a 4 Hz payload with a damping
    ratio of 0.12, 2.5 % off in frequency left 20 times the error of the exact setting, and 0.114
    for 0.12 in damping five times. Under key True the best with a pressure-dependent stiffness,
    under False the best fixed one (absent: no start)."""
    # each start also at a fixed stiffness (its frequency at the mean stiffness), so that a
    # pressure-dependent element always has its fixed twin to beat
    twins = [
        PayloadSetting(
            start.lag_s, None, start.w_top * float(np.sqrt(np.mean(stiffness_ratio(p, start.floor)))), start.zeta
        )
        for start in starts
        if start.floor is not None
    ]
    coarse = [t for start in starts + twins for t in _around(start, (FREQUENCY_STEPS, DAMPING_STEPS, (1.0,)), dt)]
    best = zoomed(_ranked(list(dict.fromkeys(coarse)), outputs, p, y, dt), outputs, p, y, dt)
    return {key: setting for key, (_error, setting) in best.items()}
