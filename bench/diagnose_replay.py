"""Decide every dumped record again with the working tree's decision rules, and score the verdicts.

Usage: python bench/diagnose_replay.py DUMP.jsonl [DUMP2.jsonl ...] [--set tuning,fresh,...] [--changes]
       python bench/diagnose_replay.py --v3 DUMP.jsonl [--rules field=value,...] [--rules ...]

``--v3``: the dump is from ``bench/diagnose_v3_dump.py``, and every ``--rules`` (overrides of
:class:`host.diagnose.rules.Rules`) is compared side by side with the current rules
(:mod:`bench.diagnose_v3_replay`).

Reads the lines ``bench/diagnose_dump.py`` wrote and replays
:meth:`host.diagnose.decide.DecisionInputs.verdict` on each: no model is refitted, so a change to
a floor, a margin or a surrogate rule in :mod:`host.diagnose.decide` is measured on every family
in seconds. Printed: per family the effects named, the false alarms on the effect-free records,
the wrong causes, and the records refused or failed; named per effect over all families; and
how many verdicts differ from the ones in the dump (0 with the rules that made it; ``--changes``
lists them). A change to how a candidate is fitted needs a new dump.

One verdict cannot always be replayed exactly: the diagnosis computes the slow drift's
surrogate null only when the drift would be named (nine joint fits), so a rule change that
lets the drift pass on a record dumped without that null decides it without the test a live
run would apply. Such records are counted and listed apart ("needs a new dump").
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import Counter
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants.families import FAMILIES  # noqa: E402
from host.diagnose.decide import DecisionInputs, drift_would_be_named  # noqa: E402

Line = dict[str, Any]
KEYS = ("family", "index", "case", "effect", "verdict")
NOT_DIAGNOSED = ("refused", "error")  # verdicts of records without decision inputs


class DumpError(ValueError):
    """A dump that cannot be read; the message names the file and line."""


def read_dump(path: Path) -> list[Line]:
    """Every record of the dump at ``path`` (blank lines skipped); :class:`DumpError` naming
    ``path:line`` for a line that is not a dump line (not JSON, or without a record's keys)."""
    try:
        text = path.read_text()
    except UnicodeDecodeError:
        raise DumpError(f"{path}: not a text file; a dump is JSON lines from bench/diagnose_dump.py") from None
    rows = []
    for number, raw in enumerate(text.splitlines(), 1):
        if not raw.strip():
            continue
        try:
            row = json.loads(raw)
        except json.JSONDecodeError:
            raise DumpError(f"{path}:{number}: not a JSON line (a dump written by another program, or cut)") from None
        missing = [k for k in KEYS if not isinstance(row, dict) or k not in row]
        if missing:
            raise DumpError(f"{path}:{number}: not a dump line (no {', '.join(missing)})")
        rows.append(row)
    return rows


def replayed(row: Line) -> tuple[str, bool]:
    """The verdict of a dumped record under the current rules (a record that was not diagnosed
    keeps its verdict), and whether it is exact: False when the drift would be named but the
    dump has no surrogate null for it (see the module docstring)."""
    if row.get("decision") is None:
        return str(row["verdict"]), True
    inputs = DecisionInputs.from_json(row["decision"])
    drift = inputs.scores.get("slow_drift")
    exact = drift is None or bool(drift.null_gains) or not drift_would_be_named(inputs.scores, inputs.noise)
    return inputs.verdict().cause, exact


def family_table(rows: list[Line], verdicts: list[str]) -> list[str]:
    """One line per family (in the registry's order) and a total: named, false alarms, wrong, and
    the records refused or failed."""
    known = list(FAMILIES)
    order = sorted({r["family"] for r in rows}, key=lambda f: (known.index(f) if f in known else len(known), f))
    lines = []
    for family in [*order, "total"]:
        pairs = [(r, v) for r, v in zip(rows, verdicts) if family in ("total", r["family"])]
        c = Counter[str](
            effects=sum(r["effect"] != "none" for r, _ in pairs),
            named=sum(v == r["effect"] for r, v in pairs if r["effect"] != "none"),
            wrong=sum(v not in ("none", *NOT_DIAGNOSED, r["effect"]) for r, v in pairs if r["effect"] != "none"),
            free=sum(r["effect"] == "none" for r, _ in pairs),
            alarms=sum(v not in ("none", *NOT_DIAGNOSED) for r, v in pairs if r["effect"] == "none"),
            refused=sum(v == "refused" for _, v in pairs),
            errors=sum(v == "error" for _, v in pairs),
        )
        lines.append(
            f"{family:10} named {c['named']:3}/{c['effects']:<3} false alarms {c['alarms']:2}/{c['free']:<3} "
            f"wrong {c['wrong']:3}  refused {c['refused']}  failed {c['errors']}"
        )
    return lines


def effect_table(rows: list[Line], verdicts: list[str]) -> list[str]:
    """Named per true effect over every family, and every verdict that is not the truth."""
    effects = list(dict.fromkeys(r["effect"] for r in rows if r["effect"] != "none"))
    lines = []
    for effect in effects:
        pairs = [(r, v) for r, v in zip(rows, verdicts) if r["effect"] == effect]
        lines.append(f"{effect:18} named {sum(v == effect for _, v in pairs):3}/{len(pairs)}")
    wrong = Counter((r["effect"], v) for r, v in zip(rows, verdicts) if v not in ("none", *NOT_DIAGNOSED, r["effect"]))
    listed = ", ".join(f"{e} -> {v} {n}" for (e, v), n in wrong.most_common()) or "none"
    lines.append(f"wrong causes and false alarms (truth -> verdict): {listed}")
    return lines


def loaded(parser: argparse.ArgumentParser, paths: list[Path], families: str | None) -> list[Line]:
    """The records of every dump, checked: each file readable, no record twice, ``families``
    (comma-separated) all present; a problem is one line from ``parser`` (exit 2)."""
    rows: list[Line] = []
    for path in paths:
        if not path.is_file():
            parser.error(f"{path}: no such dump; make one with python bench/diagnose_dump.py {path}")
        try:
            rows += read_dump(path)
        except DumpError as e:
            parser.error(str(e))
    seen: set[tuple[str, int]] = set()
    for r in rows:
        key = (r["family"], int(r["index"]))
        if key in seen:
            parser.error(f"record {key[0]}/{key[1]:03d} is in the dumps twice; give each dump once")
        seen.add(key)
    if families:
        keep = [f for f in families.split(",") if f]
        present = list(dict.fromkeys(r["family"] for r in rows))
        unknown = [f for f in keep if f not in present]
        if unknown or not keep:
            parser.error(
                f"--set: {', '.join(unknown) or '(none given)'} not in the dumps; they hold {', '.join(present)}"
            )
        rows = [r for r in rows if r["family"] in keep]
    if not rows:
        parser.error("no records to replay: the dumps are empty")
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("dumps", type=Path, nargs="+", help="JSON lines from bench/diagnose_dump.py")
    parser.add_argument("--set", help="comma-separated families to keep (default: every family in the dumps)")
    parser.add_argument("--changes", action="store_true", help="list every record whose verdict changed")
    parser.add_argument("--v3", action="store_true", help="the dumps are from bench/diagnose_v3_dump.py")
    parser.add_argument("--rules", action="append", default=[], help="--v3: Rules overrides to compare")
    args = parser.parse_args(argv)
    rows = loaded(parser, args.dumps, args.set)
    if args.v3:
        return _main_v3(parser, rows, args.rules, args.changes)
    results = []
    for r in rows:
        try:
            results.append(replayed(r))
        except ValueError as e:
            parser.error(f"record {r['family']}/{r['index']}: {e}")
    verdicts = [v for v, _ in results]
    print("\n".join(family_table(rows, verdicts)))
    print("\n".join(effect_table(rows, verdicts)))
    changed = [(r, v) for r, v in zip(rows, verdicts) if v != r["verdict"]]
    print(f"{len(changed)} of {len(rows)} verdicts differ from the dump's")
    if args.changes:
        for r, v in changed:
            print(f"  {r['family']}/{r['index']:03d} {r['case']}: {r['verdict']} -> {v} (truth {r['effect']})")
    inexact = [(r, v) for r, (v, exact) in zip(rows, results) if not exact]
    if inexact:
        print(
            f"{len(inexact)} verdicts need a new dump: the drift would be named and the dump has no surrogate "
            "null for it (a live run tests it): "
            + ", ".join(f"{r['family']}/{r['index']:03d} {v} (truth {r['effect']})" for r, v in inexact)
        )
    return 0


def _main_v3(parser: argparse.ArgumentParser, rows: list[Line], overrides: list[str], changes: bool) -> int:
    from bench.diagnose_v3_dump import overridden
    from bench.diagnose_v3_replay import replay, table
    from host.diagnose.rules import RULES

    if not all(r.get("v3") for r in rows):
        parser.error("--v3: these dumps are not from bench/diagnose_v3_dump.py (no 'v3' key)")
    try:
        versions = {"current": RULES, **{text: overridden(text) for text in overrides}}
    except ValueError as e:
        parser.error(str(e))
    print("\n".join(table(rows, versions)))
    same = sum(replay(r, RULES).verdict == r["verdict"] for r in rows)
    print(f"{same} of {len(rows)} verdicts under the current rules equal the dump's")
    if changes:
        for text in overrides:
            for r in rows:
                a, b = replay(r, RULES).verdict, replay(r, versions[text]).verdict
                if a != b:
                    print(f"  [{text}] {r['family']}/{r['index']:03d} {r['case']}: {a} -> {b} (truth {r['effect']})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
