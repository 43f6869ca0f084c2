"""Scorecard of ``pmactl diagnose`` on the test plants: the tuning set and the fresh held-out set.

Usage: python bench/diagnose_scorecard.py [--set tuning|fresh|blind|blind2|...|blind11|both|all]
       [--duration S] [--only TEXT] [--json OUT]

Prints one line per record (plant, effect:form, protocol, rate, verdict, confidence, held-out
gain, CPU seconds) and a table per set: effects named / missed per plant and effect, false alarms
on the effect-free records, median held-out gain when named, which evidence decided. The tuning
set (bench/plants/family.py: Bouc-Wen, generalised play, friction-spring, HIL) is what the method
and its constants were chosen on; the fresh set (bench/plants/fresh_family.py: four other cores,
other effect forms, protocols and rates) was built separately and is only reported. The blind
set (bench/plants/blind_family.py: four more cores, forms, protocols and rates) was built without
looking at the method, to be scored once; it has been scored three times and was replaced by
blind2 (bench/plants/blind2_family.py: four more cores, forms, protocols and rates, built blind
too), scored once for v6 and then used with the others to calibrate v7's gain floor; blind3
(bench/plants/blind3_family.py, built blind for v7) is the set v7 was scored on once, and
blind4 (bench/plants/blind4_family.py, built blind for v8) the set v8 was scored on once, and
blind5 and blind6 (bench/plants/blind5_family.py, blind6_family.py, built blind for v9) the sets
v9 was scored on once each (blind5 before v9's thermal-lag terms, blind6 after), and blind7
(bench/plants/blind7_family.py, built blind for v10) the set v10 was scored on once, blind8
(built blind for v11) the set v11 was scored on once, blind9 (built blind for v12) the set
v12 was scored on once (v12 kept v11's method), blind10 (built blind for v13) the set v13
was scored on once, and blind11 (built blind for v14) the set v14 was scored on once.
``both`` is tuning + fresh; ``all`` adds the blind sets.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from collections import defaultdict
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants.families import FAMILIES  # noqa: E402
from bench.plants.family import Case  # noqa: E402
from edge.errors import DataError  # noqa: E402
from host.data import Measurement  # noqa: E402
from host.diagnose.run import diagnose  # noqa: E402

SETS = FAMILIES


def diagnosed(m: Measurement, assume_state: bool = True) -> dict[str, object]:
    """One scored diagnosis of ``m`` (warnings silenced): verdict, held-out gain, confidence, CPU
    seconds, samples, which evidence decided, whether the hysteresis state at its first sample
    was assumed, the baseline's actuator lag and what the verdict was decided from
    (:class:`host.diagnose.decide.DecisionInputs` as JSON; None when refused). A record the
    method refuses in one line (a ``DataError``) is the verdict ``refused`` with its message: a
    counted miss, not a crash. ``assume_state``: as :func:`host.diagnose.run.diagnose`'s."""
    start = time.process_time()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = diagnose(m, progress=False, assume_state=assume_state)
    except DataError as refusal:
        outcome: dict[str, object] = {"verdict": "refused", "refusal": str(refusal), "gain": 0.0, "confidence": {}}
        outcome.update(memory_assumed=False, decided_by="refused", decision=None)
    else:
        outcome = {"verdict": d.cause, "gain": d.gain, "confidence": d.confidence, "decided_by": d.decided_by}
        outcome.update(memory_assumed=d.memory_assumed, actuator_lag_s=d.context.lag_s)
        outcome["decision"] = d.decision.as_json() if d.decision else None
    return {**outcome, "cpu_s": time.process_time() - start, "samples": len(m)}


def line(mark: str, name: str, row: dict[str, object]) -> str:
    """The printed line of one scored record."""
    if row["verdict"] == "refused":
        return f"{'REFUSED':<7} {name:<58} -> {row['refusal']}"
    confidence = row["confidence"]
    assert isinstance(confidence, dict)
    return (
        f"{mark:<5} {name:<58} -> {row['verdict']:<18} gain {row['gain']:6.1%} "
        f"margin {confidence.get('over_threshold', float('nan')):+.3f} cpu {row['cpu_s']:5.1f}s  ({row['decided_by']})"
        + ("  [state assumed]" if row.get("memory_assumed") else "")
    )


def score(
    case_list: list[Case], record: Callable[[Case], tuple[Measurement, dict[str, object]]]
) -> list[dict[str, object]]:
    rows = []
    for case in case_list:
        m, _truth = record(case)
        row = {"case": case.name, "plant": case.plant, "effect": case.effect, "form": case.form, **diagnosed(m)}
        confidence = row["confidence"]
        assert isinstance(confidence, dict)
        row["signature_p"] = confidence.get("signature_p", {})
        rows.append(row)
        ok = "ok " if row["verdict"] == case.effect else "MISS" if case.effect != "none" else "FALSE"
        print(line(ok, case.name, row), flush=True)
    return rows


def named_table(rows: Sequence[Mapping[str, Any]], columns_of: Callable[[Mapping[str, Any]], list[str]]) -> None:
    """A Markdown table of the effects named / total: a row per effect, a column per label that
    ``columns_of`` gives each record (its plant; or its kind and "all"), in sorted order."""
    by: dict[tuple[str, str], list[bool]] = defaultdict(list)
    labels: dict[str, None] = {}
    for r in rows:
        for label in columns_of(r):
            labels[label] = None
            if r["effect"] != "none":
                by[(str(r["effect"]), label)].append(r["verdict"] == r["effect"])
    columns = sorted(labels, key=lambda label: (label == "all", label))
    print(f"| effect | {' | '.join(columns)} |")
    print("|---|" + "---|" * len(columns))
    for effect in sorted({e for e, _ in by}):
        cells = [f"{sum(by[(effect, c)])}/{len(by[(effect, c)])}" if by[(effect, c)] else "-" for c in columns]
        print(f"| {effect} | {' | '.join(cells)} |")


def table(title: str, rows: list[dict[str, object]]) -> None:
    print(f"\n## {title}")
    named_table(rows, lambda r: [str(r["plant"])])
    effect_rows = [r for r in rows if r["effect"] != "none"]
    named = [r for r in effect_rows if r["verdict"] == r["effect"]]
    nones = [r for r in rows if r["effect"] == "none"]
    false = [r for r in nones if r["verdict"] != "none"]
    gains = [float(r["gain"]) for r in named]  # type: ignore[arg-type]
    cpu = [float(r["cpu_s"]) for r in rows]  # type: ignore[arg-type]
    print(
        f"\nnamed {len(named)}/{len(effect_rows)} ({len(named) / max(1, len(effect_rows)):.0%}); "
        f"false alarms {len(false)}/{len(nones)}; median held-out gain when named "
        f"{np.median(gains) if gains else float('nan'):.1%}; "
        f"CPU median {np.median(cpu):.1f} s, max {max(cpu):.1f} s"
    )
    evidence: dict[str, list[int]] = defaultdict(lambda: [0, 0])  # named right, named wrong
    for r in rows:
        if r["verdict"] != "none":
            kind = str(r["decided_by"]).split(" (")[0].split(":")[0]
            evidence[kind][0 if r["verdict"] == r["effect"] else 1] += 1
    for kind, (right, wrong_count) in evidence.items():
        print(f"decided by {kind}: {right} right, {wrong_count} wrong")
    wrong = [r for r in effect_rows if r["verdict"] != r["effect"]]
    for r in wrong + false:
        print(f"  wrong: {r['case']} -> {r['verdict']}")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", choices=[*SETS, "both", "all"], default="both")
    parser.add_argument("--duration", type=float, default=150.0, metavar="S")
    parser.add_argument("--only", help="run only cases whose name contains this text")
    parser.add_argument("--json", type=Path, help="write every row here")
    args = parser.parse_args(argv)
    results: dict[str, list[dict[str, object]]] = {}
    for name, (maker, record) in SETS.items():
        if args.set in (name, "all") or (args.set == "both" and name in ("tuning", "fresh")):
            chosen = [c for c in maker(args.duration) if not args.only or args.only in c.name]
            results[name] = score(chosen, record)
    for name, rows in results.items():
        table(f"{name} set ({'plants we tuned on' if name == 'tuning' else 'never tuned on'})", rows)
    if args.json:
        args.json.write_text(json.dumps(results, indent=2, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
