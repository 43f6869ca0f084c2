"""The candidate extensions of the diagnosis: one physical term each, fitted on one fold's training rows.

* ``rate_dependence``, two forms, the better on training rows wins: velocity-squared friction
  between the rate-independent value and the output (the output trails by ``alpha v|v|``), or a
  rate-dependent hysteresis weight (the loop widens and the stroke changes with the input speed:
  ``branch * r`` and ``x * r``, ``r`` the input speed over its 95th percentile);
* ``creep``: a creep operator, first-order relaxation of the hysteresis output (2-80 s);
* ``transport_delay``: a dead time before the hysteresis (at least 3 samples);
* ``load_dependence`` / ``temperature_drift``: the measured column shifts and bends the curve
  and widens or narrows the loop (``v, v x, v x^2, v branch``);
* ``slow_drift``: the same four terms with a ramp in time in place of a measured column: the
  drift no column explains, and the yardstick an observed cause must beat.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from host.diagnose.features import velocity_squared_lag
from host.diagnose.hammerstein import FittedModel, fit_arx, fit_hammerstein, rmse

CAUSES = ("rate_dependence", "creep", "transport_delay", "load_dependence", "temperature_drift", "slow_drift")
OBSERVED_CAUSES = ("load_dependence", "temperature_drift")
CREEP_TAUS_S = (2.0, 5.0, 10.0, 20.0, 40.0, 80.0)
MIN_DELAY_SAMPLES = 3
# dead times screened jointly with the shorter actuator lags (when a signature asks for it)
JOINT_DELAYS_S = (0.05, 0.1, 0.16, 0.2, 0.3)
DELAYS_S = (0.01, 0.02, 0.03, 0.05, 0.07, 0.1, 0.13, 0.16, 0.2, 0.25, 0.3, 0.4, 0.5)
# velocity-squared friction: the output's deflection at its 95th-percentile speed, as a share of its range
FRICTION_DEFLECTIONS = (0.0025, 0.005, 0.01, 0.02, 0.04, 0.08, 0.16)
SCREEN_ITERATIONS = 1
FULL_ITERATIONS = 3


@dataclass
class Context:
    """Everything a candidate model may use: the record, its features, one fold's training rows."""

    t: NDArray[np.float64]
    u: NDArray[np.float64]
    y: NDArray[np.float64]
    lag_rows: dict[float, NDArray[np.float32]]  # Preisach rows of the input after each actuator lag
    rate: NDArray[np.float64]
    branch: NDArray[np.float64]  # play offset (threshold 10 % of the range), scaled to +-1
    extras: dict[str, NDArray[np.float64]]
    dt: float
    train: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))
    x: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    lag_s: float = 0.0  # the actuator lag of the baseline
    output_rate: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    joint_delay: bool = False  # screen a dead time jointly with the shorter actuator lags

    @property
    def rows(self) -> NDArray[np.float32]:
        return self.lag_rows[self.lag_s]


def _best_of(
    ctx: Context, key: str, values: Sequence[float], fit_for: Callable[[float, int], FittedModel]
) -> FittedModel:
    """``fit_for(v, iterations)`` for each candidate ``v``: screened with one alternation each, the
    lowest *training* RMSE wins and is fitted fully (the screening order of the grid values is
    what matters; full alternation on every value would triple the cost)."""
    best_value: float | None = None
    best_error = np.inf
    for value in values:
        model = fit_for(value, SCREEN_ITERATIONS)
        error = rmse(model.prediction[ctx.train], ctx.y[ctx.train])
        if np.isfinite(error) and error < best_error:
            best_value, best_error = value, error
    chosen = values[0] if best_value is None else best_value  # all diverged: the first stands for the failed fit
    model = fit_for(chosen, FULL_ITERATIONS)
    model.extra[key] = float(chosen)
    return model


def centred(values: NDArray[np.float64], train: NDArray[np.bool_]) -> NDArray[np.float64]:
    return values - values[train].mean()


def _normalised(values: NDArray[np.float64], train: NDArray[np.bool_]) -> NDArray[np.float64]:
    v = centred(values, train)
    return v / (float(np.std(v[train])) or 1.0)


def _friction_model(ctx: Context, share: float, iterations: int = FULL_ITERATIONS) -> FittedModel:
    """Velocity-squared friction: what is measured trails the rate-independent model's output by
    ``alpha v|v|``, ``v`` the output's speed. Fitted by equation error (hysteresis + dynamics
    fitted to ``y + alpha v|v|`` with ``v`` from the measured training output), simulated (output
    error) through :func:`velocity_squared_lag`, which needs no measured output."""
    v = ctx.output_rate
    speed95 = float(np.percentile(np.abs(v[ctx.train]), 95)) or 1.0
    alpha = share * float(np.ptp(ctx.y[ctx.train])) / speed95**2
    model, _ = fit_hammerstein(
        "rate_dependence", ctx.rows, ctx.y + alpha * v * np.abs(v), ctx.train, ctx.dt, iterations=iterations
    )
    model.prediction = velocity_squared_lag(model.prediction, ctx.dt, alpha)
    model.extra["velocity_squared_coefficient_s2_per_unit"] = alpha
    model.extra["form"] = 0.0
    return model


def _rate_weight_model(ctx: Context) -> FittedModel:
    """Rate-dependent hysteresis weight: the loop width (``branch``) and the stroke (``x``) change
    with the input speed ``r`` (relative to its 95th percentile, capped at 3)."""
    speed = np.abs(ctx.rate)
    r = np.minimum(speed / (float(np.percentile(speed[ctx.train], 95)) or 1.0), 3.0)
    xn = _normalised(ctx.x, ctx.train)
    columns = np.column_stack([ctx.branch * r, xn * r, r])
    model = fit_arx("rate_dependence", ctx.x, ctx.y, ctx.train, columns, ["branch*speed", "x*speed", "speed"], ctx.dt)
    model.extra["form"] = 1.0
    return model


def rate_dependence(ctx: Context) -> FittedModel:
    """The better form (training RMSE) of velocity-squared friction and a rate-dependent weight."""
    friction = _best_of(
        ctx, "deflection_share_at_speed95", FRICTION_DEFLECTIONS, lambda share, it: _friction_model(ctx, share, it)
    )
    weight = _rate_weight_model(ctx)
    score = {id(m): rmse(m.prediction[ctx.train], ctx.y[ctx.train]) for m in (friction, weight)}
    return min((friction, weight), key=lambda m: score[id(m)] if np.isfinite(score[id(m)]) else np.inf)


def creep(ctx: Context) -> FittedModel:
    """A creep operator: first-order relaxation of the hysteresis output, time constant by grid."""
    taus = [tau for tau in CREEP_TAUS_S if tau <= 0.5 * ctx.y.size * ctx.dt] or [CREEP_TAUS_S[0]]
    return _best_of(
        ctx,
        "creep_time_constant_s",
        taus,
        lambda tau, it: fit_hammerstein("creep", ctx.rows, ctx.y, ctx.train, ctx.dt, it, creep_tau_s=tau)[0],
    )


def transport_delay(ctx: Context) -> FittedModel | None:
    """A dead time before the hysteresis, the dynamics refitted with it.

    The baseline's actuator lag was chosen without a dead time, and a lag absorbs much of one
    (a 0.25 s lag for a 0.2 s dead time); so with ``ctx.joint_delay`` the dead time is screened
    jointly with the shorter actuator lags too (coarse grid: :data:`JOINT_DELAYS_S`)."""

    def delayed_rows(delay_s: float, lag_s: float) -> NDArray[np.float32]:
        steps = max(1, int(round(delay_s / ctx.dt)))
        rows = ctx.lag_rows[lag_s]
        return np.concatenate([np.repeat(rows[:1], steps, axis=0), rows[:-steps]])

    longest = 0.1 * ctx.y.size * ctx.dt  # a shift of at most a tenth of the record
    # a shift of one or two samples is within what the model's own resolution (Everett grid,
    # rate smoothing) produces on a plant without any delay; evidence starts at 3 samples
    usable = [d for d in DELAYS_S if MIN_DELAY_SAMPLES * ctx.dt <= d <= longest]
    if not usable:
        return None
    pairs = [(d, ctx.lag_s) for d in usable]
    if ctx.joint_delay:
        shorter = [lag for lag in ctx.lag_rows if lag < ctx.lag_s]
        pairs += [(d, lag) for lag in shorter for d in JOINT_DELAYS_S if d in usable]
    best, best_error = pairs[0], np.inf
    for delay_s, lag_s in pairs:
        model, _ = fit_hammerstein(
            "transport_delay", delayed_rows(delay_s, lag_s), ctx.y, ctx.train, ctx.dt, SCREEN_ITERATIONS
        )
        error = rmse(model.prediction[ctx.train], ctx.y[ctx.train])
        if np.isfinite(error) and error < best_error:
            best, best_error = (delay_s, lag_s), error
    model, _ = fit_hammerstein("transport_delay", delayed_rows(*best), ctx.y, ctx.train, ctx.dt, FULL_ITERATIONS)
    model.extra["dead_time_s"] = float(best[0])
    model.extra["actuator_lag_with_dead_time_s"] = float(best[1])
    return model


def _four_terms(ctx: Context, name: str, v: NDArray[np.float64], label: str) -> FittedModel:
    """``v, v x, v x^2, v branch`` in the ARX drive: the curve shifts and bends, the loop widens or narrows."""
    xn = _normalised(ctx.x, ctx.train)
    return fit_arx(
        name,
        ctx.x,
        ctx.y,
        ctx.train,
        np.column_stack([v, v * xn, v * xn**2, v * ctx.branch]),
        [label, f"{label}*x", f"{label}*x^2", f"{label}*branch"],
        ctx.dt,
    )


def observed(ctx: Context, cause: str) -> FittedModel | None:
    """Load or temperature terms; None when the column is missing or constant."""
    column = {"load_dependence": "load", "temperature_drift": "temperature"}[cause]
    values = ctx.extras.get(column)
    if values is None or np.ptp(values) <= 0:
        return None
    return _four_terms(ctx, cause, _normalised(values, ctx.train), column)


def slow_drift(ctx: Context) -> FittedModel:
    """The four terms of a measured column with a plain ramp in time in its place: the same
    flexibility (one given shape, four coefficients), so an observed cause has to explain more
    than time alone does. (Two or more free shapes of time would also fit whatever differs between
    the parts of a protocol, which is no drift.)"""
    ramp = (ctx.t - ctx.t[ctx.train].mean()) / max(float(np.ptp(ctx.t)), ctx.dt)
    return _four_terms(ctx, "slow_drift", _normalised(ramp, ctx.train), "time")


def extension(ctx: Context, cause: str) -> FittedModel | None:
    """The model with ``cause``'s term, or None when the data cannot show it (column missing)."""
    if cause == "rate_dependence":
        return rate_dependence(ctx)
    if cause == "creep":
        return creep(ctx)
    if cause == "transport_delay":
        return transport_delay(ctx)
    if cause == "slow_drift":
        return slow_drift(ctx)
    return observed(ctx, cause)
