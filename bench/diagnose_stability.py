"""How stable are ``pmactl diagnose``'s verdicts when the start (or the end) of a record is cut off?

Usage: python bench/diagnose_stability.py [--set tuning|fresh|blind|...] [--duration S] [--cuts 7,14]
       [--from-end] [--workers N] [--only TEXT]

A verdict that changes when the first 7 or 14 s of a record are dropped says more about where the
record happens to start than about the plant (the issue's check: cutting 7-14 s changed 9 of 18
verdicts). Each record is diagnosed whole and with each cut; printed: one line per record with
its verdicts, then per set how many records kept one verdict over all cuts, how many verdicts
changed per cut, and the named/false-alarm counts per cut. A start cut whose input no longer
reaches its extremes early enough is diagnosed from an assumed state, as ``pmactl diagnose``
does since v8 (before, it was refused and counted as a change). ``--from-end`` cuts the end
instead (what ``pmactl diagnose --stability`` does: the memory start stays where it was, and a
cut assumes a state only when the whole record did). Also printed: how often a named cause is
right when it held over every cut and when it did not (is a stable verdict one to trust?).

CPU: (1 + number of cuts) diagnoses per record, ~4 s each at 100 s; ``--workers 2`` splits
records over two processes (wall time halves on an idle 2-core machine).
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from multiprocessing import Pool
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.diagnose_scorecard import SETS, diagnosed  # noqa: E402
from bench.plants.families import family_names  # noqa: E402
from bench.plants.family import Case  # noqa: E402


def verdicts(job: tuple[str, Case, tuple[float, ...], bool]) -> dict[str, object]:
    """The verdict of ``case`` whole and after each cut [s] (``cut 0`` is the whole record), cut
    from the start or, with ``from_end``, from the end."""
    set_name, case, cuts, from_end = job
    m, _truth = SETS[set_name][1](case)
    out: dict[str, object] = {"set": set_name, "case": case.name, "effect": case.effect}
    whole_assumed = True
    for cut in (0.0, *cuts):
        samples = int(round(cut / m.dt))
        if not cut:
            row = diagnosed(m)
            whole_assumed = bool(row["memory_assumed"])
        elif from_end:  # as --stability: a cut may assume a state only when the whole record did
            row = diagnosed(m.slice(0, len(m) - samples), assume_state=whole_assumed)
        else:
            row = diagnosed(m.slice(samples))
        out[f"cut {cut:g}"] = row["verdict"]
        out[f"cpu {cut:g}"] = row["cpu_s"]
    return out


def summary(rows: list[dict[str, object]], cuts: tuple[float, ...]) -> None:
    """Stability and detection per cut, for one set's rows."""
    keys = [f"cut {c:g}" for c in (0.0, *cuts)]
    stable = sum(len({r[k] for k in keys}) == 1 for r in rows)
    print(f"one verdict over every cut: {stable}/{len(rows)} ({stable / max(1, len(rows)):.0%})")
    for key in keys[1:]:
        changed = [r for r in rows if r[key] != r[keys[0]]]
        moves = Counter(f"{r[keys[0]]}->{r[key]}" for r in changed)
        listed = ", ".join(f"{move} x{count}" for move, count in moves.most_common())
        print(f"  {key} s: {len(changed)}/{len(rows)} changed: {listed}")
    effect_rows = [r for r in rows if r["effect"] != "none"]
    nones = [r for r in rows if r["effect"] == "none"]
    for key in keys:
        named = sum(r[key] == r["effect"] for r in effect_rows)
        false = sum(r[key] not in ("none", "refused") for r in nones)
        refused = sum(r[key] == "refused" for r in rows)
        print(f"  {key} s: named {named}/{len(effect_rows)}, false alarms {false}/{len(nones)}, refused {refused}")
    for label, held in (("held over every cut", True), ("changed with a cut", False)):
        named_rows = [
            r for r in rows if r[keys[0]] not in ("none", "refused") and (len({r[k] for k in keys}) == 1) == held
        ]
        right = sum(r[keys[0]] == r["effect"] for r in named_rows)
        print(f"  a cause named on the whole record that {label}: right {right}/{len(named_rows)}")
    cpu = [float(r[f"cpu {c:g}"]) for r in rows for c in (0.0, *cuts)]  # type: ignore[arg-type]
    print(f"  CPU per diagnosis: median {sorted(cpu)[len(cpu) // 2]:.1f} s, max {max(cpu):.1f} s")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", default="tuning", help=f"comma-separated, of {', '.join(SETS)}")
    parser.add_argument("--duration", type=float, default=100.0, metavar="S")
    parser.add_argument("--cuts", default="7,14", help="seconds cut from the start (or the end), comma-separated")
    parser.add_argument("--from-end", action="store_true", help="cut the end of each record, not its start")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--only", help="run only cases whose name contains this text")
    args = parser.parse_args(argv)
    try:
        sets = family_names(args.set, SETS)
    except ValueError as e:
        parser.error(f"--set: {e}")
    cuts = tuple(float(c) for c in args.cuts.split(","))
    jobs = [
        (name, case, cuts, args.from_end)
        for name in sets
        for case in SETS[name][0](args.duration)
        if not args.only or args.only in case.name
    ]
    with Pool(max(1, args.workers)) as pool:
        rows = []
        for row in pool.imap(verdicts, jobs):
            rows.append(row)
            cells = " ".join(f"{row[f'cut {c:g}']!s:<17}" for c in (0.0, *cuts))
            flag = "    " if len({row[f"cut {c:g}"] for c in (0.0, *cuts)}) == 1 else "FLIP"
            print(f"{flag} {row['case']:<60} {cells}", flush=True)
    for name in sets:
        where = "end" if args.from_end else "start"
        print(f"\n## {name} set, cuts {args.cuts} s from the {where} of {args.duration:g} s records")
        summary([r for r in rows if r["set"] == name], cuts)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
