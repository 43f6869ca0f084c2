"""Baseline and extended models of the diagnosis, fitted on training rows only.

Baseline (Ai2019's Hammerstein structure without the neural net): a rate-independent
Preisach hysteresis ``x = rows @ E`` (non-negative cell masses), followed by all-pole ARX
``y(k) = sum a_i y(k-i) + b x(k) + c`` with ``na`` in 0..2 and time constants of at most
:data:`MAX_TIME_CONSTANT_S`, the order chosen by AIC on the *simulation* error of the training
rows. Hysteresis and dynamics are fitted together by alternation (:func:`fit_hammerstein`) and
simulated (output error) over the whole record.

Extensions either add columns to the ARX drive, fitted jointly with the masses (load,
temperature, drift, rate weight, creep relaxations), refit the whole model on other hysteresis
rows (a dead time: delayed rows), or refit it to an equation-error target and pass its output
through an element (velocity-squared friction: ``host.diagnose.candidates._friction``).
:func:`fit_gains` refits gains and term coefficients with the poles given (what a held-out fold
does). Every fit sees only the rows marked in ``train``; the memory (input history) is the
whole record, since the input is known everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import nnls
from scipy.signal import lfilter, lfilter_zi

# all-pole dynamics: the rig's mechanics after the muscle are low-pass; a zero would put
# derivative action in the baseline, which mimics rate-dependent hysteresis
ORDERS = [(na, 1) for na in (0, 1, 2)]
MAX_TIME_CONSTANT_S = 2.0
STATIC_ROWS = 10_000
# ridge on the cell masses (relative to the mean diagonal of the normal equations): it keeps the
# normal equations positive definite for cells few rows visit. It was 1e-3 while the masses were
# fitted per fold (a held-out block visiting such cells got several times the training error);
# since the masses are fitted on every row that reason is gone and 1e-3 cost accuracy: on
# friction_spring/temperature_drift:narrowing/steps@50Hz/s129 the baseline's error is 0.060 mm
# at 1e-3 and 0.038 mm at 1e-4 (noise 0.031 mm). With 1e-4 the best gain of effect-free records
# grows too, which the calibrated gain floor (host.diagnose.decide.GAIN_FLOOR) accounts for.
MASS_RIDGE = 1e-4


@dataclass
class FittedModel:
    """A fitted baseline or extension and its simulation over the whole record."""

    name: str
    prediction: NDArray[np.float64]
    na: int
    nb: int
    ar: NDArray[np.float64]
    exogenous: NDArray[np.float64]
    extra: dict[str, float] = field(default_factory=dict)
    columns: list[str] = field(default_factory=list)
    masses: NDArray[np.float64] | None = None  # Preisach cell masses when the model has a hysteresis
    x_shift: float = 0.0  # x = rows @ masses + x_shift


def static_masses(
    rows: NDArray[np.floating],
    y: NDArray[np.float64],
    train: NDArray[np.bool_],
    free: NDArray[np.float64] | None = None,
) -> NDArray[np.float64]:
    """Cell masses >= 0 with ``y ~ rows @ masses + free @ d + offset`` on ``train`` rows.

    ``free`` columns (an extension's terms) are fitted jointly with any sign: they are projected
    out of the normal equations (a Schur complement), so that the term takes what it explains and
    the masses do not absorb it first; only the masses are returned.

    The offset is eliminated by centring, then NNLS runs on the Cholesky factor of the centred
    normal equations (small: one column per Everett cell). The rows carry the hysteresis memory,
    so evenly spaced training rows (at most :data:`STATIC_ROWS`) are an exact subproblem; this
    keeps the many refits of a diagnosis independent of the record's length.
    """
    chosen = np.flatnonzero(train)
    chosen = chosen[:: max(1, chosen.size // STATIC_ROWS)]
    design = np.asarray(rows[chosen], dtype=np.float64)
    design -= design.mean(axis=0)  # centred explicitly: D^T D stays positive semi-definite
    centred = y[chosen] - y[chosen].mean()
    gram = design.T @ design
    rhs = design.T @ centred
    if free is not None and free.shape[1]:
        f = free[chosen] - free[chosen].mean(axis=0)
        f_gram = f.T @ f
        f_gram += 1e-9 * (float(np.trace(f_gram)) or 1.0) * np.eye(len(f_gram))
        cross = design.T @ f
        gram = gram - cross @ np.linalg.solve(f_gram, cross.T)
        rhs = rhs - cross @ np.linalg.solve(f_gram, f.T @ centred)
        gram = 0.5 * (gram + gram.T)
    scale = max(float(np.trace(gram)) / len(gram), 1e-300)
    for ridge in (MASS_RIDGE, 1e-2):  # cells no training row visits make gram singular
        try:
            factor = np.linalg.cholesky(gram + ridge * scale * np.eye(len(gram)))
            break
        except np.linalg.LinAlgError:
            continue
    else:
        raise np.linalg.LinAlgError("hysteresis normal equations are not positive definite even with a ridge")
    masses, _ = nnls(factor.T, np.linalg.solve(factor, rhs), maxiter=20 * len(gram))
    return np.asarray(masses)


def fit_static(
    rows: NDArray[np.float32],
    y: NDArray[np.float64],
    train: NDArray[np.bool_],
    free: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Hysteresis output ``x`` for the whole record, fitted as if there were no dynamics (jointly
    with the ``free`` columns), and its masses."""
    masses = static_masses(rows, y, train, free)
    x = rows.astype(np.float64) @ masses
    return x - x[train].mean() + y[train].mean(), masses


def fit_hammerstein(
    name: str,
    rows: NDArray[np.float32],
    y: NDArray[np.float64],
    train: NDArray[np.bool_],
    dt: float,
    iterations: int = 3,
    columns: NDArray[np.float64] | None = None,
    labels: list[str] | None = None,
) -> tuple[FittedModel, NDArray[np.float64]]:
    """Hysteresis and ARX fitted together by alternation (Narendra-Gallman).

    Fitting the hysteresis first as if static lets it absorb the dynamics (a valve lag widens
    the loops); so: fit ARX on ``x``, then refit the masses on the rows filtered by the ARX
    (``y = (B/A) rows @ masses + c`` is linear in the masses), and repeat. Returns the model and
    its hysteresis output ``x``.

    ``columns`` (an extension's terms, ``labels`` their names) join the ARX drive and are fitted
    jointly with the masses (as ``(1/A) columns``), so the masses do not absorb what they explain.
    """
    free = np.zeros((y.size, 0)) if columns is None else columns

    def arx(x: NDArray[np.float64]) -> FittedModel:
        return fit_arx(name, x, y, train, free, list(labels or [f"c{i}" for i in range(free.shape[1])]), dt)

    x, masses = fit_static(rows, y, train, free)
    model = arx(x)
    model.masses = masses
    model.x_shift = float(x[0] - dense_first(rows) @ masses)
    dense = rows.astype(np.float64)
    for _ in range(iterations):
        b = model.exogenous[: model.nb]
        a = np.r_[1.0, -model.ar]
        if abs(b.sum()) < 1e-12:
            break
        filtered = _filter_columns(b, a, dense)
        free_filtered = _filter_columns(np.ones(1), a, free) if free.shape[1] else None
        masses = static_masses(filtered, y, train, free_filtered)
        x_new = dense @ masses
        candidate = arx(x_new)
        candidate.masses = masses
        if rmse(candidate.prediction[train], y[train]) >= rmse(model.prediction[train], y[train]):
            break
        model, x = candidate, x_new
    return model, x


def dense_first(rows: NDArray[np.float32]) -> NDArray[np.float64]:
    return np.asarray(rows[0], dtype=np.float64)


def _filter_columns(
    b: NDArray[np.float64], a: NDArray[np.float64], columns: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Every column through ``b/a``, starting settled at the first row."""
    if a.size == 1 and b.size == 1:
        return b[0] / a[0] * columns
    zi = lfilter_zi(b, a)[:, None] * columns[:1]
    return lfilter(b, a, columns, axis=0, zi=zi)[0]


def _lagged(signal: NDArray[np.float64], lags: range) -> NDArray[np.float64]:
    return np.column_stack([np.concatenate([np.full(lag, signal[0]), signal[: signal.size - lag]]) for lag in lags])


def fit_arx(
    name: str,
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    train: NDArray[np.bool_],
    extra: NDArray[np.float64] | None = None,
    columns: list[str] | None = None,
    dt: float = 0.01,
) -> FittedModel:
    """ARX from ``x`` (plus ``extra`` columns) to ``y``: order by AIC, then simulated.

    Poles slower than :data:`MAX_TIME_CONSTANT_S` are refused: the baseline's linear dynamics
    are the rig's mechanics; a slower relaxation is what the creep extension stands for.
    """
    pole_limit = float(np.exp(-dt / MAX_TIME_CONSTANT_S))
    usable = train.copy()
    usable[:2] = False
    extra = np.zeros((x.size, 0)) if extra is None else extra
    best: tuple[float, FittedModel] | None = None
    for na, nb in ORDERS:
        past_y = _lagged(y, range(1, na + 1)) if na else np.zeros((y.size, 0))
        inputs = _lagged(x, range(0, nb))
        design = np.column_stack([past_y, inputs, extra, np.ones(y.size)])
        theta = np.asarray(np.linalg.lstsq(design[usable], y[usable], rcond=None)[0], dtype=np.float64)
        ar = theta[:na]
        if na and np.any(np.abs(np.roots(np.r_[1.0, -ar])) >= pole_limit):
            continue  # unstable, or slower than the rig's mechanics (slow relaxation is creep)
        exogenous = theta[na:]
        drive = np.column_stack([inputs, extra, np.ones(y.size)]) @ exogenous
        prediction = lfilter([1.0], np.r_[1.0, -ar], drive, zi=_steady_state(ar, y[0]))[0]
        model = FittedModel(name, prediction, na, nb, ar, exogenous, columns=list(columns or []))
        # the model is used in simulation: judge the order by its simulation error, not by the
        # one-step equation error (which favours near-integrators that simulate badly)
        residual = prediction[usable] - y[usable]
        aic = usable.sum() * np.log(max(float(residual @ residual) / usable.sum(), 1e-300)) + 2 * theta.size
        if best is None or aic < best[0]:
            best = (aic, model)
    assert best is not None, "ARX with na=0 is always stable"
    return best[1]


def fit_gains(
    name: str,
    x: NDArray[np.float64],
    y: NDArray[np.float64],
    train: NDArray[np.bool_],
    ar: NDArray[np.float64],
    extra: NDArray[np.float64],
    columns: list[str],
) -> FittedModel:
    """``y = (1/A) (b x + extra @ d + c)`` with the poles ``ar`` given: ``b``, ``d``, ``c`` by least
    squares on the *simulated* output of the ``train`` rows (linear once the poles are fixed)."""
    a = np.r_[1.0, -ar]
    regressors = np.column_stack([x, extra, np.ones(y.size)])
    if ar.size:
        zi = lfilter_zi([1.0], a)[:, None] * regressors[:1]
        regressors = lfilter([1.0], a, regressors, axis=0, zi=zi)[0]
    theta = np.asarray(np.linalg.lstsq(regressors[train], y[train], rcond=None)[0], dtype=np.float64)
    return FittedModel(name, regressors @ theta, ar.size, 1, ar.copy(), theta, columns=list(columns))


def _steady_state(ar: NDArray[np.float64], y0: float) -> NDArray[np.float64]:
    """lfilter initial conditions so that the simulation starts at ``y0`` (with the drive at its level)."""
    if ar.size == 0:
        return np.zeros(0)
    # direct form II transposed with b = [1]: start as if y had been y0 for ever
    zi = np.zeros(ar.size)
    for i in range(ar.size):
        zi[i] = y0 * ar[i:].sum()
    return zi


def rmse(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))
