"""Benchmark of diagnosis v3: wall time, CPU time and peak memory for one long record and for
many short runs.

Usage: python bench/diagnose_v3_bench.py [--busy] [--composite-draws N]

Rows: the HIL's mixed protocol at 100 Hz with creep hidden, 10 000 and 40 000 samples in one
file; and 40 runs of 200 samples (a 8 000-sample recording cut into 40 files, each restarting
``t`` at 0). Each row runs ``diagnose_runs`` in a fresh process (default threading) and reports
wall time, the process's CPU time (user + system) and its peak resident memory. ``--busy``: another
CPU-bound process (numpy matrix products) runs throughout, as on a shared 2-core machine.
``--composite-draws N``: with the composite structural null on (N simulated records per class).
Targets (issue 33): 40 000 samples in <= 15 s and <= 1 GB; 40 runs of 200 samples in <= 10 s.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from hil.record import record, write_recording

CHILD = """
import json, resource, sys, time, warnings
warnings.simplefilter("ignore")
from host.data import load_measurement
from dataclasses import replace
from host.diagnose.rules import RULES
from host.diagnose.v3 import diagnose_runs
start = time.perf_counter()
runs = [load_measurement(p) for p in sys.argv[2:]]
loaded = time.perf_counter() - start
result = diagnose_runs(runs, rules=replace(RULES, composite_draws=int(sys.argv[1])))
usage = resource.getrusage(resource.RUSAGE_SELF)
print(json.dumps({"seconds": time.perf_counter() - start, "load_s": loaded, "cpu_s": usage.ru_utime + usage.ru_stime,
                  "cause": result.cause, "peak_mb": usage.ru_maxrss / 1024}))
"""

BUSY = """
import numpy as np
a = np.random.default_rng(0).normal(size=(600, 600))
while True:
    a = np.tanh(a @ a.T / 600.0)
"""


def one_file(n: int, tmp: Path) -> list[Path]:
    return [write_recording(record("mixed", 1, n / 100.0, "creep"), tmp / f"{n}.csv")]


def short_runs(count: int, length: int, tmp: Path) -> list[Path]:
    whole = record("mixed", 2, count * length / 100.0, "none")
    paths = []
    for i in range(count):
        sl = slice(i * length, (i + 1) * length)
        t = np.arange(length) * 0.01
        path = tmp / f"run{i:02d}.csv"
        np.savetxt(
            path,
            np.column_stack([t, whole.u[sl], whole.y[sl]]),
            delimiter=",",
            header="t,u,y",
            comments="",
            fmt="%.5f",
        )
        paths.append(path)
    return paths


def main(argv: list[str]) -> int:
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    busy = subprocess.Popen([sys.executable, "-c", BUSY], env=env) if "--busy" in argv else None
    draws = argv[argv.index("--composite-draws") + 1] if "--composite-draws" in argv else "0"
    print(f"another CPU-bound process: {'yes' if busy else 'no'}; cores: {os.cpu_count()}; composite draws: {draws}")
    print(f"{'data':>22} {'wall s':>7} {'CPU s':>7} {'load s':>7} {'peak MB':>8} {'cause':>16}")
    try:
        with tempfile.TemporaryDirectory() as tmp_name:
            tmp = Path(tmp_name)
            rows = [("10000 samples, 1 file", one_file(10_000, tmp)), ("40000 samples, 1 file", one_file(40_000, tmp))]
            rows.append(("40 runs x 200 samples", short_runs(40, 200, tmp)))
            for label, paths in rows:
                out = subprocess.run(
                    [sys.executable, "-c", CHILD, draws, *map(str, paths)],
                    capture_output=True,
                    text=True,
                    check=True,
                    env=env,
                )
                row = json.loads(out.stdout.strip().splitlines()[-1])
                print(
                    f"{label:>22} {row['seconds']:>7.1f} {row['cpu_s']:>7.1f} {row['load_s']:>7.1f} "
                    f"{row['peak_mb']:>8.0f} {row['cause']:>16}",
                    flush=True,
                )
    finally:
        if busy:
            busy.terminate()
            busy.wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
