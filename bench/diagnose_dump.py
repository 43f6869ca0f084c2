"""Dump what every verdict of the diagnosis is decided from, so a decision rule can be replayed.

Usage: python bench/diagnose_dump.py OUT.jsonl [--set tuning,fresh,...] [--effect none,creep,...]
       [--duration S] [--workers N]      (default: every family and effect, 100 s records)

A full scorecard over every family takes about an hour of CPU on this machine; a change to the
decision rules (a floor, a margin, a surrogate test) does not need any model refitted. This runs
:func:`host.diagnose.run.diagnose` once per record and appends one JSON line per record to
``OUT.jsonl``: family, index, case, true effect and form, the verdict, the baseline's actuator
lag (negative: an input lead), the CPU seconds and the
:class:`host.diagnose.decide.DecisionInputs` (every candidate's fold gains, surrogate gains and
drift margins, the noise floor, the columns' correlation with time, the residual signatures).
``bench/diagnose_replay.py`` then decides every record again with the working tree's rules in
seconds. A record the diagnosis refuses (``DataError``) is written with the verdict ``refused``
and its message. The file is appended to and records already in it are skipped, so an
interrupted run resumes where it stopped; a dump belongs to the code that made it (a change to
a candidate's fit needs a new dump).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from multiprocessing import Pool
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from edge.errors import DataError  # noqa: E402
from host.diagnose.run import diagnose  # noqa: E402
from tests.plants.families import FAMILIES  # noqa: E402
from tests.plants.family import Case  # noqa: E402

Job = tuple[str, int, Case]


def dumped(job: Job) -> dict[str, object]:
    """One record's line: its case, truth, verdict, CPU seconds and decision inputs."""
    family, index, case = job
    m, _ = FAMILIES[family][1](case)
    start = time.process_time()
    line: dict[str, object] = {"family": family, "index": index, "case": case.name, "effect": case.effect}
    line["form"] = case.form
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            d = diagnose(m, progress=False)
        line.update(verdict=d.cause, actuator_lag_s=d.context.lag_s)
        line["decision"] = d.decision.as_json() if d.decision else None
    except DataError as e:
        line.update(verdict="refused", message=str(e), decision=None)
    line["cpu_s"] = time.process_time() - start
    return line


def done_in(path: Path) -> set[tuple[str, int]]:
    """(family, index) of every record already in the dump at ``path``."""
    if not path.exists():
        return set()
    with path.open() as f:
        return {(row["family"], int(row["index"])) for row in map(json.loads, f) if row}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("out", type=Path, help="the dump (JSON lines), appended to")
    parser.add_argument("--set", default=",".join(FAMILIES), help=f"comma-separated, of {', '.join(FAMILIES)}")
    parser.add_argument("--effect", help="comma-separated true effects to keep (none: the effect-free records)")
    parser.add_argument("--duration", type=float, default=100.0, metavar="S")
    parser.add_argument("--workers", type=int, default=1)
    args = parser.parse_args(argv)
    names = [s for s in args.set.split(",") if s]
    unknown = [s for s in names if s not in FAMILIES]
    if unknown or not names:
        parser.error(f"--set: unknown family {', '.join(unknown) or '(none given)'}; use some of {', '.join(FAMILIES)}")
    if args.duration <= 0 or args.workers < 1:
        parser.error("--duration must be > 0 s and --workers >= 1")
    done = done_in(args.out)
    jobs = [(s, i, c) for s in names for i, c in enumerate(FAMILIES[s][0](args.duration)) if (s, i) not in done]
    if args.effect:
        jobs = [job for job in jobs if job[2].effect in args.effect.split(",")]
    print(f"{len(jobs)} records to diagnose ({len(done)} already in {args.out})", file=sys.stderr)
    with Pool(args.workers) as pool, args.out.open("a") as out:
        for k, line in enumerate(pool.imap_unordered(dumped, jobs), 1):
            out.write(json.dumps(line) + "\n")
            out.flush()
            print(f"{k}/{len(jobs)} {line['case']}: {line['verdict']} ({line['cpu_s']:.1f} s CPU)", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
