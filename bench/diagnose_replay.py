"""Decide every dumped record again with the working tree's decision rules, and score the verdicts.

Usage: python bench/diagnose_replay.py DUMP.jsonl [DUMP2.jsonl ...] [--set tuning,fresh,...] [--changes]

Reads the lines ``bench/diagnose_dump.py`` wrote and replays
:meth:`host.diagnose.decide.DecisionInputs.verdict` on each: no model is refitted, so a change to
a floor, a margin or a surrogate rule in :mod:`host.diagnose.decide` is measured on every family
in seconds. Printed: per family the effects named, the false alarms on the effect-free records,
the wrong causes and the refused records; named per effect over all families; and how many
verdicts differ from the ones in the dump (0 with the rules that made it; ``--changes`` lists
them). A change to how a candidate is fitted needs a new dump.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from host.diagnose.decide import DecisionInputs  # noqa: E402


def replayed(row: dict[str, Any]) -> str:
    """The verdict of a dumped record under the current rules (``refused`` stays refused)."""
    if row.get("decision") is None:
        return str(row["verdict"])
    return DecisionInputs.from_json(row["decision"]).verdict().cause


def family_table(rows: list[dict[str, Any]], verdicts: list[str]) -> list[str]:
    """One line per family (in dump order) and a total: named, false alarms, wrong, refused."""
    order = list(dict.fromkeys(r["family"] for r in rows))
    lines = []
    for family in [*order, "total"]:
        pairs = [(r, v) for r, v in zip(rows, verdicts) if family in ("total", r["family"])]
        c = Counter[str](
            effects=sum(r["effect"] != "none" for r, _ in pairs),
            named=sum(v == r["effect"] for r, v in pairs if r["effect"] != "none"),
            wrong=sum(v not in ("none", "refused", r["effect"]) for r, v in pairs if r["effect"] != "none"),
            free=sum(r["effect"] == "none" for r, _ in pairs),
            alarms=sum(v not in ("none", "refused") for r, v in pairs if r["effect"] == "none"),
            refused=sum(v == "refused" for _, v in pairs),
        )
        lines.append(
            f"{family:10} named {c['named']:3}/{c['effects']:<3} false alarms {c['alarms']:2}/{c['free']:<3} "
            f"wrong {c['wrong']:3}  refused {c['refused']}"
        )
    return lines


def effect_table(rows: list[dict[str, Any]], verdicts: list[str]) -> list[str]:
    """Named per true effect over every family, and the most common wrong causes."""
    effects = list(dict.fromkeys(r["effect"] for r in rows if r["effect"] != "none"))
    lines = []
    for effect in effects:
        pairs = [(r, v) for r, v in zip(rows, verdicts) if r["effect"] == effect]
        lines.append(f"{effect:18} named {sum(v == effect for _, v in pairs):3}/{len(pairs)}")
    wrong = Counter((r["effect"], v) for r, v in zip(rows, verdicts) if v not in ("none", "refused", r["effect"]))
    lines.append("wrong verdicts, truth -> verdict: " + (", ".join(f"{e} -> {v} {n}" for (e, v), n in wrong.most_common()) or "none"))
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dumps", type=Path, nargs="+", help="JSON lines from bench/diagnose_dump.py")
    parser.add_argument("--set", help="comma-separated families to keep (default: every family in the dumps)")
    parser.add_argument("--changes", action="store_true", help="list every record whose verdict changed")
    args = parser.parse_args(argv)
    rows: list[dict[str, Any]] = []
    for path in args.dumps:
        if not path.is_file():
            parser.error(f"{path}: no such dump; make one with python bench/diagnose_dump.py {path}")
        with path.open() as f:
            rows += [json.loads(line) for line in f if line.strip()]
    if args.set:
        keep = set(args.set.split(","))
        rows = [r for r in rows if r["family"] in keep]
    if not rows:
        parser.error("no records to replay (an empty dump, or --set matches no family in it)")
    verdicts = [replayed(r) for r in rows]
    print("\n".join(family_table(rows, verdicts)))
    print("\n".join(effect_table(rows, verdicts)))
    changed = [(r, v) for r, v in zip(rows, verdicts) if v != r["verdict"]]
    print(f"{len(changed)} of {len(rows)} verdicts differ from the dump's")
    if args.changes:
        for r, v in changed:
            print(f"  {r['family']}/{r['index']:03d} {r['case']}: {r['verdict']} -> {v} (truth {r['effect']})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
