"""Dump what every verdict of the diagnosis is decided from, so a decision rule can be replayed.

Usage: python bench/diagnose_dump.py OUT.jsonl [--set tuning,fresh,...] [--effect none,creep,...]
       [--duration S] [--workers N]      (default: every family and effect, 100 s records)

A full scorecard over every family takes about 1.5 h of CPU on this machine (7 s a record); a
change to the decision rules (a floor, a margin, a surrogate test) needs no model refitted. This runs
:func:`host.diagnose.run.diagnose` once per record and appends one JSON line per record to
``OUT.jsonl``: family, index, case, true effect and form, the verdict, the baseline's actuator
lag (negative: an input lead), the CPU seconds and the
:class:`host.diagnose.decide.DecisionInputs` (every candidate's fold gains, surrogate gains and
drift margins, the noise floor, the columns' correlation with time, the residual signatures).
``bench/diagnose_replay.py`` then decides every record again with the working tree's rules in
seconds. Each line holds the scorecard's row of the record (``bench/diagnose_scorecard.py``): a
record the diagnosis refuses (``DataError``) has the verdict ``refused`` and its message; one
whose diagnosis fails otherwise is written with ``error`` and the exception (a defect to fix;
the run goes on). The file is appended to and records already in it are
skipped, so an interrupted run resumes where it stopped (a last line cut by the interruption is
dropped and its record diagnosed again). Every line carries the record duration and the code
version (``git describe --always --dirty``); a dump belongs to the code that made it, so
resuming with another duration or version is refused: start a new file.
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import time
from multiprocessing import Pool
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.diagnose_scorecard import diagnosed  # noqa: E402
from bench.plants.families import FAMILIES, family_names  # noqa: E402
from bench.plants.family import Case  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from diagnose_replay import DumpError, Line, read_dump  # noqa: E402

Job = tuple[str, int, Case]


def dumped(job: Job) -> Line:
    """One record's line: its case, truth and the scorecard's row of it
    (:func:`bench.diagnose_scorecard.diagnosed`: verdict, CPU seconds, decision inputs, ...)."""
    family, index, case = job
    m, _ = FAMILIES[family][1](case)
    line: Line = {"family": family, "index": index, "case": case.name, "effect": case.effect, "form": case.form}
    start = time.process_time()
    try:
        line.update(diagnosed(m))
    except Exception as e:  # noqa: BLE001 - a failed record is written down, the others still run
        line.update(verdict="error", message=f"{type(e).__name__}: {e}", decision=None)
        line["cpu_s"] = time.process_time() - start
    return line


def code_version() -> str:
    """``git describe --always --dirty`` of this checkout, or ``unknown`` outside a git checkout."""
    try:
        done = subprocess.run(
            ["git", "describe", "--always", "--dirty"],
            cwd=Path(__file__).resolve().parent,
            capture_output=True,
            text=True,
            timeout=10,
        )
    except (OSError, subprocess.TimeoutExpired):
        return "unknown"
    return done.stdout.strip() if done.returncode == 0 else "unknown"


def without_cut_tail(path: Path) -> bool:
    """Drop a last line that an interrupted write left without its newline; whether one was."""
    data = path.read_bytes()
    if not data or data.endswith(b"\n"):
        return False
    path.write_bytes(data[: data.rfind(b"\n") + 1])
    return True


def resumed(parser: argparse.ArgumentParser, out: Path, duration_s: float, version: str) -> set[tuple[str, int]]:
    """(family, index) of every record already in ``out``, after checking it can be appended to
    with this duration and code version (a problem is one line from ``parser``, exit 2)."""
    if out.is_dir():
        parser.error(f"{out}: is a folder; give a file name for the dump")
    if not out.parent.is_dir():
        parser.error(f"{out.parent}: no such folder; create it or write the dump elsewhere")
    if not out.exists():
        return set()
    if without_cut_tail(out):
        print(f"{out}: dropped a last line cut by an interruption; its record is diagnosed again", file=sys.stderr)
    try:
        rows = read_dump(out)
    except DumpError as e:
        parser.error(f"{e}; give a new file for the dump")
    for key, now in (("duration_s", duration_s), ("code", version)):
        before = {row[key] for row in rows if key in row}
        if before and before != {now}:
            parser.error(
                f"{out} holds records made with {key} {', '.join(map(str, sorted(before)))}, not {now}; "
                "a dump belongs to one duration and one code version: give a new file"
            )
    return {(row["family"], int(row["index"])) for row in rows}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path, help="the dump (JSON lines), appended to")
    parser.add_argument("--set", default=",".join(FAMILIES), help=f"comma-separated, of {', '.join(FAMILIES)}")
    parser.add_argument("--effect", help="comma-separated true effects to keep (none: the effect-free records)")
    parser.add_argument("--duration", type=float, default=100.0, metavar="S")
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args(argv)
    try:
        names = family_names(args.set)
    except ValueError as e:
        parser.error(f"--set: {e}")
    if not math.isfinite(args.duration) or args.duration <= 0 or args.workers < 1:
        parser.error("--duration must be a number of seconds > 0 and --workers >= 1")
    version = code_version()
    done = resumed(parser, args.out, args.duration, version)
    jobs = [(s, i, c) for s in names for i, c in enumerate(FAMILIES[s][0](args.duration))]
    if args.effect:
        wanted, known = args.effect.split(","), sorted({c.effect for _, _, c in jobs})
        if not set(wanted) <= set(known):
            parser.error(
                f"--effect: unknown {', '.join(sorted(set(wanted) - set(known)))}; use some of {', '.join(known)}"
            )
        jobs = [job for job in jobs if job[2].effect in wanted]
    todo = [job for job in jobs if (job[0], job[1]) not in done]
    print(f"{len(todo)} records to diagnose ({len(jobs) - len(todo)} already in {args.out})", flush=True)
    written = 0
    try:
        with Pool(args.workers) as pool, args.out.open("a") as out:
            for line in pool.imap_unordered(dumped, todo):
                line.update(duration_s=args.duration, code=version)
                out.write(json.dumps(line) + "\n")
                out.flush()
                written += 1
                print(
                    f"{written}/{len(todo)} {line['case']}: {line['verdict']} ({line['cpu_s']:.1f} s CPU)", flush=True
                )
    except KeyboardInterrupt:
        print(f"interrupted: {written} records written to {args.out}; run the same command to resume", file=sys.stderr)
        return 130
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
