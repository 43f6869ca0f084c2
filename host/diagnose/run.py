"""The diagnosis: baseline vs physically motivated extensions on blocked held-out data.

1. The baseline and each extension (one physical term, :mod:`host.diagnose.candidates`) are
   identified on the whole record after the first sample where the memory is known (or from
   the first sample with an assumed state when that leaves too few: :func:`known_memory`):
   hysteresis jointly with the term.
2. That record is cut into ``folds * blocks_per_fold`` contiguous blocks, dealt to the folds in
   turn (:func:`host.diagnose.folds.holdout_masks`). For each fold every model's gain, offset and
   term coefficients are refitted on the other folds' rows and scored (RMSE) on the held-out rows
   it can be judged on; a candidate's score per fold is its relative reduction of held-out RMSE
   against the baseline on the same rows. A measured column's terms are also scored with nine
   shifted copies of the column in its place (the surrogate null of that cause), and so is the
   ramp in time of ``slow_drift`` when the drift would be named.
3. :func:`host.diagnose.decide.choose` names the cause with calibrated evidence, or ``none``
   with the reason; :func:`host.diagnose.decide.with_signatures` then applies the two-stage rule:
   a residual signature (:mod:`host.diagnose.signatures`, surrogate-calibrated) nominates a cause
   that the held-out gain confirms, and :func:`host.diagnose.decide.distinct` turns a cause that
   another term explains as well into ``none`` ("cannot tell X from Y").

Records longer than :data:`MAX_WORK_SAMPLES` are decimated (block means, an anti-alias filter)
with a warning; BLAS threads are sized to the problem (small least-squares problems run fastest
on one thread, and extra threads only fight a busy machine).
"""

from __future__ import annotations

import sys
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from edge.errors import DataError
from host.data import Measurement
from host.diagnose.candidates import (
    CAUSES,
    COLUMNS,
    OBSERVED_CAUSES,
    Context,
    Design,
    baseline,
    design,
    observed,
    shifted_copies,
    slow_drift,
)
from host.diagnose.decide import (
    BLOWUP_RATIO,
    GAIN_FLOOR,
    CandidateScore,
    DecisionInputs,
    column_floor,
    detection_limit,
    drift_would_be_named,
)
from host.diagnose.evidence import baseline_evidence
from host.diagnose.features import actuator_input, branch_offset, preisach_rows, smoothed_rate
from host.diagnose.folds import BLOCKS_PER_FOLD, MIN_BLOCK_SAMPLES, check_folds, holdout_masks, noise_floor
from host.diagnose.hammerstein import FittedModel, fit_hammerstein, rmse
from host.diagnose.signatures import signatures
from host.identify.common import MemoryStart, memory_start

__all__ = ["CAUSES", "Diagnosis", "detection_limits", "diagnose", "held_out_score", "limit_sentence", "prepare"]

# first-order actuator (valve + mechanics) lag before the hysteresis, part of the baseline's
# dynamics (PAMInertial: a PAM is a first-order lag plus a dead time); up to 250 ms, so that a plant
# with more lag than a valve alone does not leave a lag a short dead time then "explains".
# Negative: the recorded input is the driving pressure read through a first-order lag of its own
# (a snubber or an RC filter on the transducer), undone by its inverse; at least half a sample.
# A rate weight's branch x speed term is such a lead to first order: without it rate dependence
# was named on effect-free records of a braid read through a 4-15 ms snubber (+38 %; +5 % with it)
ACTUATOR_LAGS_S = (-0.025, -0.012, -0.006, 0.0, 0.02, 0.05, 0.1, 0.17, 0.25)
# a lead is a claim about the rig (the notes state it): it must lower the baseline's whole-record
# RMSE by this share against the best lag. Chosen on near-ties (0.2-3.6 %) it turned three load
# and temperature effects injected into real piezo records into none or slow_drift
LEAD_MARGIN = 0.05
MIN_SAMPLES = 400
# Everett grid intervals of the baseline: 12 left 2-5x the effect sizes of foreign plants as model
# error (tuning plants); 16 halves it at 1.7x the cost
PREISACH_LEVELS = 16
MAX_WORK_SAMPLES = 30_000
# the dead-time signature at or below this p asks for a dead time screened jointly with the
# shorter actuator lags (the baseline's lag may have absorbed it); cheaper than always doing so
JOINT_DELAY_P = 0.2
# a hold's first second(s) are the baseline's own settling, not drift
SETTLE_S = 1.0
LARGE_PROBLEM_CELLS = 20_000_000  # rows x Everett cells above which a second BLAS thread pays
# shifted copies of each measured column: its surrogate p-value is at best 1 / (this + 1)
COLUMN_SURROGATES = 9


class DecimatedWarning(UserWarning):
    """The record was longer than the diagnosis needs and was decimated."""


@dataclass
class Diagnosis:
    cause: str
    scores: dict[str, float]
    baseline_rmse: float
    extended_rmse: float
    gain: float
    holdout: str
    extended_model: dict[str, object]
    reason: str
    decided_by: str
    confidence: dict[str, object]
    fold_gains: dict[str, list[float]]
    column_surrogates: dict[str, dict[str, object]]
    baseline_full: FittedModel
    extended_full: FittedModel | None
    start_index: int
    evidence: dict[str, object]
    context: Context
    notes: list[str]
    memory_assumed: bool = False  # the hysteresis state at the first sample was assumed (see notes)
    decision: DecisionInputs | None = None  # what the verdict was decided from (for replaying a rule)

    def as_json(self) -> dict[str, object]:
        """The result as plain JSON values: non-finite numbers (a fold with no rows to judge, a
        fit that failed) become null, so that any strict JSON parser reads it."""
        fields = finite_or_null(self._fields())
        assert isinstance(fields, dict)
        return fields

    def _fields(self) -> dict[str, object]:
        return {
            "cause": self.cause,
            "reason": self.reason,
            "decided_by": self.decided_by,
            "confidence": self.confidence,
            "scores": self.scores,
            "fold_gains": self.fold_gains,
            "column_surrogates": self.column_surrogates,
            "baseline_rmse": self.baseline_rmse,
            "extended_rmse": self.extended_rmse,
            "gain": self.gain,
            "holdout": self.holdout,
            "extended_model": self.extended_model,
            "signatures": self.evidence.get("signatures", {}),
            "notes": self.notes,
            "start_index": self.start_index,
            "memory_assumed": self.memory_assumed,
        }


def finite_or_null(value: object) -> object:
    """``value`` with every non-finite float (nan, inf) replaced by None, recursively."""
    if isinstance(value, dict):
        return {k: finite_or_null(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [finite_or_null(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return float(value) if np.isfinite(value) else None
    return value


def decimated(m: Measurement, limit: int = MAX_WORK_SAMPLES) -> tuple[Measurement, str | None]:
    """``m`` itself, or block means of ``q`` samples when it is longer than ``limit``."""
    q = int(np.ceil(len(m) / limit))
    if q <= 1:
        return m, None
    n = len(m) // q * q

    def mean(v: NDArray[np.float64]) -> NDArray[np.float64]:
        return v[:n].reshape(-1, q).mean(axis=1)

    out = Measurement(
        m.t[:n:q].copy(), mean(m.u), mean(m.y), {k: mean(v) for k, v in m.extras.items()}, m.source, list(m.notes)
    )
    note = (
        f"{len(m)} samples at {1 / m.dt:g} Hz decimated by {q} (block means) to {len(out)} samples at "
        f"{1 / out.dt:g} Hz; dead times shorter than {3 * out.dt:.3g} s cannot be resolved"
    )
    return out, note


def decimated_with_warning(m: Measurement) -> tuple[Measurement, list[str]]:
    """:func:`decimated`, warning once (:class:`DecimatedWarning`) when it decimates; also
    returns the note for the diagnosis' ``notes``."""
    m, note = decimated(m)
    if not note:
        return m, []
    warnings.warn(note, DecimatedWarning, stacklevel=3)
    return m, [note]


def known_memory(
    u: NDArray[np.float64], source: str, assume_state: bool = True, needed: int = MIN_SAMPLES
) -> tuple[MemoryStart, list[str]]:
    """Where the hysteresis memory of input ``u`` is known (:func:`memory_start`), or, when ``u``
    reaches an end of its range too late to leave ``needed`` samples after it (a sine of growing
    amplitude, an excerpt of a longer run), the first sample with an assumed state: the input
    rose from the record's minimum to its first value (the actuator at rest, vented or at its
    lowest drive, before the record). The note says so: the first samples' verdict carries that
    assumption. Without ``assume_state`` such a record is refused (:class:`DataError`)."""
    start = memory_start(u)
    if u.size - start.index >= needed:
        return start, []
    if not assume_state:
        raise DataError(
            f"{source}: the input reaches the end of its range only at sample {start.index}; fewer than "
            f"{needed} samples (what the folds need, at least {MIN_SAMPLES}) remain with a known hysteresis state"
        )
    note = (
        f"the input reaches the end of its range only at sample {start.index} of {u.size}, so the "
        "hysteresis state at the start is assumed: the input rose from the record's minimum "
        f"({float(u.min()):g}) to its first value ({float(u[0]):g}); start the record at rest "
        "and sweep the full range first to diagnose without this assumption"
    )
    return MemoryStart(0, "ascending"), [note]


def samples_needed(folds: int, blocks_per_fold: int = BLOCKS_PER_FOLD) -> int:
    """Samples after the memory start that ``folds`` folds of ``blocks_per_fold`` blocks need
    (:data:`MIN_BLOCK_SAMPLES` each), and at least :data:`MIN_SAMPLES`."""
    return max(MIN_SAMPLES, folds * blocks_per_fold * MIN_BLOCK_SAMPLES)


def prepare(
    m: Measurement, levels: int, assume_state: bool = True, needed: int = MIN_SAMPLES
) -> tuple[Context, int, list[str]]:
    """Validate the record and compute the features shared by every fold; also returns the first
    sample used and the notes on what was assumed (:func:`known_memory`; ``needed``: the samples
    the folds need after the memory start)."""
    if len(m) < MIN_SAMPLES:
        raise DataError(f"{m.source}: {len(m)} samples is too short to diagnose; record at least {MIN_SAMPLES}")
    if np.ptp(m.u) <= 1e-9 * max(1.0, float(np.abs(m.u).max())):
        raise DataError(f"{m.source}: the input u is constant; a diagnosis needs the actuator to move")
    if np.ptp(m.y) <= 1e-9 * max(1.0, float(np.abs(m.y).max())):
        raise DataError(
            f"{m.source}: the output y is constant ({m.y[0]:g}); check the sensor wiring or the column "
            "mapping, there is nothing to diagnose"
        )
    start, notes = known_memory(m.u, m.source, assume_state, needed)
    sl = slice(start.index, None)
    extras = {k: v[sl] for k, v in m.extras.items() if k in ("load", "temperature")}
    rows_after = partial(rows_after_filter, m.u, start, levels)
    lag_rows = {lag: rows_after(partial(actuator_input, dt=m.dt, lag_s=lag)) for lag in actuator_lags(m.dt)}
    ctx = Context(
        m.t[sl],
        m.u[sl],
        m.y[sl],
        lag_rows,
        smoothed_rate(m.u, m.dt)[sl],
        branch_offset(m.u, start)[sl],
        extras,
        m.dt,
        output_rate=smoothed_rate(m.y, m.dt)[sl],
        rows_after=rows_after,
    )
    return ctx, start.index, notes


def rows_after_filter(
    u: NDArray[np.float64],
    start: MemoryStart,
    levels: int,
    input_filter: Callable[[NDArray[np.float64]], NDArray[np.float64]],
) -> NDArray[np.float32]:
    """Preisach rows (from ``start``) of the whole input ``u`` after ``input_filter``."""
    return preisach_rows(input_filter(u), start, levels)


def actuator_lags(dt: float) -> list[float]:
    """The actuator lags of :data:`ACTUATOR_LAGS_S` a record sampled every ``dt`` [s] can show:
    leads of at least half a sample."""
    return [lag for lag in ACTUATOR_LAGS_S if lag >= 0 or -lag >= 0.5 * dt]


def lead_notes(lag_s: float) -> list[str]:
    """What a negative actuator lag says about the rig (nothing for a lag)."""
    if lag_s >= 0:
        return []
    return [
        f"the output leads the recorded input: the baseline reads the input through the inverse of a "
        f"{-lag_s * 1e3:g} ms lag (a snubber or a filter on the pressure transducer; or an effect that makes "
        "the output lead, such as a term in du/dt, which this reading absorbs); a faster pressure reading at "
        "the muscle's port tells the two apart"
    ]


def choose_actuator_lag(ctx: Context) -> float:
    """The actuator lag (or input lead: negative) whose baseline fits the whole record best (one
    discrete setting shared by every candidate, so choosing it on all rows favours no candidate);
    a lead only when it lowers that error by :data:`LEAD_MARGIN` against the best lag."""
    every = np.ones(ctx.y.size, dtype=bool)
    errors = {}
    for lag in ctx.lag_rows:
        model, _ = fit_hammerstein("baseline", ctx.lag_rows[lag], ctx.y, every, ctx.dt)
        errors[lag] = rmse(model.prediction, ctx.y)
    best_lag = min((lag for lag in errors if lag >= 0), key=lambda lag: errors[lag])
    best = min(errors, key=lambda lag: errors[lag])
    return best if errors[best] <= (1.0 - LEAD_MARGIN) * errors[best_lag] else best_lag


def fit_baseline(ctx: Context) -> FittedModel:
    """The baseline on every row at ``ctx.lag_s``; sets ``ctx.x`` (the hysteresis output)."""
    every = np.ones(ctx.y.size, dtype=bool)
    model, ctx.x = fit_hammerstein("baseline", ctx.rows, ctx.y, every, ctx.dt)
    ctx.ar = model.ar
    model.extra["actuator_lag_s"] = ctx.lag_s
    return model


def _progress(total: int, enabled: bool | None):  # noqa: ANN202 - a tqdm bar
    from tqdm import tqdm

    tqdm.monitor_interval = 0  # no monitor thread: the bar lives in one call
    show = sys.stderr.isatty() if enabled is None else enabled
    return tqdm(total=total, desc="diagnose", unit="fit", file=sys.stderr, leave=False, disable=not show)


def diagnose(
    m: Measurement,
    *,
    folds: int = 4,
    blocks_per_fold: int = BLOCKS_PER_FOLD,
    levels: int = PREISACH_LEVELS,
    progress: bool | None = None,
    assume_state: bool = True,
) -> Diagnosis:
    """Run the diagnosis (see module docstring). ``progress``: a tqdm line on stderr (None: when
    stderr is a terminal). ``assume_state``: when the memory is known too late, diagnose from the
    first sample with an assumed state (:func:`known_memory`) rather than refuse."""
    m, notes = decimated_with_warning(m)
    threads = 1 if len(m) * (levels + 1) * (levels + 2) // 2 < LARGE_PROBLEM_CELLS else 2
    with threadpool_limits(limits=threads):
        return _diagnose(m, folds, blocks_per_fold, levels, progress, notes, assume_state)


def _fold_prediction(ctx: Context, d: Design, train: NDArray[np.bool_]) -> NDArray[np.float64] | None:
    """``d`` fitted on ``train`` and simulated over the record; None when the fit fails (a failed
    fit, not evidence)."""
    try:
        with np.errstate(all="ignore"):
            return d.fit(ctx, train).prediction
    except (np.linalg.LinAlgError, ValueError):
        return None


def _error(prediction: NDArray[np.float64] | None, y: NDArray[np.float64], rows: NDArray[np.bool_]) -> float:
    return float("inf") if prediction is None else rmse(prediction[rows], y[rows])


def _fold_errors(
    ctx: Context, designs: dict[str, Design | None], held: NDArray[np.bool_], base: NDArray[np.float64]
) -> dict[str, tuple[float, ...] | None]:
    """Per design, the held-out RMSE of the baseline (``base``: its prediction fitted on this
    fold's training rows) and of the design on the rows the design can be judged on (None: not
    available; nan: too few such rows). For each measured column also ``"<cause>|slow_drift"``:
    the baseline's, the column's and the drift's errors on the rows both can be judged on, so
    that the two are compared on the same rows. Each design is fitted once per fold."""
    train = ~held
    predictions: dict[str, NDArray[np.float64] | None] = {}
    out: dict[str, tuple[float, ...] | None] = {}
    for name, d in designs.items():
        if d is None:
            out[name] = None
            continue
        rows = d.scored(train, held)
        if rows.sum() < MIN_BLOCK_SAMPLES:
            out[name] = (np.nan, np.nan)
            continue
        predictions[name] = _fold_prediction(ctx, d, train)
        out[name] = (rmse(base[rows], ctx.y[rows]), _error(predictions[name], ctx.y, rows))
    drift = designs.get("slow_drift")
    for cause in OBSERVED_CAUSES:
        d = designs.get(cause)
        if d is None or drift is None or cause not in predictions or "slow_drift" not in predictions:
            continue
        rows = d.scored(train, held) & drift.scored(train, held)
        if rows.sum() >= MIN_BLOCK_SAMPLES:
            out[f"{cause}|slow_drift"] = (
                rmse(base[rows], ctx.y[rows]),
                _error(predictions[cause], ctx.y, rows),
                _error(predictions["slow_drift"], ctx.y, rows),
            )
    return out


def _surrogate_gains(
    ctx: Context,
    cause: str,
    column: NDArray[np.float64],
    make: Callable[[NDArray[np.float64]], Design | None],
    masks: list[NDArray[np.bool_]],
    base_folds: list[NDArray[np.float64]],
) -> list[float]:
    """Mean held-out gains of ``cause``'s terms with ``column`` replaced by shifted copies of
    itself (:func:`shifted_copies`; ``make`` builds the design from a copy): what a column of the
    same shape gains by chance on this record, structural error and slow drifts included. Each
    copy is scored by the candidate's own rules (failed folds left out); a copy that is constant
    or whose fit fails on more than one fold is drawn again. ``base_folds``: the baseline's
    prediction per fold."""
    rng = np.random.default_rng(0)
    out: list[float] = []
    for _ in range(4 * COLUMN_SURROGATES):  # bounded redraws
        if len(out) == COLUMN_SURROGATES:
            break
        surrogate = make(shifted_copies(column, 1, rng)[0])
        if surrogate is None:
            continue
        score = held_out_score(ctx, cause, surrogate, masks, base_folds)
        if not score.failed and score.gains:
            out.append(score.mean)
    return out


def held_out_score(
    ctx: Context,
    name: str,
    d: Design,
    masks: list[NDArray[np.bool_]],
    base_folds: list[NDArray[np.float64]],
) -> CandidateScore:
    """``d``'s held-out record over the folds (``masks``: held-out rows per fold; ``base_folds``:
    the baseline's prediction fitted on each fold's training rows), by the candidates' own rules:
    a fold with too few rows ``d`` can be judged on is skipped, a blown-up fit is a failed fold."""
    score = CandidateScore(name)
    for held, base in zip(masks, base_folds):
        pair = _fold_errors(ctx, {name: d}, held, base)[name]
        if pair is not None and np.isfinite(pair[0]):
            score.add(pair[0], pair[1])
    return score


def _column_nulls(
    ctx: Context,
    designs: dict[str, Design | None],
    masks: list[NDArray[np.bool_]],
    base_folds: list[NDArray[np.float64]],
) -> dict[str, list[float]]:
    """Surrogate gains (:func:`_surrogate_gains`) of each measured column present."""
    out: dict[str, list[float]] = {}
    for cause in OBSERVED_CAUSES:
        column = ctx.extras.get(COLUMNS[cause])
        if designs.get(cause) is not None and column is not None:
            out[cause] = _surrogate_gains(ctx, cause, column, partial(observed, ctx, cause), masks, base_folds)
    return out


def _drift_null(ctx: Context, masks: list[NDArray[np.bool_]], base_folds: list[NDArray[np.float64]]) -> list[float]:
    """Surrogate gains of ``slow_drift``: the ramp in time replaced by shifted mirrored copies of
    itself (tents and slopes with a kink, placed at random). A structural error that changes
    across a protocol (growing amplitudes, a level held longer at the end) is fitted by such
    slow shapes of time as well as by the ramp; a drift is monotone in time and fits the ramp
    better than all nine of them (surrogate p <= 0.1)."""
    return _surrogate_gains(ctx, "slow_drift", ctx.t, partial(slow_drift, ctx), masks, base_folds)


def _diagnose(
    m: Measurement,
    folds: int,
    blocks_per_fold: int,
    levels: int,
    progress: bool | None,
    notes: list[str],
    assume_state: bool,
) -> Diagnosis:
    ctx, start_index, assumed = prepare(m, levels, assume_state, samples_needed(folds, blocks_per_fold))
    notes = notes + assumed
    n = ctx.y.size
    check_folds(folds, n, blocks_per_fold)
    masks = holdout_masks(n, folds, blocks_per_fold)
    with _progress(2 + len(CAUSES), progress) as bar:
        ctx.lag_s = choose_actuator_lag(ctx)
        notes += lead_notes(ctx.lag_s)
        baseline_full = fit_baseline(ctx)
        found = signatures(
            ctx.y - baseline_full.prediction,
            ctx.y,
            baseline_full.prediction,
            ctx.u,
            ctx.dt,
            settle_s=SETTLE_S + 5.0 * max(ctx.lag_s, 0.0),
        )
        delay_signature = found.get("transport_delay")
        ctx.joint_delay = delay_signature is not None and delay_signature.p_value <= JOINT_DELAY_P
        bar.update()
        base_design = baseline(ctx, baseline_full)
        designs: dict[str, Design | None] = {}
        for cause in CAUSES:
            with np.errstate(all="ignore"):
                designs[cause] = design(ctx, cause)
            bar.update()
        base_folds = [base_design.fit(ctx, ~held).prediction for held in masks]
        fold_errors = [_fold_errors(ctx, designs, held, base) for held, base in zip(masks, base_folds)]
        null_gains = _column_nulls(ctx, designs, masks, base_folds)
        bar.update()
    scores = {c: CandidateScore(c, null_gains=null_gains.get(c, [])) for c in CAUSES}
    base_scores: dict[str, list[float]] = {c: [] for c in CAUSES}
    ext_scores: dict[str, list[float]] = {c: [] for c in CAUSES}
    for errors in fold_errors:
        for cause in CAUSES:
            pair = errors[cause]
            if pair is None:
                scores[cause].add(1.0, None)
            elif not np.isfinite(pair[0]):  # too few rows it can be judged on in this fold
                scores[cause].all_gains.append(float("nan"))
            else:
                scores[cause].add(pair[0], pair[1])
                if np.isfinite(pair[1]):
                    base_scores[cause].append(pair[0])
                    ext_scores[cause].append(pair[1])
        for cause in OBSERVED_CAUSES:
            shared = errors.get(f"{cause}|slow_drift")
            margin = None
            if shared is not None:
                base_rmse, column_rmse, drift_rmse = shared
                if max(column_rmse, drift_rmse) <= BLOWUP_RATIO * base_rmse:  # both fits held
                    margin = (drift_rmse - column_rmse) / base_rmse
            scores[cause].drift_margins.append(margin)
    noise = noise_floor(ctx.y)
    if drift_would_be_named(scores, noise):  # only then is the drift's surrogate null worth its cost
        with _progress(1, progress) as bar:  # nine joint fits: seconds, said on the progress line
            bar.set_description("diagnose: drift surrogates")
            scores["slow_drift"].null_gains = _drift_null(ctx, masks, base_folds)
            bar.update()
    time_correlation = {
        name: float(np.corrcoef(values, ctx.t)[0, 1]) for name, values in ctx.extras.items() if np.ptp(values) > 0
    }
    decision = DecisionInputs(scores, noise, time_correlation, found)
    verdict = decision.verdict()
    cause = verdict.cause
    limits = detection_limits(ctx, masks, base_folds, noise, time_correlation)
    chosen = designs.get(cause) if cause != "none" else None
    extended_full = chosen.fit(ctx, np.ones(n, dtype=bool)) if chosen is not None else None
    evidence = baseline_evidence(baseline_full.prediction - ctx.y, ctx.u, ctx.rate, ctx.extras, ctx.dt)
    evidence["noise_floor"] = noise
    evidence["signatures"] = {c: g.as_json() for c, g in found.items()}
    reason = verdict.reason
    if cause == "none" and verdict.decided_by == "no candidate passed":  # not when two terms tie
        whiteness = evidence["whiteness"]
        if whiteness["p_value"] < 0.01:  # type: ignore[index]
            reason += (
                f"; the baseline's residual is not white (Ljung-Box p = {whiteness['p_value']:.1g}), so something "  # type: ignore[index]
                "is left that none of the extensions captures"
            )
        else:
            reason += "; the baseline's residual is white: what remains looks like noise"
        reason += "; " + limit_sentence(limits)
    # the baseline's held-out error on the rows of the named cause (every row when none is named:
    # the rate-dependence term is judged on all held-out rows)
    memory = "its hysteresis state assumed, see notes" if assumed else "where the hysteresis memory is known"
    reference = cause if cause != "none" else "rate_dependence"
    baseline_rmse = float(np.mean(base_scores[reference])) if base_scores[reference] else float("nan")
    extended_rmse = float(np.mean(ext_scores[cause])) if cause != "none" else baseline_rmse
    return Diagnosis(
        cause=cause,
        scores={c: s.mean for c, s in scores.items()},
        baseline_rmse=baseline_rmse,
        extended_rmse=extended_rmse,
        gain=float(max(0.0, 1.0 - extended_rmse / baseline_rmse)) if cause != "none" else 0.0,
        holdout=(
            f"{folds * blocks_per_fold} contiguous blocks in time after sample {start_index} ({memory}), dealt "
            f"to {folds} folds in turn ({blocks_per_fold} blocks of "
            f"{n * ctx.dt / (folds * blocks_per_fold):.0f} s each); each model's hysteresis identified on the "
            "whole record, its dynamics and term coefficients fitted on the other folds' blocks, simulated over "
            "the whole record and scored on the held-out blocks; RMSE averaged over the folds"
        ),
        extended_model=_describe(extended_full, ctx) if extended_full else {"name": "baseline (no extension)"},
        reason=reason,
        decided_by=verdict.decided_by,
        confidence={**verdict.confidence, "detection_limit": limits},
        fold_gains={c: s.all_gains for c, s in scores.items()},
        column_surrogates={
            c: {"p_value": s.surrogate_p, "mean_gains": s.null_gains} for c, s in scores.items() if s.null_gains
        },
        baseline_full=baseline_full,
        extended_full=extended_full,
        start_index=start_index,
        evidence=evidence,
        context=ctx,
        notes=notes,
        memory_assumed=bool(assumed),
        decision=decision,
    )


def detection_limits(
    ctx: Context,
    masks: list[NDArray[np.bool_]],
    base_folds: list[NDArray[np.float64]],
    noise: float,
    time_correlation: dict[str, float],
) -> dict[str, float | None]:
    """The smallest RMS [units of y] of an effect's own part (what the baseline cannot absorb) that
    could be named on this record (:func:`host.diagnose.decide.detection_limit`), from the
    baseline's held-out RMSE on every held-out row (``baseline_rmse``): for a dynamic term, and
    for a measured column at its floor (:func:`host.diagnose.decide.column_floor` of its
    ``time_correlation``; None without a load or temperature column that moves); with the
    output's range (peak to peak) to read them against."""
    base = float(np.mean([rmse(b[held], ctx.y[held]) for held, b in zip(masks, base_folds)]))
    floors = [column_floor(r) for name, r in time_correlation.items() if name in COLUMNS.values()]
    return {
        "dynamic_term": detection_limit(base, noise, GAIN_FLOOR),
        "measured_column": detection_limit(base, noise, min(floors)) if floors else None,
        "baseline_rmse": base,
        "output_range": float(np.ptp(ctx.y)),
    }


def limit_sentence(limits: dict[str, float | None]) -> str:
    """What :func:`detection_limits` means for a ``none`` that no candidate passed, in one clause."""
    dynamic, column, span = limits["dynamic_term"], limits["measured_column"], limits["output_range"]
    assert dynamic is not None and span is not None
    if not np.isfinite(dynamic):
        return "the baseline's error is at the noise floor: no effect could be told from noise on this record"
    through_column = f", {column:.3g} through a load or temperature column" if column is not None else ""
    return (
        "to be named here, an effect would have to leave an error of its own (one the rate-independent "
        f"model cannot absorb) of at least {dynamic:.3g} RMS in y's units ({dynamic / (span or 1.0):.1%} of "
        f"y's peak-to-peak range){through_column}; smaller effects may be present"
    )


TERMS = {
    "rate_dependence": "rate dependence: velocity-squared friction (y trails the rate-independent output by "
    "alpha v|v|, form 0), a rate-dependent hysteresis weight (loop width and stroke scaled by the input "
    "speed, form 1) or a payload on the muscle's pressure-dependent stiffness (y'' = w(p)^2 (x - y) - "
    "2 zeta w(p) y', w(p)^2 = w_top^2 (p_n + floor) / (1 + floor), form 2)",
    "creep": "creep spectrum: first-order relaxations of the hysteresis output at 1-64 s, shares of one sign, "
    "y gets sum e_i*(lowpass(x, tau_i) - x)",
    "transport_delay": "dead time before the hysteresis: x(k - d), or x(k - d_rise) while the input rises and "
    "x(k - d_fall) while it falls",
    "load_dependence": "load terms: y gets e1*L + e2*L*x + e3*L*x^2 (curve) + e4*L*branch (loop width) + e5*L^2",
    "temperature_drift": "temperature terms: y gets e1*T + e2*T*x + e3*T*x^2 (curve) + e4*T*branch (loop width) "
    "+ e5*T^2, and f1*Tlag + f2*Tlag*x for T after each of a 3 s and a 10 s thermal lag",
    "output_lag": "mechanics after the hysteresis: a first-order lag, y gets lag(x, tau), or a payload on a "
    "fixed stiffness, y'' = w^2 (x - y) - 2 zeta w y'",
    "slow_drift": "slow drift in time no column explains: y gets e1*t + e2*t*x + e3*t*x^2 (curve) + e4*t*branch "
    "(loop width) + e5*t^2",
}


def _describe(model: FittedModel, ctx: Context) -> dict[str, object]:
    """A readable description of an extended model and its fitted parameters."""
    n_extra = len(model.columns)
    coefficients = model.exogenous[model.nb : model.nb + n_extra] if n_extra else np.zeros(0)
    return {
        "name": model.name,
        "structure": ("actuator lag" if ctx.lag_s >= 0 else "inverse input lag")
        + " + Preisach hysteresis + ARX(na, nb) + "
        + TERMS[model.name],
        "actuator_lag_s": ctx.lag_s,
        "na": model.na,
        "nb": model.nb,
        "ar_coefficients": [float(a) for a in model.ar],
        "extra_terms": {c: float(e) for c, e in zip(model.columns, coefficients)},
        **model.extra,
    }
