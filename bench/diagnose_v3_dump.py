"""Dump everything a v3 decision needs, per record, so that decision rules replay in seconds.

Usage: python bench/diagnose_v3_dump.py OUT.jsonl [--set tuning,fresh] [--duration S] [--every K]
       [--rules field=value,...]

For every K-th case of each family (effect-free records in the same stride) it fits the baseline
and scores every cause (:func:`host.diagnose.v3.score`) with the rules given, and writes one JSON
line: per cause the unique and marginal statistic, df, level and p under each null separately;
the richer rung's unique statistic and p (the robustness ladder); the held-out comparison of
*every* cause (Clark-West p, the gain and its 90 % interval), not only the ones the live rules
reach; the oracle's p (the true noise-free effect waveform as one regressor beyond the baseline,
whitened, block-bootstrap calibrated; families that simulate their cases); every measured column's
held-out gain against its surrogate copies' (:func:`host.diagnose.v3.column_heldout_test`,
confirmed or not); and the live verdict.
``python bench/diagnose_replay.py --v3 OUT.jsonl`` then decides every record again under any
:class:`host.diagnose.rules.Rules` overrides, without refitting. A change to the nuisance, the
groups or a null needs a new dump (pass the same ``--rules`` here).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.stats import norm
from threadpoolctl import threadpool_limits

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants import engine  # noqa: E402
from bench.plants.families import FAMILIES, family_names  # noqa: E402
from bench.plants.registry import specs  # noqa: E402
from host.data import Measurement  # noqa: E402
from host.diagnose.actuator import with_actuator  # noqa: E402
from host.diagnose.conditional import (  # noqa: E402
    GroupTest,
    block_length,
    orthonormal,
    stationary_draws,
    whitened,
)
from host.diagnose.heldout import (  # noqa: E402
    HeldOut,
    cluster_labels,
    held_out_statistics,
    holdout_folds,
    scoring_name,
)
from host.diagnose.nuisance import ar_whitener  # noqa: E402
from host.diagnose.rules import CAUSES, RULES, Rules, with_overrides  # noqa: E402
from host.diagnose.runs import run_set  # noqa: E402
from host.diagnose.v3 import (  # noqa: E402
    beyond_the_named,
    choose,
    column_heldout_test,
    confirmed,
    decide,
    held_out_beyond,
    passing_columns,
    richer_rung,
    score,
    with_columns,
)


def overridden(text: str, rules: Rules = RULES) -> Rules:
    """``rules`` with ``field=value`` overrides (:func:`host.diagnose.rules.with_overrides`)."""
    return with_overrides(text, rules)


def oracle_p(rs_wave: np.ndarray, w: Any) -> float:
    """Block-bootstrap p of the true effect waveform as one regressor beyond the baseline."""
    u = orthonormal(w.prepare(rs_wave[:, None]))
    e = w.residual
    stat = float(np.sum((u.T @ e) ** 2))
    draws = e[stationary_draws(e.size, block_length(e), 199, np.random.default_rng(0))]
    null = np.sum((u.T @ draws) ** 2, axis=0) * (e @ e / e.size) / np.mean(draws**2, axis=0)
    return float((1 + np.sum(null >= stat)) / 200)


def _trial_json(h: HeldOut) -> dict[str, float]:
    return {
        "cw_p": round(h.clark_west_p, 6),
        "lo": round(h.interval[0], 4),
        "hi": round(h.interval[1], 4),
        "gain": round(h.gain, 4),
    }


def _richer_json(t: GroupTest) -> dict[str, float]:
    return {"unique_stat": round(t.unique_stat, 4), "unique_p": round(t.unique_p, 6), "level": t.level}


def dump_record(m: Measurement, wave: np.ndarray | None, rules: Rules, seed: int = 0) -> dict[str, Any]:
    """Every input of a v3 decision on one record (see module docstring)."""
    rs = with_actuator(run_set([m], rules.max_rows, rules.min_samples), rules)
    base, groups, tests, _ = score(rs, rules.preisach_levels, rules, seed)
    richer = richer_rung(rs, rules, seed)
    masks, _ = holdout_folds(rs, rules)
    # every held-out fit once, scored four ways (per row or cluster-robust, raw or whitened errors):
    # bench/diagnose_replay.py --v3 picks the scoring the rules ask for
    labels = cluster_labels(rs, replace(rules, heldout_clusters=True))
    ar = ar_whitener(rs.y - base.prediction, rules.max_ar_order)
    trials, variants = {}, {}
    for g in groups:
        h = held_out_beyond(rs, base, groups, g, [], masks, rules, seed, None, None)
        assert h.scored is not None
        for clustered in (False, True):
            for white in (False, True):
                t, interval = held_out_statistics(
                    rs,
                    h.base_prediction,
                    h.ext_prediction,
                    h.scored,
                    np.random.default_rng(seed),
                    labels if clustered else None,
                    ar if white else None,
                )
                variant = replace(h, clark_west_t=t, clark_west_p=float(norm.sf(t)), interval=interval)
                variants.setdefault(scoring_name(clustered, white), {})[g] = variant
                if clustered == rules.heldout_clusters and white == rules.heldout_whitened:
                    trials[g] = variant
    # every column's held-out surrogate test, confirmed or not: the replay applies the gates
    surrogates = {g: column_heldout_test(rs, base, groups, g, masks, rules, seed) for g in groups if CAUSES[g].column}
    passers = passing_columns(
        {g: (r.p, r.gain) for g, r in surrogates.items()}, tests, lambda g: confirmed(trials[g], rules)
    )
    ranked, cannot_tell = decide(tests, rules)
    choice = choose(ranked, tests, lambda: richer, trials.__getitem__, rules)
    if rules.column_heldout_surrogates:
        choice = with_columns(choice, passers, trials.__getitem__)
        if choice.cause in passers:
            cannot_tell = []  # as diagnose_runs: a named column leaves nothing untold
    clusters = labels if rules.heldout_clusters else None
    whitener = ar if rules.heldout_whitened else None

    def trial_beyond(candidate: str, before: list[str]) -> HeldOut:
        return held_out_beyond(rs, base, groups, candidate, before, masks, rules, seed, clusters, whitener)

    further = beyond_the_named(choice, ranked, tests, lambda: richer, trial_beyond, rules)[1]
    oracle = None
    if wave is not None:
        w = whitened(rs, base, rules)
        wave_rs = run_set([Measurement(m.t, m.u, wave, {}, m.source)], rules.max_rows, rules.min_samples).y
        oracle = oracle_p(wave_rs, w)
    return {
        "verdict": choice.cause,
        "cannot_tell": cannot_tell,
        # causes confirmed held out beyond the named one, in turn (live rules only: not replayed)
        "further": [{"cause": g, **_trial_json(h)} for g, h in further],
        "tests": {g: t.as_json() for g, t in tests.items()},
        "richer": {g: _richer_json(t) for g, t in richer.items()},
        "trials": {g: _trial_json(h) for g, h in trials.items()},
        "trials_by_scoring": {k: {g: _trial_json(h) for g, h in v.items()} for k, v in variants.items()},
        "oracle_p": oracle,
        "heldout_surrogates": {g: r.as_json() for g, r in surrogates.items()},
        "baseline_columns": int(base.nuisance.shape[1]),
        "input_lag_s": rs.input_lag_s,
        "output_lag_s": base.lag_s,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path)
    parser.add_argument("--set", default="tuning,fresh")
    parser.add_argument("--duration", type=float, default=60.0, metavar="S")
    parser.add_argument("--every", type=int, default=3, metavar="K")
    parser.add_argument("--rules", default="", help="Rules overrides, e.g. class_nuisance=true,ladder_drop=1")
    args = parser.parse_args(argv)
    try:
        rules = overridden(args.rules)
        names = family_names(args.set)
    except ValueError as e:
        parser.error(str(e))
    registry = specs()
    with args.out.open("w") as out:
        for family in names:
            cases_of, record = FAMILIES[family]
            for index, case in list(enumerate(cases_of(args.duration)))[:: args.every]:
                wall, cpu = time.perf_counter(), time.process_time()
                m, _ = record(case)
                wave = None
                if case.effect != "none":
                    try:
                        sim = engine.simulate(registry[family], case)
                        wave = np.asarray(sim["on"] - sim["off"], dtype=np.float64)
                        wave = wave if wave.size == m.y.size else None
                    except (TypeError, KeyError):
                        wave = None
                with warnings.catch_warnings(), threadpool_limits(limits=1):
                    warnings.simplefilter("ignore")
                    row = dump_record(m, wave, rules)
                row = {
                    "family": family,
                    "index": index,
                    "case": case.name,
                    "effect": case.effect,
                    "v3": True,
                    "rules": args.rules,
                    **row,
                    "cpu_s": round(time.process_time() - cpu, 2),
                    "wall_s": round(time.perf_counter() - wall, 2),
                }
                out.write(json.dumps(row) + "\n")
                out.flush()
                print(
                    f"{family}/{index:03d} {case.name:<60} -> {row['verdict']:<18} cpu {row['cpu_s']:5.1f}s",
                    file=sys.stderr,
                    flush=True,
                )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
