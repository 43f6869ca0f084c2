"""Scorecard of ``pmactl diagnose RUN.csv [RUN.csv ...]`` on real campaigns of short runs with one
known effect injected (:mod:`bench.plants.injected_runs`).

Usage: python bench/diagnose_runs_injected.py [--data ../shared/data] [--only TEXT] [--json OUT]
       [--rules field=value,...] [--dry-run]

Prints one line per campaign (verdict, held-out gain with its interval, the true cause's unique p,
CPU seconds), then effects named / total per effect, and the verdicts on the campaigns as measured
(a real rig may carry real effects: a measured effect there is not a false alarm by construction,
but naming a decoy column is, since no column acts on the measured data).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.diagnose_v3_dump import oracle_p, overridden  # noqa: E402
from bench.plants.injected_runs import injected_runs, runs_cases  # noqa: E402
from host.data import Measurement  # noqa: E402
from host.diagnose.conditional import whitened  # noqa: E402
from host.diagnose.rules import CAUSES, RULES, Rules  # noqa: E402
from host.diagnose.runs import run_set  # noqa: E402
from host.diagnose.v3 import diagnose_runs  # noqa: E402

HERE = Path(__file__).resolve().parent


def scored(case: Any, data: Path, rules: Rules) -> dict[str, Any]:
    runs, truth = injected_runs(case, data)
    wall, cpu = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose_runs(runs, rules=rules)
    true_test = d.tests.get(case.effect)
    oracle = None
    if case.effect != "none":  # the true effect waveform as one regressor beyond the same baseline
        waves = [Measurement(m.t, m.u, e, {}, m.source) for m, e in zip(runs, truth["oracle_waveforms"])]
        wave = run_set(waves, rules.max_rows, rules.min_samples).y
        oracle = oracle_p(wave, whitened(d.runset, d.baseline, rules))
    return {
        "case": case.name,
        "effect": case.effect,
        "verdict": d.cause,
        "gain": d.gain,
        "interval": list(d.heldout.interval) if d.heldout is not None and d.cause != "none" else None,
        "true_unique_p": true_test.unique_p if true_test else None,
        "true_level": true_test.level if true_test else None,
        "oracle_p": oracle,
        "oracle_detects": oracle is not None and oracle <= rules.alpha / max(len(d.tests), 1),
        "rejected": d.rejected,
        "cannot_tell": d.cannot_tell,
        "also_confirmed": [g for g, _ in d.further],
        "runs": truth["runs"],
        "samples": truth["samples"],
        "size_over_span": truth["effect_size_over_span"],
        "size_over_noise": truth["effect_size_over_noise"],
        "wall_s": time.perf_counter() - wall,
        "cpu_s": time.process_time() - cpu,
    }


def line(r: dict[str, Any]) -> str:
    mark = "base" if r["effect"] == "none" else "ok" if r["verdict"] == r["effect"] else "MISS"
    p = "-" if r["true_unique_p"] is None else f"{r['true_unique_p']:.3f}"
    p += "" if r["oracle_p"] is None else f" oracle {r['oracle_p']:.3f}"
    interval = "" if r["interval"] is None else f" [{r['interval'][0]:+.0%}, {r['interval'][1]:+.0%}]"
    extra = f" rejected {','.join(r['rejected'])}" if r["rejected"] else ""
    extra += f" cannot tell {','.join(r['cannot_tell'])}" if r["cannot_tell"] else ""
    extra += f" also confirmed {','.join(r['also_confirmed'])}" if r["also_confirmed"] else ""
    return (
        f"{mark:<5} {r['case']:<52} -> {r['verdict']:<18} gain {r['gain']:6.1%}{interval} true p {p} "
        f"size {r['size_over_span']:.1%} ({r['size_over_noise']:.0f}x noise) {r['runs']} runs "
        f"cpu {r['cpu_s']:.1f}s{extra}"
    )


def summary(rows: list[dict[str, Any]]) -> None:
    effects = sorted({r["effect"] for r in rows if r["effect"] != "none"})
    print("\n| effect | named | named or also confirmed | unique test passed | oracle detects |\n|---|---|---|---|---|")
    for e in effects:
        mine = [r for r in rows if r["effect"] == e]
        passed = sum(r["true_unique_p"] is not None and r["true_unique_p"] <= r["true_level"] for r in mine)
        oracle = sum(r["oracle_detects"] for r in mine)
        print(
            f"| {e} | {sum(r['verdict'] == e for r in mine)}/{len(mine)} "
            f"| {sum(e in [r['verdict'], *r['also_confirmed']] for r in mine)}/{len(mine)} | {passed}/{len(mine)} "
            f"| {oracle}/{len(mine)} |"
        )
    injected = [r for r in rows if r["effect"] != "none"]
    named = [r for r in injected if r["verdict"] == r["effect"]]
    wrong = [r for r in injected if r["verdict"] not in ("none", r["effect"])]
    gains = [r["gain"] for r in named]
    print(
        f"\nnamed {len(named)}/{len(injected)}; wrong cause {len(wrong)}/{len(injected)}; median held-out gain "
        f"when named {np.median(gains) if gains else float('nan'):.1%}; CPU median "
        f"{np.median([r['cpu_s'] for r in rows]):.1f} s, max {max(r['cpu_s'] for r in rows):.1f} s"
    )
    column_causes = {c.name for c in CAUSES.values() if c.kind == "column"}
    print("\nas measured (a column cause named here is a false alarm: no column acts on measured data):")
    for r in rows:
        if r["effect"] == "none":
            flag = "  FALSE ALARM (decoy column)" if r["verdict"] in column_causes else ""
            also = f"; also confirmed {', '.join(r['also_confirmed'])}" if r["also_confirmed"] else ""
            flag += "  FALSE ALARM (decoy column confirmed too)" if set(r["also_confirmed"]) & column_causes else ""
            print(f"  {r['case']}: {r['verdict']} (gain {r['gain']:.1%}){also}{flag}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=HERE.parent.parent / "shared" / "data")
    parser.add_argument("--only", help="only cases whose name contains this text")
    parser.add_argument("--json", type=Path, help="write every row here")
    parser.add_argument("--rules", default="", help="Rules overrides, field=value,... (as bench/diagnose_v3_dump.py)")
    parser.add_argument("--dry-run", action="store_true", help="build the campaigns and print their sizes only")
    args = parser.parse_args(argv)
    if not (args.data / "pam_muscle_sensory").is_dir():
        print(
            f"no muscle campaigns under {args.data}; pass --data DIR (the folder with pam_muscle_sensory/)",
            file=sys.stderr,
        )
        return 2
    try:
        rules = overridden(args.rules, RULES)
    except ValueError as error:
        print(error, file=sys.stderr)
        return 2
    cases = [c for c in runs_cases(args.data) if not args.only or args.only in c.name]
    if not cases:
        print(f"no campaigns under {args.data} match --only {args.only!r}", file=sys.stderr)
        return 2
    rows = []
    for case in cases:
        if args.dry_run:
            _, truth = injected_runs(case, args.data)
            print(
                f"{case.name}: {truth['runs']} runs, {truth['samples']} samples, "
                f"size {truth['effect_size_over_span']:.1%} of span ({truth['effect_size_over_noise']:.0f}x noise) "
                f"{truth['parameters']}"
            )
            continue
        rows.append(scored(case, args.data, rules))
        print(line(rows[-1]), flush=True)
    if rows:
        summary(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
