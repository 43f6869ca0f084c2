"""The candidate extensions of the diagnosis: one physical term each, identified on the whole record.

Each candidate is a :class:`Design`: its hysteresis (and any grid setting) fitted on every row,
jointly with its term; a fold then refits only the gains and the term's coefficients.

* ``rate_dependence``, three forms, the best on the whole record wins: velocity-squared friction
  between the rate-independent value and the output (the output trails by ``alpha v|v|``), a
  rate-dependent hysteresis weight (the loop widens and the stroke changes with the input speed:
  ``branch * r`` and ``x * r``, ``r`` the input speed over its 95th percentile), or a payload on
  the muscle's pressure-dependent stiffness (:mod:`host.diagnose.payload`: it rings faster the
  higher the pressure);
* ``output_lag`` (a yardstick, never named): mechanics after the hysteresis, a first-order lag or a
  payload on a fixed stiffness; a speed-dependent term must explain more than these do;
* ``creep``: a creep spectrum, first-order relaxations of the hysteresis output at 1-64 s whose
  shares all have one sign (:func:`creep`);
* ``transport_delay``: a dead time before the hysteresis (whole samples, at least 3:
  :func:`delay_grid`), or one that differs between rising and falling input
  (:func:`direction_dependent_delay`);
* ``load_dependence`` / ``temperature_drift``: the measured column shifts and bends the curve
  and widens or narrows the loop, and acts through a curved map of itself
  (``v, v x, v x^2, v branch, v^2``); temperature also through the column after 3 s and 10 s
  thermal lags (``v_lag, v_lag x`` each: the rubber, braid or regulator body warms after the
  probe, and the difference of two lags is a gradient across a part);
* ``slow_drift``: the same five terms with a ramp in time in place of a measured column: the
  drift no column explains, and the yardstick an observed cause must beat.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import partial

import numpy as np
from numpy.typing import NDArray

from host.diagnose.features import actuator_input, direction_delayed, first_order, slow_part, velocity_squared_lag
from host.diagnose.hammerstein import FittedModel, fit_gains, fit_hammerstein, rmse
from host.diagnose.payload import (
    PayloadSetting,
    equation_error_starts,
    payload_follow,
    refined,
    stiffness_ratio,
    zoomed,
)

CAUSES = (
    "rate_dependence",
    "creep",
    "transport_delay",
    "load_dependence",
    "temperature_drift",
    "slow_drift",
    "output_lag",
)
# not causes but yardsticks: what a physical cause must explain more than (never named)
YARDSTICKS = ("slow_drift", "output_lag")
OBSERVED_CAUSES = ("load_dependence", "temperature_drift")
CREEP_TAUS_S = (2.0, 5.0, 10.0, 20.0, 40.0, 80.0)  # cross-run diagnosis: one time constant
CREEP_SPECTRUM_S = (1.0, 4.0, 16.0, 64.0)
# thermal time constants between the temperature probe and what a temperature changes (rubber,
# braid, the regulator's body take seconds to a minute); two, so that their difference (and the
# column less its 3 s lag) can follow a gradient across a part that fades when the temperature
# settles. A 40 s lag was never measured (it would only be used on records over 160 s, and the
# scorecards are 100 s)
THERMAL_LAGS_S = (3.0, 10.0)
MIN_DELAY_SAMPLES = 3
# dead times screened jointly with the shorter actuator lags (when a signature asks for it)
JOINT_DELAYS_S = (0.05, 0.1, 0.16, 0.2, 0.3)
# the dead-time grid: whole samples from MIN_DELAY_SAMPLES up, each about DELAY_RATIO times the
# last (a fixed grid in seconds had nothing under 10 ms, 3-10 samples of a 1 kHz record)
DELAY_RATIO = 1.3
MAX_DELAY_S = 0.5
# velocity-squared friction: the output's deflection at its 95th-percentile speed, as a share of its range
FRICTION_DEFLECTIONS = (0.0025, 0.005, 0.01, 0.02, 0.04, 0.08, 0.16)
SCREEN_ITERATIONS = 1
FULL_ITERATIONS = 3


@dataclass
class Context:
    """Everything a candidate model may use: the record, its features and the baseline's fit."""

    t: NDArray[np.float64]
    u: NDArray[np.float64]
    y: NDArray[np.float64]
    lag_rows: dict[float, NDArray[np.float32]]  # Preisach rows of the input after each actuator lag
    rate: NDArray[np.float64]
    branch: NDArray[np.float64]  # play offset (threshold 10 % of the range), scaled to +-1
    extras: dict[str, NDArray[np.float64]]
    dt: float
    x: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    lag_s: float = 0.0  # the actuator lag of the baseline
    output_rate: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    joint_delay: bool = False  # screen a dead time jointly with the shorter actuator lags
    ar: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))  # the baseline's poles
    # Preisach rows of a filter of the whole input (its history before the memory start
    # included); None: only the precomputed ``lag_rows`` exist
    rows_after: Callable[[Callable[[NDArray[np.float64]], NDArray[np.float64]]], NDArray[np.float32]] | None = None
    # the payload element's settings (host.diagnose.payload.refined), found once per record and
    # shared by rate_dependence and output_lag; None: not searched yet
    payload_settings: dict[bool, PayloadSetting] | None = None

    @property
    def rows(self) -> NDArray[np.float32]:
        return self.lag_rows[self.lag_s]


@dataclass
class Design:
    """A model whose hysteresis is identified on the whole record; what a fold refits is linear.

    The Preisach cell masses (and any grid setting: creep time constant, dead time, friction
    coefficient) are fitted once on every row, so a held-out block never asks the hysteresis for
    a memory state its training blocks did not visit (with ~100-200 masses that error swamped
    every effect: held-out baseline errors 4x the in-sample error on multisines). Per fold only
    the gain, the offset and the term's few coefficients are refitted on the training rows (the
    poles kept) and scored on the held-out rows: a term that fits one part of the record but not
    another fails there. Baseline and extensions all get their masses from every row, so
    neither is favoured.
    """

    name: str
    x: NDArray[np.float64]  # hysteresis output over the whole record [units of y]
    columns: NDArray[np.float64]  # the term's regressors in the ARX drive, (n, k)
    labels: list[str]
    ar: NDArray[np.float64]  # poles of the dynamics identified on the whole record (y_k = ar @ past y + drive)
    velocity_alpha: float = 0.0  # > 0: velocity-squared friction element after the ARX [s^2 / unit]
    extra: dict[str, float] = field(default_factory=dict)
    # the measured column (or time) the term is a function of: held-out rows where it lies outside
    # the training rows' range are not scored (see :meth:`scored`)
    source: NDArray[np.float64] | None = None

    def scored(self, train: NDArray[np.bool_], held: NDArray[np.bool_]) -> NDArray[np.bool_]:
        """Held-out rows this design can be judged on: where its column is inside the range the
        training rows saw. A blocked fold puts the first and last loads or temperatures of a
        record in a block of their own; a term there extrapolates its curvature, and its error
        says nothing about whether the column matters (the same rows are used for the baseline)."""
        if self.source is None:
            return held
        lo, hi = float(self.source[train].min()), float(self.source[train].max())
        return held & (self.source >= lo) & (self.source <= hi)

    def fit(self, ctx: Context, train: NDArray[np.bool_]) -> FittedModel:
        """Gain, offset and term coefficients on ``train`` rows (the poles kept), simulated over
        the whole record. Re-choosing the dynamics' order per fold made folds disagree for
        reasons that have nothing to do with the term."""
        target = ctx.y
        if self.velocity_alpha > 0:
            v = ctx.output_rate
            target = ctx.y + self.velocity_alpha * v * np.abs(v)
        model = fit_gains(self.name, self.x, target, train, self.ar, self.columns, self.labels)
        if self.velocity_alpha > 0:
            model.prediction = velocity_squared_lag(model.prediction, ctx.dt, self.velocity_alpha)
        model.extra.update(self.extra)
        return model


def _training_error(model: FittedModel, ctx: Context) -> float:
    error = rmse(model.prediction, ctx.y)
    return error if np.isfinite(error) else np.inf


def _screened(values: Sequence[float], design_for: Callable[[float, int], Design], ctx: Context) -> list[float]:
    """The whole-record RMSE of ``design_for(v, iterations)`` for each grid value ``v``, fitted
    with one alternation (a screen: full alternation on every value would triple the cost; the
    screening order of the grid values is what matters)."""
    every = np.ones(ctx.y.size, dtype=bool)
    return [_training_error(design_for(v, SCREEN_ITERATIONS).fit(ctx, every), ctx) for v in values]


def _fully_fitted(
    values: Sequence[float], errors: Sequence[float], design_for: Callable[[float, int], Design]
) -> Design:
    """The value of ``values`` with the lowest screened ``errors`` (the first on a tie), fitted fully."""
    return design_for(values[int(np.argmin(errors))], FULL_ITERATIONS)


def _best_of(values: Sequence[float], design_for: Callable[[float, int], Design], ctx: Context) -> Design:
    """The grid value of ``values`` whose screen (:func:`_screened`) has the lowest whole-record
    RMSE, fitted fully."""
    return _fully_fitted(values, _screened(values, design_for, ctx), design_for)


def _better_on_record(ctx: Context, forms: Sequence[Design]) -> Design:
    """The form of one cause with the lowest whole-record RMSE (each fitted on every row)."""
    every = np.ones(ctx.y.size, dtype=bool)
    return min(forms, key=lambda d: _training_error(d.fit(ctx, every), ctx))


def _normalised(values: NDArray[np.float64]) -> NDArray[np.float64]:
    v = values - values.mean()
    return v / (float(np.std(v)) or 1.0)


def _empty(n: int) -> NDArray[np.float64]:
    return np.zeros((n, 0))


def baseline(ctx: Context, fitted: FittedModel) -> Design:
    """Rate-independent hysteresis after the actuator lag (``ctx.x``), then the ``fitted`` baseline's dynamics."""
    return Design("baseline", ctx.x, _empty(ctx.y.size), [], fitted.ar, extra={"actuator_lag_s": ctx.lag_s})


def _hysteresis(
    ctx: Context,
    rows: NDArray[np.float32],
    target: NDArray[np.float64],
    iterations: int,
    columns: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The hysteresis output and the poles of a model fitted on every row (jointly with ``columns``)."""
    every = np.ones(ctx.y.size, dtype=bool)
    model, x = fit_hammerstein("x", rows, target, every, ctx.dt, iterations, columns=columns)
    return x, model.ar


def with_columns(ctx: Context, name: str, columns: NDArray[np.float64], labels: list[str], **extra: float) -> Design:
    """A term of ``columns`` (n x k regressors in the ARX drive, one coefficient each, named by
    ``labels``) whose hysteresis is refitted jointly with it on every row; ``extra``: settings to
    report with the fitted model. ``name`` is the cause it stands for.

    Not nested in the baseline: the ridge on the cell masses does not act on the columns, so a
    joint fit can move loop shape into hysteresis-shaped columns (``v x``) and end a little worse
    than the baseline on the whole record (0.1866 vs 0.1833 mm on pma_mixed for the drift). That
    biases the comparison towards ``none``. Keeping the better of this and "baseline + term"
    (nested) was measured: tuning set 16/35 named with 3/20 false alarms (creep on two step
    records) instead of 16/35 with 1/20, the fresh set unchanged (18/40, 5/20); the conservative
    form stays."""
    x, ar = _hysteresis(ctx, ctx.rows, ctx.y, FULL_ITERATIONS, columns=columns)
    return Design(name, x, columns, labels, ar, extra=dict(extra))


def _friction(ctx: Context, share: float, iterations: int) -> Design:
    """Velocity-squared friction: what is measured trails the rate-independent model's output by
    ``alpha v|v|``, ``v`` the output's speed. The hysteresis is fitted by equation error (to
    ``y + alpha v|v|`` with ``v`` from the measured output); the simulation passes the ARX output
    through :func:`velocity_squared_lag`, which needs no measured output."""
    v = ctx.output_rate
    speed95 = float(np.percentile(np.abs(v), 95)) or 1.0
    alpha = share * float(np.ptp(ctx.y)) / speed95**2
    x, ar = _hysteresis(ctx, ctx.rows, ctx.y + alpha * v * np.abs(v), iterations)
    extra = {"velocity_squared_coefficient_s2_per_unit": alpha, "deflection_share_at_speed95": share, "form": 0.0}
    return Design("rate_dependence", x, _empty(ctx.y.size), [], ar, velocity_alpha=alpha, extra=extra)


def _rate_weight(ctx: Context) -> Design:
    """Rate-dependent hysteresis weight: the loop width (``branch``) and the stroke (``x``) change
    with the input speed ``r`` (relative to its 95th percentile, capped at 3)."""
    speed = np.abs(ctx.rate)
    r = np.minimum(speed / (float(np.percentile(speed, 95)) or 1.0), 3.0)
    xn = _normalised(ctx.x)
    columns = np.column_stack([ctx.branch * r, xn * r, r])
    return with_columns(ctx, "rate_dependence", columns, ["branch*speed", "x*speed", "speed"], form=1.0)


def _payload_settings(ctx: Context) -> dict[bool, PayloadSetting]:
    """The payload element's best settings on this record (:func:`host.diagnose.payload.refined`),
    searched once: with the rows of no actuator lag and of the baseline's (the baseline may have
    taken a payload's ringing for a long lag)."""
    if ctx.payload_settings is None:
        lags = sorted({min(ctx.lag_rows, key=abs), ctx.lag_s})
        starts, outputs = equation_error_starts({lag: ctx.lag_rows[lag] for lag in lags}, ctx.u, ctx.y, ctx.dt)
        ctx.payload_settings = refined(starts, outputs, ctx.u, ctx.y, ctx.dt) if starts else {}
    return ctx.payload_settings


PAYLOAD_REFITS = 1  # zooms on the hysteresis refitted with the element, each followed by a refit


def payload_dynamics(ctx: Context, pressure_dependent: bool) -> Design | None:
    """A payload on the muscle's stiffness after the hysteresis (:mod:`host.diagnose.payload`),
    the hysteresis refitted on the rows filtered through it (the element is linear in its input,
    so ``y = element(rows @ E)``). ``pressure_dependent``: the stiffness grows with the pressure
    (a rate dependence: the loop's dynamic part changes along the stroke) or is fixed (linear
    mechanics, part of the ``output_lag`` yardstick). None when the record gives no such element.

    The setting found on the equation-error hysteresis is zoomed again on the hysteresis refitted
    with it (:data:`PAYLOAD_REFITS` times): a lightly damped payload must be matched within a
    fraction of a percent. On a 4 Hz payload on a fixed stiffness (tests/test_diagnose_payload.py)
    the fixed element gained +59.5 % held out after one refit and +74.5 % after two, for 0.8 s more
    CPU on that 60 s record."""
    setting = _payload_settings(ctx).get(pressure_dependent)
    if setting is None:
        return None
    every = np.ones(ctx.y.size, dtype=bool)
    rows = ctx.lag_rows[setting.lag_s]
    dense = rows.astype(np.float64)
    for refit in range(PAYLOAD_REFITS + 1):
        stiffness = stiffness_ratio(ctx.u, setting.floor)
        filtered = payload_follow(dense, ctx.dt, stiffness, setting.w_top, setting.zeta).astype(np.float32)
        model, x = fit_hammerstein("x", filtered, ctx.y, every, ctx.dt, FULL_ITERATIONS)
        if refit == PAYLOAD_REFITS or model.masses is None:
            break
        error = rmse(model.prediction, ctx.y)
        found = zoomed(
            {pressure_dependent: (error, setting)}, {setting.lag_s: dense @ model.masses}, ctx.u, ctx.y, ctx.dt
        )
        if found[pressure_dependent][1] == setting:
            break
        setting = found[pressure_dependent][1]
    extra = {
        "payload_frequency_at_top_hz": setting.frequency_hz,
        "payload_damping_ratio": setting.zeta,
        "actuator_lag_with_payload_s": setting.lag_s,
    }
    if setting.floor is not None:
        extra |= {"stiffness_floor": setting.floor, "form": 2.0}
    name = "rate_dependence" if pressure_dependent else "output_lag"
    return Design(name, x, _empty(ctx.y.size), [], model.ar, extra=extra)


def rate_dependence(ctx: Context) -> Design:
    """The best form (whole-record RMSE) of velocity-squared friction, a rate-dependent weight and
    a payload on the muscle's pressure-dependent stiffness."""
    friction = _best_of(FRICTION_DEFLECTIONS, partial(_friction, ctx), ctx)
    payload = payload_dynamics(ctx, pressure_dependent=True)
    return _better_on_record(ctx, (friction, _rate_weight(ctx), *([payload] if payload else [])))


OUTPUT_LAGS_S = (0.01, 0.02, 0.05, 0.1, 0.2)


def output_lag(ctx: Context) -> Design:
    """A first-order lag after the hysteresis (the mechanics between the muscle and the sensor),
    the hysteresis refitted with it: ``y = lag(rows @ E)`` is linear in the masses, so the rows
    are filtered once per grid value. A speed-dependent term (velocity-squared friction, a loop
    width growing with speed) also fits such a lag; it has to explain more than this does."""

    def design(tau_s: float, iterations: int) -> Design:
        rows = first_order(ctx.rows.astype(np.float64), ctx.dt, tau_s).astype(np.float32)
        x, ar = _hysteresis(ctx, rows, ctx.y, iterations)
        return Design("output_lag", x, _empty(ctx.y.size), [], ar, extra={"output_lag_s": tau_s})

    lag = _best_of(OUTPUT_LAGS_S, design, ctx)
    resonance = payload_dynamics(ctx, pressure_dependent=False)
    return lag if resonance is None else _better_on_record(ctx, (lag, resonance))


def _creep_spectrum(ctx: Context, sign: float) -> Design:
    """The relaxations of :func:`creep` whose shares all have ``sign``: a time constant whose
    share comes out with the other sign is dropped and the rest refitted (an active-set fit)."""
    every = np.ones(ctx.y.size, dtype=bool)
    taus = [tau for tau in CREEP_SPECTRUM_S if tau <= 0.5 * ctx.y.size * ctx.dt] or [CREEP_SPECTRUM_S[0]]
    while taus:
        columns = np.column_stack([slow_part(ctx.x, ctx.dt, tau) for tau in taus])
        candidate = with_columns(ctx, "creep", columns, [f"creep_{tau:g}s" for tau in taus])
        model = candidate.fit(ctx, every)
        shares = model.exogenous[model.nb : model.nb + len(taus)] / (model.exogenous[0] or 1.0)
        if np.all(sign * shares >= 0):
            candidate.extra = {f"creep_share_{tau:g}s": float(share) for tau, share in zip(taus, shares)}
            return candidate
        taus = [tau for tau, share in zip(taus, shares) if sign * share > 0]
    return Design("creep", ctx.x, _empty(ctx.y.size), [], ctx.ar)  # no relaxation of this sign: the baseline


def creep(ctx: Context) -> Design:
    """A creep spectrum: first-order relaxations of the hysteresis output at time constants
    spread over :data:`CREEP_SPECTRUM_S` (a Prony series: logarithmic creep and creep with two
    time constants are both sums of such terms), fitted jointly with the hysteresis.

    Every relaxation of one record runs the same way: either the output keeps following the
    input after it stops (delayed viscoelastic response: positive shares) or it relaxes back
    under the held pressure and load (the muscle lengthening: negative shares). A fit whose
    shares have mixed signs makes a band-pass out of relaxations, which fits some other error
    (a lag, an overshoot of the mechanics); so each sign is fitted on its own and the one with
    the lower whole-record error is kept."""
    return _better_on_record(ctx, [_creep_spectrum(ctx, sign) for sign in (1.0, -1.0)])


def transport_delay(ctx: Context) -> Design | None:
    """A dead time before the hysteresis, the hysteresis and dynamics refitted with it; the
    better (whole-record RMSE) of one dead time and one that differs between rising and falling
    input (:func:`direction_dependent_delay`).

    The baseline's actuator lag was chosen without a dead time, and a lag absorbs much of one
    (a 0.25 s lag for a 0.2 s dead time; 20 ms for a 16 ms shift of a real piezo record): so each
    dead time is screened with the baseline's lag and with what is left of it once the dead time
    is taken out (:func:`_lag_left`), and with ``ctx.joint_delay`` a coarse grid of dead times
    (:data:`JOINT_DELAYS_S`) with every shorter actuator lag too. A dead time with a shorter lag
    than the baseline's is kept only when it fits the whole record better than that lag followed
    by a second lag (:func:`_second_order_lag`); else the best dead time with the baseline's lag."""

    def delayed_rows(delay_s: float, lag_s: float) -> NDArray[np.float32]:
        steps = max(1, int(round(delay_s / ctx.dt)))
        rows = ctx.lag_rows[lag_s]
        return np.concatenate([np.repeat(rows[:1], steps, axis=0), rows[:-steps]])

    usable = usable_delays(ctx)
    if not usable:
        return None
    pairs = [(d, ctx.lag_s) for d in usable] + [(d, _lag_left(ctx, d)) for d in usable]
    if ctx.joint_delay:
        shorter = [lag for lag in ctx.lag_rows if 0 <= lag < ctx.lag_s]
        joint = {min(usable, key=lambda d: abs(d - j)) for j in JOINT_DELAYS_S if j <= usable[-1]}
        pairs += [(d, lag) for lag in shorter for d in sorted(joint)]
    pairs = list(dict.fromkeys(pairs))

    def design(index: float, iterations: int) -> Design:
        delay_s, lag_s = pairs[int(index)]
        x, ar = _hysteresis(ctx, delayed_rows(delay_s, lag_s), ctx.y, iterations)
        extra = {"dead_time_s": delay_s, "actuator_lag_with_dead_time_s": lag_s}
        return Design("transport_delay", x, _empty(ctx.y.size), [], ar, extra=extra)

    indices = [float(i) for i in range(len(pairs))]
    errors = _screened(indices, design, ctx)
    one = _fully_fitted(indices, errors, design)
    lag_s, delay_s = one.extra["actuator_lag_with_dead_time_s"], one.extra["dead_time_s"]
    if lag_s < ctx.lag_s:  # part of the baseline's lag became dead time: a second lag must not do as well
        second = _second_order_lag(ctx, lag_s, delay_s)
        if second is not None:
            every = np.ones(ctx.y.size, dtype=bool)
            rival = _training_error(second.fit(ctx, every), ctx)
            one.extra["second_lag_rmse"] = rival
            if _training_error(one.fit(ctx, every), ctx) >= rival:
                # the best dead time with the baseline's lag, from the same screen
                plain = [i for i, pair in enumerate(pairs) if pair[1] == ctx.lag_s]
                one = _fully_fitted([indices[i] for i in plain], [errors[i] for i in plain], design)
    two = direction_dependent_delay(ctx, one.extra["dead_time_s"], one.extra["actuator_lag_with_dead_time_s"])
    return one if two is None else _better_on_record(ctx, (one, two))


def _second_order_lag(ctx: Context, lag_s: float, delay_s: float) -> Design | None:
    """The actuator lag ``lag_s`` followed by a second first-order lag of half, once or twice
    ``delay_s`` (the best on the whole record): what a dead time that took over part of the
    baseline's lag must explain more than. A valve and a hose, or a valve and a mechanics
    resonance, make a lag of higher order, which a dead time plus a shorter lag also fits (v8:
    false alarms 3 -> 6 of 80 when every dead time was screened with the shorter lags). None
    when the input's history is not available."""
    if ctx.rows_after is None:
        return None
    rows_after = ctx.rows_after

    def design(tau_s: float, iterations: int) -> Design:
        def lagged(u: NDArray[np.float64]) -> NDArray[np.float64]:
            return first_order(actuator_input(u, ctx.dt, lag_s), ctx.dt, tau_s)

        x, ar = _hysteresis(ctx, rows_after(lagged), ctx.y, iterations)
        return Design("second_order_lag", x, _empty(ctx.y.size), [], ar, extra={"second_lag_s": tau_s})

    return _best_of([0.5 * delay_s, delay_s, 2.0 * delay_s], design, ctx)


def usable_delays(ctx: Context) -> list[float]:
    """The dead times the record can show (:func:`delay_grid`): at least :data:`MIN_DELAY_SAMPLES`
    samples (a shift of one or two samples is within what the model's own resolution, the Everett
    grid and the rate smoothing, produces on a plant without any delay) and at most a tenth of
    the record."""
    return delay_grid(ctx.dt, _longest_delay(ctx))


def delay_grid(dt: float, longest_s: float) -> list[float]:
    """Dead times [s] of whole samples from :data:`MIN_DELAY_SAMPLES` to ``longest_s`` (at most
    :data:`MAX_DELAY_S`), each about :data:`DELAY_RATIO` times the one before."""
    shortest, longest = MIN_DELAY_SAMPLES * dt, min(longest_s, MAX_DELAY_S)
    if longest < shortest:
        return []
    count = int(np.floor(np.log(longest / shortest) / np.log(DELAY_RATIO))) + 1
    steps = np.unique(np.round(shortest * DELAY_RATIO ** np.arange(count) / dt).astype(int))
    return [float(k * dt) for k in steps]


def _lag_left(ctx: Context, delay_s: float) -> float:
    """The longest actuator lag of the baseline's grid (0 or more) no longer than the baseline's
    lag less ``delay_s``: what remains of the lag once a dead time explains part of it. A
    baseline that reads the input through a lead (``lag_s <= 0``) has no lag a dead time could
    take over: its own reading is kept (pairing the dead time with no lag would drop the lead)."""
    if ctx.lag_s <= 0:
        return ctx.lag_s
    left = [lag for lag in ctx.lag_rows if 0 <= lag <= ctx.lag_s - delay_s]
    return max(left) if left else 0.0 if 0.0 in ctx.lag_rows else ctx.lag_s


def _longest_delay(ctx: Context) -> float:
    """The longest dead time a record can be judged on [s]: a tenth of it."""
    return 0.1 * ctx.y.size * ctx.dt


# the other direction's dead time, as a share of the one found for both
OTHER_DIRECTION_SHARES = (0.0, 0.5, 2.0)


def direction_dependent_delay(ctx: Context, delay_s: float, lag_s: float) -> Design | None:
    """A dead time of ``delay_s`` in one direction of the input and a share of
    :data:`OTHER_DIRECTION_SHARES` of it in the other (:func:`direction_delayed`; after the
    actuator lag ``lag_s``): a pilot valve that opens late but exhausts at once, a long supply
    line that fills slower than it vents. None when the input's history is not available."""
    if ctx.rows_after is None:
        return None
    rows_after = ctx.rows_after
    others = [share * delay_s for share in OTHER_DIRECTION_SHARES if share * delay_s <= _longest_delay(ctx)]
    pairs = [(delay_s, other) for other in others] + [(other, delay_s) for other in others]

    def design(index: float, iterations: int) -> Design:
        rise_s, fall_s = pairs[int(index)]

        def arriving(u: NDArray[np.float64]) -> NDArray[np.float64]:
            return direction_delayed(actuator_input(u, ctx.dt, lag_s), ctx.dt, rise_s, fall_s)

        x, ar = _hysteresis(ctx, rows_after(arriving), ctx.y, iterations)
        extra = {"dead_time_rise_s": rise_s, "dead_time_fall_s": fall_s, "actuator_lag_with_dead_time_s": lag_s}
        return Design("transport_delay", x, _empty(ctx.y.size), [], ar, extra=extra)

    return _best_of([float(i) for i in range(len(pairs))], design, ctx)


def _column_terms(ctx: Context, name: str, v: NDArray[np.float64], label: str) -> Design:
    """``v, v x, v x^2, v branch, v^2`` in the ARX drive: the curve shifts and bends, the loop
    widens or narrows, and the column acts through a curved map of itself (a load sags a muscle
    more per kilogram as it grows; rubber softens faster as it warms): without ``v^2`` a curved
    offset was left to whatever slow term came next (a creep, a drift).

    A temperature column also acts after each thermal lag of :data:`THERMAL_LAGS_S` shorter than
    a quarter of the record (``v_lag, v_lag x``: a shift and a gain change that follow the probe
    late); its shifted copies get the same terms, so they stay its null."""
    xn = _normalised(ctx.x)
    columns = np.column_stack([v, v * xn, v * xn**2, v * ctx.branch, v * v])
    labels = [label, f"{label}*x", f"{label}*x^2", f"{label}*branch", f"{label}^2"]
    if label == "temperature":
        for tau in THERMAL_LAGS_S:
            if tau < 0.25 * ctx.y.size * ctx.dt:
                lagged = _normalised(first_order(v, ctx.dt, tau))
                columns = np.column_stack([columns, lagged, lagged * xn])
                labels += [f"{label}_lag{tau:g}s", f"{label}_lag{tau:g}s*x"]
    model = with_columns(ctx, name, columns, labels)
    model.source = v
    return model


COLUMNS = {"load_dependence": "load", "temperature_drift": "temperature"}


def observed(ctx: Context, cause: str, values: NDArray[np.float64] | None = None) -> Design | None:
    """Load or temperature terms (of ``values`` in place of the column when given: a surrogate);
    None when the column is missing or constant."""
    column = COLUMNS[cause]
    if values is None:
        values = ctx.extras.get(column)
    if values is None or np.ptp(values) <= 0:
        return None
    return _column_terms(ctx, cause, _normalised(values), column)


def shifted_copies(values: NDArray[np.float64], count: int, rng: np.random.Generator) -> list[NDArray[np.float64]]:
    """Surrogates of a measured column: the column followed by its mirror image (length 2n),
    shifted circularly by 25-75 % or 125-175 % of the record and cut to n, so each is as smooth
    and as wide-ranging as the column but placed differently in time (a plain circular shift
    would put a jump in a warming curve). Shifts near 0 and 200 % return the column itself, and
    near 100 % its reversal, which the terms' free signs fit as well as the column: a quarter
    of the record is kept away from both. (With 10 % the copies of a heat-gun bump overlapped
    the bump and explained a real temperature effect nearly as well: tuning plants 14/35 named
    with 10-80 % shifts, 17/35 with these, false alarms 1/20 both, the fresh set unchanged.)
    A monotone column's copies are still correlated with it; the verdict states that confound
    instead (:data:`host.diagnose.decide.CONFOUNDED_R`)."""
    n = values.size
    mirrored = np.concatenate([values, values[::-1]])
    shares = rng.uniform(0.25, 0.75, count) + np.where(rng.random(count) < 0.5, 0.0, 1.0)
    return [np.roll(mirrored, int(share * n))[:n] for share in shares]


def slow_drift(ctx: Context, time: NDArray[np.float64] | None = None) -> Design:
    """The five terms of a measured column with a plain ramp in time in its place: the same
    flexibility (one given shape, five coefficients), so an observed cause has to explain more
    than time alone does. (Two or more free shapes of time would also fit whatever differs between
    the parts of a protocol, which is no drift.) ``time``: a surrogate in place of the ramp."""
    return _column_terms(ctx, "slow_drift", _normalised(ctx.t if time is None else time), "time")


def design(ctx: Context, cause: str) -> Design | None:
    """``cause``'s model fitted on the whole record, or None when the data cannot show it (column missing)."""
    if cause == "rate_dependence":
        return rate_dependence(ctx)
    if cause == "creep":
        return creep(ctx)
    if cause == "transport_delay":
        return transport_delay(ctx)
    if cause == "slow_drift":
        return slow_drift(ctx)
    if cause == "output_lag":
        return output_lag(ctx)
    return observed(ctx, cause)
