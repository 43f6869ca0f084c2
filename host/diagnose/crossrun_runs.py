"""Cross-run diagnosis over lists of runs: what a model identified on every training run together
gets wrong on every test run.

1. prepare: training and test runs as one :class:`host.diagnose.runs.RunSet` (one sample rate,
   one Everett grid over the *training* input range; a test input outside it is clipped and a
   note says how much);
2. identify: the baseline M0 of diagnosis v3 (Preisach hysteresis, output lag, its tangents and
   static output map; :mod:`host.diagnose.nuisance`) fitted on the training rows only, then run
   unchanged on the test runs' inputs (memory restarts at each run);
3. correct: one correction at a time is fitted to the test runs' residual on training folds and
   scored on held-out folds (whole test runs when runs are short, else contiguous blocks; their
   number adapts to the data): a session offset, a gain, an input (transducer zero) shift, each
   cause group of v3 but slow drift (rate, creep, dead time, a measured column), and the whole
   hysteresis identified again (the yardstick). Slow drift *within* the test session is left
   out: lab campaigns record their runs in the order of the protocol's settings, so a spline of
   the test clock fits whatever differs between settings (on the muscle campaigns it beat every
   physical correction that way), and it says nothing about what changed between sessions;
4. decide: a correction is named when its Clark-West test of the held-out improvement over the
   session offset passes at ``alpha / number of corrections`` (Bonferroni) and its 90 % interval
   of the held-out gain lies above 0; the physical correction with the largest gain first, the
   refitted hysteresis only when no physical one passes; an offset alone when only it passes.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError
from host.data import Measurement
from host.diagnose.groups import cause_groups
from host.diagnose.heldout import HeldOut, held_out, holdout_folds
from host.diagnose.nuisance import Baseline, fit_baseline, ridge_fit, run_gradient, run_lowpass
from host.diagnose.rules import CAUSES, RULES, Rules
from host.diagnose.runs import RunSet, node_differences, preisach_nodes, run_set

OFFSET = "session_drift"
# input (pressure transducer) zero shifts whose first-order directions form the input_drift group,
# as shares of the training input range
INPUT_SHIFTS = (-0.15, -0.05, 0.05, 0.15)
# a test run must last this many of the model's slowest time constants (its memory)
MEMORY_LAGS = 3.0
MIN_RUN_SAMPLES = 10
# v3 causes that are not a difference between sessions (module docstring, step 3)
LEFT_OUT = ("slow_drift",)


@dataclass
class RunLine:
    """One test run: RMS errors [units of y] of the training model as it is, held out with the
    session offset, and held out with the named correction."""

    name: str
    samples: int
    model_rmse: float
    offset_rmse: float
    corrected_rmse: float

    def as_json(self) -> dict[str, object]:
        return {
            "run": self.name,
            "samples": self.samples,
            "model_rmse": round(self.model_rmse, 6),
            "offset_rmse": round(self.offset_rmse, 6),
            "corrected_rmse": round(self.corrected_rmse, 6),
        }


@dataclass
class CrossRunsResult:
    """What the training runs' model gets wrong on the test runs."""

    cause: str  # a correction's name or "none"
    reason: str
    corrections: dict[str, HeldOut]  # each against the session offset (session_drift: against nothing)
    level: float  # per-correction test level (alpha / number of corrections)
    holdout: str
    train_names: list[str]
    test: RunSet  # the test runs (y, clock, run labels)
    model_prediction: NDArray[np.float64]  # the training model on the test runs [units of y]
    corrected_prediction: NDArray[np.float64]  # held out, with the named correction (or the offset)
    train_rmse: float
    per_run: list[RunLine]
    lag_s: float
    notes: list[str] = field(default_factory=list)
    seconds: float = 0.0
    cpu_seconds: float = 0.0

    @property
    def gain(self) -> float:
        """Held-out gain (fraction) of the named correction over the training model with the offset."""
        return self.corrections[self.cause].gain if self.cause in self.corrections else 0.0

    def as_json(self) -> dict[str, object]:
        named = self.corrections.get(self.cause)
        return {
            "method": "v3-crossrun",
            "cause": self.cause,
            "gain": round(self.gain, 4),
            "interval_90": [round(v, 4) for v in named.interval] if named is not None else None,
            "reason": self.reason,
            "level": round(self.level, 6),
            "p_values": {c: round(h.clark_west_p, 6) for c, h in self.corrections.items()},
            "corrections": {c: h.as_json() for c, h in self.corrections.items()},
            "holdout": self.holdout,
            "train": self.train_names,
            "test": self.test.names,
            "train_rmse": round(self.train_rmse, 6),
            "per_run": [line.as_json() for line in self.per_run],
            "output_lag_s": round(self.lag_s, 6),
            "notes": self.notes,
        }


def _subset(rs: RunSet, keep: NDArray[np.bool_]) -> RunSet:
    """The runs of ``rs`` whose rows ``keep`` marks (whole runs), renumbered from 0, clock from 0."""
    labels = np.unique(rs.run[keep])
    run = np.searchsorted(labels, rs.run[keep]).astype(np.int64)
    clock = rs.clock[keep]
    return RunSet(
        rs.t[keep],
        clock - clock[0],
        rs.u[keep],
        rs.y[keep],
        run,
        rs.dt,
        [rs.names[i] for i in labels],
        {c: v[keep] for c, v in rs.columns.items()},
    )


def _identified(rs: RunSet, nodes: NDArray[np.float64], train: NDArray[np.bool_], lag: float, rules: Rules) -> Baseline:
    """M0 with output lag ``lag`` [s], its weights fitted on the ``train`` rows only, evaluated on every row."""
    smooth = node_differences(rules.preisach_levels)
    smooth = smooth.T @ smooth
    ones = np.ones((rs.y.size, 1))
    lagged_nodes = run_lowpass(rs, nodes, lag)
    theta = ridge_fit(np.hstack([lagged_nodes, ones])[train], rs.y[train], smooth, rules.node_ridge)
    x = nodes @ theta[:-1]
    xc = (x - x[train].mean()) / (float(np.std(x[train])) or 1.0)
    lagged_x = run_lowpass(rs, x, lag)
    tangents = np.column_stack(
        [
            run_lowpass(rs, x, 1.5 * lag + rs.dt) - lagged_x,
            run_lowpass(rs, run_gradient(rs, x), lag) * rs.dt,
            run_lowpass(rs, xc**2, lag),
            run_lowpass(rs, xc**3, lag),
        ]
        + [run_lowpass(rs, x, tau) - lagged_x for tau in rules.nuisance_lags_s if tau != lag]
    )
    nuisance = np.hstack([lagged_nodes, tangents, ones])
    coef = ridge_fit(nuisance[train], rs.y[train], smooth, rules.node_ridge)
    return Baseline(nuisance, smooth, x, nuisance @ coef, lag)


def _on_training_range(rs: RunSet, train: NDArray[np.bool_], shift: float = 0.0) -> RunSet:
    """``rs`` with the test rows' input shifted by ``shift`` and clipped to the training input
    range (so the Everett grid :func:`preisach_nodes` builds is the training runs' grid)."""
    lo, hi = float(rs.u[train].min()), float(rs.u[train].max())
    u = np.where(train, rs.u, np.clip(rs.u - shift, lo, hi))
    return replace(rs, u=u)


def _refuse_short_tests(test: RunSet, lag_s: float, rules: Rules) -> None:
    """A test run must outlast the model's memory: :data:`MEMORY_LAGS` times its slowest filter
    (the output lag or the longest nuisance lag), which each run starts settled at its first sample."""
    slowest = max((lag_s, *rules.nuisance_lags_s))
    need = max(MIN_RUN_SAMPLES, int(np.ceil(MEMORY_LAGS * slowest / test.dt)))
    for (a, b), name in zip(test.bounds(), test.names):
        if b - a < need:
            raise DataError(
                f"{name}: test run of {b - a} samples is shorter than the model's memory ({need} samples: "
                f"{MEMORY_LAGS:g} x its slowest lag of {slowest:g} s at {1 / test.dt:.3g} Hz); record a longer run "
                "or leave it out of --test"
            )


def cross_runs(
    train_runs: list[Measurement], test_runs: list[Measurement], *, rules: Rules = RULES, seed: int = 0
) -> CrossRunsResult:
    """The model identified on ``train_runs`` together, checked on ``test_runs`` (module docstring)."""
    wall, cpu = time.perf_counter(), time.process_time()
    if not train_runs or not test_runs:
        raise DataError("cross-run diagnosis needs at least one --train run and one --test run")
    # both sides get the rows one v3 record gets
    rs = run_set(train_runs + test_runs, 2 * rules.max_rows, rules.min_samples)
    train = rs.run < len(train_runs)
    if int(train.sum()) < rules.min_samples:
        raise DataError(
            f"the training runs hold {int(train.sum())} samples; identify on at least {rules.min_samples} "
            "(give more --train runs)"
        )
    notes = list(rs.notes)
    lo, hi = float(rs.u[train].min()), float(rs.u[train].max())
    outside = float(np.mean((rs.u[~train] < lo) | (rs.u[~train] > hi)))
    if outside > 0:
        notes.append(
            f"{outside:.2%} of the test input lies outside the training range {lo:.4g}..{hi:.4g}; the model "
            "saturates there (record the training runs over the full range)"
        )
    nodes, node_notes = preisach_nodes(_on_training_range(rs, train), rules.preisach_levels)
    notes += node_notes
    smooth = node_differences(rules.preisach_levels)
    train_rs = _subset(rs, train)
    lag = fit_baseline(
        train_rs, nodes[train], smooth.T @ smooth, rules.output_lags_s, rules.node_ridge, rules.nuisance_lags_s
    ).lag_s
    model = _identified(rs, nodes, train, lag, rules)
    test = _subset(rs, ~train)
    _refuse_short_tests(test, lag, rules)
    yhat = model.prediction[~train]
    residual = replace(test, y=test.y - yhat)
    groups = _correction_groups(rs, train, test, model, lag, rules)
    masks, holdout = holdout_folds(test, rules)
    n = test.y.size
    none, ones = np.zeros((n, 1)), np.ones((n, 1))
    no_nodes = np.zeros((0, 0))
    corrections: dict[str, HeldOut] = {}
    for name, group in groups.items():
        base = none if name == OFFSET else ones
        row = CAUSES.get(name)
        column = test.columns.get(row.column) if row is not None and row.column else None
        corrections[name] = held_out(
            residual, base, no_nodes, group, masks, rules.node_ridge, np.random.default_rng(seed), column
        )
    level = rules.alpha / len(corrections)
    cause, reason = _verdict(corrections, level)
    offset = corrections[OFFSET]
    chosen = corrections.get(cause, offset)
    corrected = yhat + chosen.ext_prediction
    per_run = [
        RunLine(
            Path(name).name,
            b - a,
            _rms(yhat[a:b] - test.y[a:b]),
            _rms(yhat[a:b] + offset.ext_prediction[a:b] - test.y[a:b]),
            _rms(corrected[a:b] - test.y[a:b]),
        )
        for (a, b), name in zip(test.bounds(), test.names)
    ]
    out = CrossRunsResult(
        cause,
        reason,
        corrections,
        level,
        holdout,
        [m.source for m in train_runs],
        test,
        yhat,
        corrected,
        _rms(model.prediction[train] - rs.y[train]),
        per_run,
        lag,
        notes,
    )
    out.seconds, out.cpu_seconds = time.perf_counter() - wall, time.process_time() - cpu
    return out


def _rms(e: NDArray[np.float64]) -> float:
    return float(np.sqrt(np.mean(e**2))) if e.size else float("nan")


def _correction_groups(
    rs: RunSet, train: NDArray[np.bool_], test: RunSet, model: Baseline, lag: float, rules: Rules
) -> dict[str, NDArray[np.float64]]:
    """Each correction's regressors on the test rows (all fitted beside a session offset)."""
    yhat = model.prediction[~train]
    n = test.y.size
    span = float(np.ptp(rs.u[train])) or 1.0
    shifted = []
    for share in INPUT_SHIFTS:
        nodes, _ = preisach_nodes(_on_training_range(rs, train, share * span), rules.preisach_levels)
        moved = _identified(rs, nodes, train, lag, rules).prediction[~train]
        shifted.append((moved - yhat) / share)
    test_base = Baseline(model.nuisance[~train], model.smoothness, model.x[~train], yhat, lag)
    groups: dict[str, NDArray[np.float64]] = {
        OFFSET: np.ones((n, 1)),
        "gain_change": (yhat - yhat.mean())[:, None],
        "input_drift": np.column_stack(shifted),
    }
    groups.update({c: g for c, g in cause_groups(test, test_base, rules).items() if c not in LEFT_OUT})
    groups["hysteresis_change"] = model.nuisance[~train][:, :-1]
    return {name: g for name, g in groups.items() if g.shape[1]}


def _verdict(corrections: dict[str, HeldOut], level: float) -> tuple[str, str]:
    """The named correction and the reason in one sentence (module docstring, step 4)."""

    def passes(h: HeldOut) -> bool:
        return h.clark_west_p <= level and h.interval[0] > 0.0

    offset = corrections[OFFSET]
    richer = [c for c, h in corrections.items() if c != OFFSET and passes(h)]
    physical = [c for c in richer if c != "hysteresis_change"]
    pool = physical or richer
    offset_text = (
        f"an offset alone lowers the training model's held-out RMS error on the test runs from "
        f"{offset.base_rmse:.3g} to {offset.ext_rmse:.3g} ({offset.gain:.1%})"
    )
    if not pool:
        if passes(offset):
            return OFFSET, f"the relation moved between the sessions: {offset_text}; no richer correction adds to it"
        best = max(corrections, key=lambda c: corrections[c].gain)
        h = corrections[best]
        return "none", (
            f"no correction predicts held-out test rows better at level {level:.3g}: the best, {best}, gains "
            f"{h.gain:+.1%} (90 % interval {h.interval[0]:+.1%} to {h.interval[1]:+.1%}, Clark-West p = "
            f"{h.clark_west_p:.2g}); the training runs' model holds on the test runs"
        )
    best = max(pool, key=lambda c: corrections[c].gain)
    h = corrections[best]
    reason = (
        f"{best} lowers the held-out RMS error on the test runs from {h.base_rmse:.3g} (training model plus an "
        f"offset) to {h.ext_rmse:.3g} ({h.gain:.1%}, 90 % interval {h.interval[0]:.1%} to {h.interval[1]:.1%}, "
        f"Clark-West p = {h.clark_west_p:.2g} at level {level:.3g}); {offset_text}"
    )
    if best == "hysteresis_change":
        reason += "; no single physical correction explains the difference: the loop itself differs"
    others = [c for c in pool if c != best]
    if others:
        reason += f"; also passing: {', '.join(others)}"
    return best, reason
