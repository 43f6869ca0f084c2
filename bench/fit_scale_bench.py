"""Fits that scale: peak memory and time of ``pmactl fit`` per model on long HIL recordings.

Usage: python bench/fit_scale_bench.py [--samples 1000000] [--scenario mixed] [--seed 1]
                                       [--models pi mpi dpi preisach] [--effect rate_dependence]

Records ``--samples`` samples at 100 Hz with ``pmactl hil record`` (once, in a scratch folder),
then runs ``pmactl fit --model M --train rec.csv`` for each model in its own child process and
reads that child's peak resident memory and CPU time from ``os.wait4`` (the loader's and the
fit's together: what a user's machine needs). Target: every model finishes in at most 1 GB.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LIMIT_MB = 1024.0


def run_child(command: list[str]) -> tuple[int, float, float, float, str]:
    """(exit status, wall s, CPU s, peak RSS MB, first line of output) of one child process."""
    with tempfile.TemporaryFile("w+") as output:
        start = time.perf_counter()
        child = subprocess.Popen(command, stdout=output, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(child.pid, 0)  # this child's own rusage: its peak memory
        child.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - start
        output.seek(0)
        line = (output.read().strip().splitlines() or [""])[0]
    return child.returncode, wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, line[:110]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--samples", type=int, default=1_000_000)
    parser.add_argument("--scenario", default="mixed")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--effect", default="none")
    parser.add_argument("--models", nargs="+", default=["pi", "mpi", "dpi", "preisach"])
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        record = Path(scratch) / "rec.csv"
        subprocess.run(
            ["pmactl", "hil", "record", "--scenario", args.scenario, "--seed", str(args.seed), "--effect", args.effect,
             "--duration", str(args.samples / 100.0), "--out", str(record)],
            check=True, capture_output=True,
        )  # fmt: skip
        print(
            f"\n**pmactl fit on {args.samples} HIL samples** ({args.scenario}, seed {args.seed}, "
            f"effect {args.effect}), one child process per model\n"
        )
        print("| model | exit | wall [s] | CPU [s] | peak RSS [MB] | within 1 GB | first line of output |")
        print("|---|---:|---:|---:|---:|---|---|")
        for model in args.models:
            code, wall, cpu, rss, line = run_child(["pmactl", "fit", "--model", model, "--train", str(record)])
            within = "yes" if rss <= LIMIT_MB else "NO"
            print(f"| {model} | {code} | {wall:.1f} | {cpu:.1f} | {rss:.0f} | {within} | {line} |")
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
