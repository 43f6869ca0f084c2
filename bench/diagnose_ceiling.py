"""Ceiling of ``pmactl diagnose`` on the test plants: which hidden effects could *any* candidate name?

Usage: python bench/diagnose_ceiling.py [--set fresh,blind,...,blind11] [--duration S]
       [--workers N] [--only TEXT] [--json OUT]      (default: --set blind4 --duration 100)

For every effect record the plant family knows the effect's own noise-free waveform (the output
with the effect minus the same record without it). An *oracle* candidate gets exactly that
waveform as its one term, fitted jointly with the hysteresis like every real candidate
(:func:`host.diagnose.candidates.with_columns`) and scored on the same held-out folds by the same
per-candidate rules (:func:`host.diagnose.decide.against_baseline` at the effect's own floor,
:func:`host.diagnose.decide.floor_for`; no surrogate null). No candidate form can honestly do much
better than the oracle: what the oracle cannot show, the baseline absorbs (a creep that repeats
each cycle is loop shape to a Preisach model) or the record's structural error buries.

Per effect the table counts: named (the diagnosis named it); *form misses* (the oracle passes,
the diagnosis did not name it: a candidate form or a decision rule is what failed); *buried* (not
even the oracle passes: at these floors no candidate could have named it; a record the diagnosis
names anyway is counted in both, and the count is printed); records the diagnosis refused; and
the oracle's median held-out gain next to the diagnosis' own candidate's. The effect-free records
are not scored here (``bench/diagnose_scorecard.py`` counts their false alarms). A record longer
than the diagnosis works on is decimated, its waveform with it, exactly as the diagnosis does.

CPU per record: one diagnosis, then on its context and baseline the baseline's four fold fits
and the oracle's joint fit and four fold fits, ~6 s at 100 s; ``--workers 2`` splits records over two
processes. The tuning family is not here: its records are not built from a noise-free pair with
and without the effect.
"""

from __future__ import annotations

import argparse
import importlib
import json
import sys
import time
import warnings
from collections import defaultdict
from multiprocessing import Pool
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants.families import FAMILIES, family_names  # noqa: E402
from bench.plants.family import Case  # noqa: E402
from edge.errors import DataError  # noqa: E402
from host.diagnose.candidates import baseline, with_columns  # noqa: E402
from host.diagnose.decide import against_baseline, floor_for  # noqa: E402
from host.diagnose.folds import BLOCKS_PER_FOLD, holdout_masks, noise_floor  # noqa: E402
from host.diagnose.run import diagnose, finite_or_null, held_out_score  # noqa: E402

FOLDS = 4
# family -> the function that lists its cases; each family's module has simulate() and measurement_from()
SETS = {name: cases for name, (cases, _record) in FAMILIES.items() if name != "tuning"}


def oracle(set_name: str, case: Case) -> dict[str, Any]:
    """The diagnosis of ``case`` and its oracle's held-out score (see the module docstring)."""
    family = importlib.import_module(SETS[set_name].__module__)
    sim = family.simulate(case)
    if "on" not in sim or "off" not in sim:
        raise SystemExit(f"{family.__name__}.simulate gives no 'on'/'off' outputs; the ceiling needs both")
    m, _truth = family.measurement_from(case, sim)
    waveform = np.asarray(sim["on"] - sim["off"], dtype=np.float64)
    row: dict[str, Any] = {"set": set_name, "case": case.name, "plant": case.plant, "effect": case.effect}
    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            d = diagnose(m, progress=False, folds=FOLDS)
        except DataError as refusal:
            refused = {"verdict": "refused", "why_not": str(refusal), "candidate": 0.0, "oracle": 0.0}
            return {**row, **refused, "passes": False, "cpu_s": time.process_time() - start}
        # the diagnosis' own record (decimated as it was), baseline and folds; the waveform is
        # decimated the same way (block means of the same length)
        ctx, start_index = d.context, d.start_index
        step = len(m) // (start_index + ctx.y.size)
        if step > 1:
            waveform = waveform[: (start_index + ctx.y.size) * step].reshape(-1, step).mean(axis=1)
        masks = holdout_masks(ctx.y.size, FOLDS, BLOCKS_PER_FOLD)
        base = baseline(ctx, d.baseline_full)
        base_folds = [base.fit(ctx, ~held).prediction for held in masks]
        term = with_columns(ctx, "oracle", waveform[start_index:, None], ["effect"])
        score = held_out_score(ctx, "oracle", term, masks, base_folds)
        why_not = against_baseline(score, noise_floor(ctx.y), surrogates=False, floor=floor_for(case.effect))
    return {
        **row,
        "verdict": d.cause,
        "candidate": d.scores.get(case.effect, 0.0),
        "oracle": score.mean,
        "passes": why_not is None and not score.failed,
        "why_not": why_not or "",
        "cpu_s": time.process_time() - start,
    }


def _job(job: tuple[str, Case]) -> dict[str, Any]:
    return oracle(*job)


def table(set_name: str, rows: list[dict[str, Any]]) -> None:
    """Per effect: named / form misses / buried, and the oracle's and the candidate's median gains."""
    print(f"\n## {set_name}")
    if not rows:
        print("no effect records (check --only)")
        return
    print(
        "| effect | named | form miss (oracle passes) | buried (oracle fails) | refused | oracle median gain "
        "| candidate median gain |"
    )
    print("|---|---|---|---|---|---|---|")
    by: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for r in rows:
        by[r["effect"]].append(r)
    for effect in [*sorted(by), "all"]:
        group = rows if effect == "all" else by[effect]
        named = sum(r["verdict"] == r["effect"] for r in group)
        form = sum(r["passes"] and r["verdict"] != r["effect"] for r in group)
        refused = sum(r["verdict"] == "refused" for r in group)
        buried = sum(not r["passes"] for r in group) - refused
        print(
            f"| {effect} | {named}/{len(group)} | {form} | {buried} | {refused} | "
            f"{np.median([r['oracle'] for r in group]):+.1%} | {np.median([r['candidate'] for r in group]):+.1%} |"
        )
    named_buried = sum(r["verdict"] == r["effect"] and not r["passes"] for r in rows)  # counted in both
    print(f"\nnamed although the oracle fails its rules: {named_buried} (a candidate fitted more than the effect)")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", default="blind4", help=f"comma-separated, of {', '.join(SETS)}")
    parser.add_argument("--duration", type=float, default=100.0, metavar="S")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--only", help="run only cases whose name contains this text")
    parser.add_argument("--json", type=Path, help="write every row here")
    args = parser.parse_args(argv)
    try:
        sets = family_names(args.set, SETS)
    except ValueError as e:
        parser.error(f"--set: {e}")
    jobs: list[tuple[str, Case]] = []
    for s in sets:
        cases = SETS[s](args.duration)
        jobs += [(s, c) for c in cases if c.effect != "none" and (not args.only or args.only in c.name)]
    rows: list[dict[str, Any]] = []
    with Pool(max(1, args.workers)) as pool:
        for row in pool.imap(_job, jobs):
            rows.append(row)
            mark = "named" if row["verdict"] == row["effect"] else "form" if row["passes"] else "buried"
            mark = "refused" if row["verdict"] == "refused" else mark
            print(
                f"{mark:<6} {row['case']:<64} oracle {row['oracle']:+6.1%} candidate {row['candidate']:+6.1%} "
                f"-> {row['verdict']}",
                flush=True,
            )
    for s in sets:
        table(s, [r for r in rows if r["set"] == s])
    if args.json:
        args.json.write_text(json.dumps(finite_or_null(rows), indent=2, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
