"""Diagnosis v3: calibrated conditional tests over one or more runs.

prepare -> baseline -> score -> decide -> explain:

1. prepare: the runs as one :class:`host.diagnose.runs.RunSet`, the input through the actuator
   lag chosen for the record (:mod:`host.diagnose.actuator`), and their Preisach rows;
2. baseline: M0, the nuisance space that is not an effect (:mod:`host.diagnose.nuisance`);
3. score: each cause's group tested conditionally on M0, marginal and unique, whitened and
   calibrated per record (:mod:`host.diagnose.conditional`);
4. decide: a cause is named when its unique test passes at its level (one family-wise alpha per
   record); causes that pass only jointly are "cannot tell X from Y"; a named dynamic cause whose
   statistic collapses with a richer rate-independent baseline is the baseline's class, not a
   cause (the robustness ladder); the named cause must predict held-out data, and further causes
   are confirmed held out one after another beyond it (:func:`further_causes`);
5. explain: the held-out gain of the named extension (:mod:`host.diagnose.heldout`) and one
   paragraph of reason.

Every threshold is in :class:`host.diagnose.rules.Rules`.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import NDArray
from threadpoolctl import threadpool_limits

from host.data import Measurement
from host.diagnose.actuator import with_actuator
from host.diagnose.composite import class_nuisance, null_classes, simulated_records, unrestricted_residual
from host.diagnose.conditional import GroupTest, column_copies, group_tests, whitened
from host.diagnose.groups import branch_of, cause_groups, column_group
from host.diagnose.heldout import HeldOut, cluster_labels, held_out, holdout_folds
from host.diagnose.heldout_surrogates import HeldOutSurrogates, held_out_surrogates
from host.diagnose.nuisance import Baseline, ar_whitener, fit_baseline, with_nuisance
from host.diagnose.rules import CAUSES, RULES, Rules
from host.diagnose.runs import RunSet, preisach_basis, run_set


@dataclass
class DiagnosisV3:
    """What v3 found on a set of runs."""

    cause: str  # a name of :data:`CAUSES` or "none"
    also: list[str]
    cannot_tell: list[str]
    class_mismatch: bool
    reason: str
    tests: dict[str, GroupTest]
    heldout: HeldOut | None
    holdout: str
    runset: RunSet
    baseline: Baseline
    extended_prediction: NDArray[np.float64] | None  # full-record fit of the extension
    rules: Rules
    notes: list[str] = field(default_factory=list)
    not_confirmed: bool = False  # a cause passed its test on the record but not held out
    rejected: list[str] = field(default_factory=list)  # passed on the record, failed the ladder or held out
    seconds: float = 0.0
    cpu_seconds: float = 0.0
    # every held-out comparison beyond the baseline alone, in order (further causes are in ``further``)
    trials: dict[str, HeldOut] = field(default_factory=dict)
    # measured columns confirmed held out, against their copies' held-out gains (rules.column_heldout_surrogates)
    column_heldout: dict[str, HeldOutSurrogates] = field(default_factory=dict)
    # further causes confirmed held out, each beyond the baseline, the named cause and those before it
    further: list[tuple[str, HeldOut]] = field(default_factory=list)

    @property
    def gain(self) -> float:
        return self.heldout.gain if self.heldout is not None and self.cause != "none" else 0.0

    def as_json(self) -> dict[str, object]:
        return {
            "method": self.rules.version,
            "cause": self.cause,
            "gain": round(self.gain, 4),
            "also": self.also,
            # each beyond the baseline, the named cause and the causes listed before it
            "also_confirmed": [
                {"cause": g, "beyond": [self.cause] + [f for f, _ in self.further[:i]], **h.as_json()}
                for i, (g, h) in enumerate(self.further)
            ],
            "cannot_tell": self.cannot_tell,
            "class_mismatch": self.class_mismatch,
            "rejected": self.rejected,
            "reason": self.reason,
            "p_values": {g: round(t.unique_p, 6) for g, t in self.tests.items()},
            "interval_90": [round(v, 4) for v in self.heldout.interval]
            if self.heldout is not None and self.cause != "none"
            else None,
            # the named cause's held-out comparison, or the first candidate's that held-out data rejected
            "heldout": {"of": self.cause if self.cause != "none" else self.rejected[0], **self.heldout.as_json()}
            if self.heldout is not None and (self.cause != "none" or self.rejected)
            else None,
            "holdout": self.holdout,
            "evidence": {g: t.as_json() for g, t in self.tests.items()},
            "baseline": {
                "input_lag_s": round(self.runset.input_lag_s, 6),
                "output_lag_s": round(self.baseline.lag_s, 6),
                "nuisance_columns": self.baseline.nuisance.shape[1],
            },
            "heldout_surrogates": {g: r.as_json() for g, r in self.column_heldout.items()},
            "runs": self.runset.names,
            "samples": int(self.runset.y.size),
            "rules": self.rules.as_json(),
            "notes": self.notes,
        }


def _say(enabled: bool, text: str) -> None:
    if enabled:
        print(text, file=sys.stderr, flush=True)


def score(
    rs: RunSet, levels: int, rules: Rules, seed: int, say: Callable[[str], None] | None = None
) -> tuple[Baseline, dict[str, NDArray[np.float64]], dict[str, GroupTest], list[str]]:
    """Baseline at ``levels`` and every cause's tests; ``say`` gets a progress line between them."""
    nodes, smoothness, notes = preisach_basis(rs, levels, rules.preisach_pad_levels)
    base = fit_baseline(
        rs,
        nodes,
        smoothness,
        rules.output_lags_s,
        rules.node_ridge,
        rules.nuisance_lags_s,
        rules.resonance_hz if rules.resonance_nuisance else (),
        rules.resonance_zetas,
        series_lags_s=rules.series_lags_s if rules.series_lag else (),
    )
    if rules.class_nuisance:
        base = with_nuisance(rs, base, class_nuisance(rs, base, rules), rules.node_ridge)
    groups = cause_groups(rs, base, rules)
    if say is not None:
        say(f"diagnose v3: baseline fitted (output lag {base.lag_s:g} s); testing {len(groups)} causes ...")
    w = whitened(rs, base, rules)
    branch = branch_of(rs)

    def surrogate(cause: str, copy: NDArray[np.float64]) -> NDArray[np.float64]:
        return column_group(rs, base, copy, rules, branch)

    rng = np.random.default_rng(seed)
    sims = None
    if rules.composite_draws > 0 and any(CAUSES[g].kind != "column" for g in groups):
        noise = unrestricted_residual(rs, base, groups)
        sims = {
            c.name: simulated_records(rs, c.fit, noise, rules.composite_draws, rules, rng)
            for c in null_classes(rs, base, rules)
        }
    tests = group_tests(w, groups, rules, surrogate, rng, sims)
    return base, groups, tests, notes


def richer_rung(rs: RunSet, rules: Rules, seed: int) -> dict[str, GroupTest]:
    """Every cause's tests with the richer rate-independent baseline (``rules.richer_levels``): the
    robustness ladder's rung. Only the dynamic causes' tests are read (:func:`choose`), so the
    composite null and the column surrogates are skipped."""
    cheaper = replace(rules, composite_draws=0, surrogate_screen_p=0.0)
    return score(rs, rules.richer_levels, cheaper, seed + 1)[2]


def decide(tests: dict[str, GroupTest], rules: Rules = RULES) -> tuple[list[str], list[str]]:
    """(candidates, cannot_tell): the causes whose unique test passes at their level, the largest
    unique share first (a physical cause before ``slow_drift``); with ``rules.marginal_candidates``
    they are followed by the causes significant beyond the baseline alone (largest marginal
    statistic per degree of freedom first): groups overlap, so a real effect's unique part can
    vanish into a rival's directions, and the held-out confirmation then tells which one
    predicts. Without it, when no unique test passes, the one cause significant beyond the
    baseline alone; else those significant only jointly (cannot tell). With
    ``rules.column_first`` the measured columns come first (see the field's comment)."""
    unique = [g for g, t in tests.items() if t.unique_p <= t.level]
    ranked = sorted(unique, key=lambda g: (g == "slow_drift", -tests[g].unique_share))
    if rules.column_first:
        columns = [g for g in ranked if CAUSES[g].kind == "column"]
        drift = tests.get("slow_drift")
        if drift is None or drift.unique_p > drift.level:  # time adds nothing beyond the causes
            columns += [
                g
                for g, t in sorted(tests.items(), key=lambda kv: kv[1].marginal_p)
                if CAUSES[g].kind == "column" and g not in columns and t.marginal_p <= t.level
            ]
        ranked = columns + [g for g in ranked if g not in columns]
        unique = ranked
    joint = [g for g, t in tests.items() if t.marginal_p <= t.level]
    if rules.marginal_candidates:
        rest = [g for g in joint if g not in unique]
        ranked += sorted(rest, key=lambda g: (g == "slow_drift", -tests[g].marginal_stat / max(tests[g].df, 1)))
        return ranked, [] if unique or len(rest) < 2 else sorted(rest, key=lambda g: tests[g].marginal_p)
    if unique:
        return ranked, []
    if len(joint) == 1:
        return joint, []
    return [], sorted(joint, key=lambda g: tests[g].marginal_p)


@dataclass
class Choice:
    """What :func:`choose` decided from the tests, the ladder and the held-out trials."""

    cause: str
    rejected: list[str]
    class_mismatch: bool
    not_confirmed: bool
    heldout_of: str | None  # whose held-out trial the verdict reports


def choose(
    ranked: list[str],
    tests: dict[str, GroupTest],
    richer_tests: Callable[[], dict[str, GroupTest]],
    trial: Callable[[str], HeldOut],
    rules: Rules,
) -> Choice:
    """The first of ``ranked`` (causes whose unique test passed) that survives the robustness
    ladder (when ``rules.ladder_drop`` < 1) and the held-out confirmation (when
    ``rules.heldout_gate``). ``richer_tests()`` and ``trial(cause)`` compute on demand, so the
    same rules replay from a dump (``bench/diagnose_replay.py --v3``) without refits."""
    cause, class_mismatch, not_confirmed = "none", False, False
    rejected: list[str] = []
    heldout_of: str | None = None
    for candidate in ranked:  # the largest unique share first; the first confirmed is named
        if faded(candidate, tests, richer_tests, rules):
            class_mismatch = class_mismatch or not rejected
            rejected.append(candidate)
            continue
        if confirmed(trial(candidate), rules) or not rules.heldout_gate:
            return Choice(candidate, rejected, False, False, candidate)
        if not rejected:
            heldout_of, not_confirmed = candidate, True
        rejected.append(candidate)
    return Choice(cause, rejected, class_mismatch, not_confirmed, heldout_of)


def with_columns(choice: Choice, passers: list[str], trial: Callable[[str], HeldOut]) -> Choice:
    """``choice``, or the first of ``passers`` (columns that beat their copies held out,
    :func:`column_passers`) when it predicts held-out data better than the chosen cause (or none
    was chosen): of two confirmed causes, the one that predicts best is named, the other is
    ``also``."""
    if not passers:
        return choice
    column = passers[0]
    if choice.cause != "none" and trial(column).gain <= trial(choice.cause).gain:
        return choice
    return Choice(column, [g for g in choice.rejected if g != column], False, False, column)


def confirmed(h: HeldOut, rules: Rules) -> bool:
    """Nested confirmation: the extension predicts rows it was not fitted on (Clark-West p <= alpha,
    and with ``rules.heldout_interval_gate`` the gain's 90 % interval above 0)."""
    return h.clark_west_p <= rules.alpha and (h.interval[0] > 0.0 or not rules.heldout_interval_gate)


def held_out_beyond(
    rs: RunSet,
    base: Baseline,
    groups: dict[str, NDArray[np.float64]],
    candidate: str,
    before: list[str],
    masks: list[NDArray[np.bool_]],
    rules: Rules,
    seed: int,
    clusters: NDArray[np.int64] | None,
    whitener: NDArray[np.float64] | None,
) -> HeldOut:
    """``candidate``'s held-out comparison (:func:`host.diagnose.heldout.held_out`) beyond the
    baseline and the causes ``before`` (their groups join the nuisance, each keeping its ridge)."""
    column = CAUSES[candidate].column
    return held_out(
        rs,
        np.hstack([base.nuisance, *(groups[g] for g in before)]),
        base.smoothness,
        groups[candidate],
        masks,
        rules.node_ridge,
        np.random.default_rng(seed),
        rs.columns.get(column) if column else None,
        clusters,
        whitener,
        [groups[g].shape[1] for g in before],
    )


def faded(
    cause: str, tests: dict[str, GroupTest], richer_tests: Callable[[], dict[str, GroupTest]], rules: Rules
) -> bool:
    """The robustness ladder: a dynamic cause whose unique test fails with the richer baseline, its
    statistic down by more than ``rules.ladder_drop``, is the baseline's class, not a cause."""
    if CAUSES[cause].kind != "dynamic" or rules.ladder_drop >= 1.0:
        return False
    r = richer_tests()[cause]
    return r.unique_p > r.level and r.unique_stat < (1 - rules.ladder_drop) * tests[cause].unique_stat


def further_causes(
    named: str,
    candidates: list[str],
    trial_beyond: Callable[[str, list[str]], HeldOut],
    rules: Rules,
) -> list[tuple[str, HeldOut]]:
    """The causes of ``candidates`` (in order) confirmed held out one after another, each beyond
    the baseline, ``named`` and the causes confirmed before it (``trial_beyond(cause, before)``);
    the first that is not confirmed ends the sequence (fixed-sequence testing at alpha), and at
    most ``rules.max_further_causes`` are kept."""
    found: list[tuple[str, HeldOut]] = []
    if named == "none":
        return found
    for g in candidates:
        if len(found) >= rules.max_further_causes:
            break
        h = trial_beyond(g, [named] + [f for f, _ in found])
        if not confirmed(h, rules):
            break
        found.append((g, h))
    return found


def beyond_the_named(
    choice: Choice,
    ranked: list[str],
    tests: dict[str, GroupTest],
    richer_tests: Callable[[], dict[str, GroupTest]],
    trial_beyond: Callable[[str, list[str]], HeldOut],
    rules: Rules,
) -> tuple[list[str], list[tuple[str, HeldOut]]]:
    """(also, further) for the cause ``choice`` names: the other ``ranked`` causes it did not reject
    (none when nothing is named), and those of them confirmed held out beyond it in turn
    (:func:`further_causes`; a cause that fades on the ladder is not tried). One rule for
    :func:`diagnose_runs` and the dumps of ``bench/diagnose_v3_dump.py``."""
    if choice.cause == "none":
        return [], []
    also = [g for g in ranked if g != choice.cause and g not in choice.rejected]
    candidates = [g for g in also if not faded(g, tests, richer_tests, rules)]
    return also, further_causes(choice.cause, candidates, trial_beyond, rules)


def column_heldout_test(
    rs: RunSet,
    base: Baseline,
    groups: dict[str, NDArray[np.float64]],
    cause: str,
    masks: list[NDArray[np.bool_]],
    rules: Rules,
    seed: int,
) -> HeldOutSurrogates:
    """The held-out gain of column cause ``cause`` beyond the baseline and drift in time, against
    that of ``rules.column_surrogates`` copies of its column (:mod:`host.diagnose.heldout_surrogates`):
    a column that only stands in for a drift gains nothing over the drift terms, nor do its copies."""
    column = CAUSES[cause].column
    assert column is not None
    branch = branch_of(rs)
    beyond = np.hstack([base.nuisance, groups["slow_drift"]]) if "slow_drift" in groups else base.nuisance
    copies, kind = column_copies(rs, rs.columns[column], rules.column_surrogates, np.random.default_rng(seed))
    return held_out_surrogates(
        rs.y,
        beyond,
        base.smoothness,
        lambda copy: column_group(rs, base, copy, rules, branch),
        rs.columns[column],
        copies,
        kind,
        masks,
        rules.node_ridge,
    )


def column_passers(
    rs: RunSet,
    base: Baseline,
    groups: dict[str, NDArray[np.float64]],
    tests: dict[str, GroupTest],
    trial: Callable[[str], HeldOut],
    masks: list[NDArray[np.bool_]],
    rules: Rules,
    seed: int,
    say: Callable[[str], None] = lambda text: None,
) -> tuple[list[str], dict[str, HeldOutSurrogates]]:
    """The measured columns confirmed held out whose held-out gain beats their surrogate copies'
    at the column's level (``rules.column_heldout_surrogates``, :func:`column_heldout_test`), the
    largest gain first, and every tested column's result."""
    found: dict[str, HeldOutSurrogates] = {}
    if not rules.column_heldout_surrogates:
        return [], found
    for g in tests:
        if CAUSES[g].column is None or not confirmed(trial(g), rules):
            continue
        say(f"diagnose v3: held-out gain of {g} against {rules.column_surrogates} copies of its column ...")
        found[g] = column_heldout_test(rs, base, groups, g, masks, rules, seed)
    passed = passing_columns({g: (r.p, r.gain) for g, r in found.items()}, tests, lambda g: True)
    return passed, found


def passing_columns(
    results: dict[str, tuple[float, float]],
    tests: dict[str, GroupTest],
    confirmed_held_out: Callable[[str], bool],
) -> list[str]:
    """The columns whose held-out surrogate p (``results``: column cause -> (p, held-out gain)) is
    at the column's level and that are confirmed held out, the largest gain first: the rule
    :func:`column_passers` applies live and the dump and replay apply to stored results."""
    passed = [g for g, (p, _) in results.items() if p <= tests[g].level and confirmed_held_out(g)]
    return sorted(passed, key=lambda g: -results[g][1])


def diagnose_runs(
    runs: list[Measurement], *, rules: Rules = RULES, progress: bool = False, seed: int = 0
) -> DiagnosisV3:
    """Diagnose one or more runs of one rig together (see module docstring)."""
    wall, cpu = time.perf_counter(), time.process_time()
    rs = run_set(runs, rules.max_rows, rules.min_samples)
    threads = 1 if rs.y.size < 15_000 else 2
    with threadpool_limits(limits=threads):
        _say(progress, f"diagnose v3: {rs.n_runs} run(s), {rs.y.size} samples: choosing the actuator lag ...")
        rs = with_actuator(rs, rules)
        _say(progress, "diagnose v3: fitting the baseline ...")
        base, groups, tests, notes = score(
            rs, rules.preisach_levels, rules, seed, (lambda text: _say(progress, text)) if progress else None
        )
        masks, holdout = holdout_folds(rs, rules)
        whitener = ar_whitener(rs.y - base.prediction, rules.max_ar_order) if rules.heldout_whitened else None
        richer: dict[str, GroupTest] = {}
        trials: dict[str, HeldOut] = {}

        def richer_tests() -> dict[str, GroupTest]:
            if not richer:
                _say(progress, "diagnose v3: checking the dynamic causes against a richer baseline ...")
                richer.update(richer_rung(rs, rules, seed))
            return richer

        def trial_beyond(candidate: str, before: list[str]) -> HeldOut:
            after = f" beyond {', '.join(before)}" if before else ""
            _say(progress, f"diagnose v3: held-out gain of {candidate}{after} over {len(masks)} folds ...")
            return held_out_beyond(
                rs, base, groups, candidate, before, masks, rules, seed, cluster_labels(rs, rules), whitener
            )

        def trial(candidate: str) -> HeldOut:
            if candidate not in trials:
                trials[candidate] = trial_beyond(candidate, [])
            return trials[candidate]

        ranked, cannot_tell = decide(tests, rules)
        choice = choose(ranked, tests, richer_tests, trial, rules)
        passers, column_heldout = column_passers(
            rs, base, groups, tests, trial, masks, rules, seed, lambda text: _say(progress, text)
        )
        unreachable = [g for g, r in column_heldout.items() if 1.0 / (r.copies + 1) > tests[g].level]
        if unreachable:
            notes.append(
                f"the held-out column test of {', '.join(unreachable)} cannot pass: {rules.column_surrogates} copies "
                f"give p >= {1.0 / (rules.column_surrogates + 1):.2g}, above the column's level "
                f"{tests[unreachable[0]].level:.2g}; raise column_surrogates"
            )
        choice = with_columns(choice, passers, trial)
        if choice.cause in passers:
            cannot_tell = []
            ranked = [choice.cause] + [g for g in ranked if g != choice.cause]
        cause, class_mismatch, not_confirmed, rejected = (
            choice.cause,
            choice.class_mismatch,
            choice.not_confirmed,
            choice.rejected,
        )
        result_heldout = trials.get(choice.heldout_of) if choice.heldout_of else None
        also, further = beyond_the_named(choice, ranked, tests, richer_tests, trial_beyond, rules)
    first = rejected[0] if rejected else "none"
    out = DiagnosisV3(
        cause,
        also,
        cannot_tell,
        class_mismatch and cause == "none",
        "",
        tests,
        result_heldout,
        holdout,
        rs,
        base,
        result_heldout.ext_prediction if result_heldout is not None and cause != "none" else None,
        rules,
        rs.notes + notes,
        not_confirmed=not_confirmed and cause == "none",
        rejected=rejected,
        trials=trials,
        column_heldout=column_heldout,
        further=further,
    )
    out.reason = explain(out, first)
    out.seconds, out.cpu_seconds = time.perf_counter() - wall, time.process_time() - cpu
    return out


def explain(d: DiagnosisV3, tested: str) -> str:
    """The reason in one paragraph."""
    t = d.tests
    if d.class_mismatch:
        return (
            f"{tested} passed its unique test (p = {t[tested].unique_p:.2g}) with the {d.rules.preisach_levels}-level "
            f"baseline but faded with a {d.rules.richer_levels}-level one: the rate-independent baseline's class does "
            "not fit this record, which is not a cause; identify a richer hysteresis model before diagnosing"
        )
    if d.not_confirmed and d.heldout is not None:
        h = d.heldout
        return (
            f"{tested} passed its test on the whole record (p = {t[tested].unique_p:.2g}) but does not predict "
            f"held-out data ({h.gain:+.1%}, 90 % interval {h.interval[0]:+.1%} to {h.interval[1]:+.1%}, Clark-West "
            f"p = {h.clark_west_p:.2g}): the baseline misses something that this cause's regressors fit only in-sample "
            "(a structural misfit of the hysteresis, most likely); no cause is named"
        )
    if d.cause != "none":
        g = t[d.cause]
        hv = d.heldout
        held = (
            f"; held out, the extension lowers the RMS error from {hv.base_rmse:.3g} to {hv.ext_rmse:.3g} "
            f"({hv.gain:.1%}, 90 % interval {hv.interval[0]:.1%} to {hv.interval[1]:.1%}; "
            f"Clark-West p = {hv.clark_west_p:.2g})"
            if hv
            else ""
        )
        also = "".join(
            f"; beyond it{' and ' + ', '.join(f for f, _ in d.further[:i]) if i else ''}, {g} also predicts "
            f"held-out data better ({h.gain:.1%}, 90 % interval {h.interval[0]:.1%} to {h.interval[1]:.1%}; "
            f"Clark-West p = {h.clark_west_p:.2g})"
            for i, (g, h) in enumerate(d.further)
        )
        confirmed_too = {g for g, _ in d.further}
        unchecked = [g for g in d.also if g not in confirmed_too]
        if unchecked:
            also += "; also significant on its own (not confirmed held out beyond the named causes): " + ", ".join(
                unchecked
            )
        if d.rejected:
            also += f"; passed on the record but failed held out or with a richer baseline: {', '.join(d.rejected)}"
        if d.cause in d.column_heldout:
            s = d.column_heldout[d.cause]
            return (
                f"{d.cause}: the {CAUSES[d.cause].column} column's terms predict held-out data better than those of "
                f"{s.copies} surrogate copies of it ({s.kind}): beyond the baseline and the drift terms, a held-out "
                f"gain of {s.gain:.1%} against a median "
                f"{s.median_copy_gain:.1%} (p = {s.p:.2g} at level {g.level:.3g}; in-sample unique p = "
                f"{g.unique_p:.2g}){held}{also}"
            )
        return (
            f"{d.cause}: its own regressors ({CAUSES[d.cause].meaning}) explain {g.unique_share:.1%} of the whitened "
            f"residual beyond the baseline and every other cause (p = {g.unique_p:.2g} at level {g.level:.3g}, "
            f"{g.null}){held}{also}"
        )
    if d.cannot_tell:
        names = " and ".join(d.cannot_tell)
        record = "; ".join(f"for {c}: {CAUSES[c].to_record}" for c in d.cannot_tell)
        return (
            f"cannot tell {names} apart: together they explain what the baseline misses, but none does on its own "
            f"(each needs the others' directions); record what separates them ({record})"
        )
    smallest = min(t.values(), key=lambda g: g.mde) if t else None
    detect = (
        f"; on this record an effect would need an own part of about {smallest.mde:.3g} RMS in y's units "
        f"({smallest.name}, the most sensitive test) to be found with 80 % power"
        if smallest
        else ""
    )
    return f"no cause passes its test at family-wise alpha {d.rules.alpha:g}{detect}; smaller effects may be present"
