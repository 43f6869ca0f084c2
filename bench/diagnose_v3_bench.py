"""Benchmark of diagnosis v3 against the targets of issue 33: wall time, CPU time, peak memory
and progress lines for one long record and for many short runs, idle and beside a busy process.

Usage: python bench/diagnose_v3_bench.py [--idle-only | --busy-only] [--busy-threads K]
       [--composite-draws N] [--blas-threads K]

Rows: the HIL's mixed protocol at 100 Hz with creep hidden, 40 000 samples in one file; and
40 runs of 200 samples (an 8 000-sample recording cut into 40 files, each restarting ``t`` at
0). Each row runs ``diagnose_runs`` with progress lines on (as ``pmactl diagnose`` does for more
than 10 000 samples or 10 runs) in a fresh process and reports its wall time, its CPU time
(user + system), its peak resident memory, when its first stderr line came and the longest
silence on stderr, and the ratio of wall time and memory to the targets (<= 1 meets it). Each
row is run idle and then with a competing CPU-bound process (numpy matrix products on
``--busy-threads`` BLAS threads, default 1) running throughout, as on a shared 2-core machine.
``--blas-threads K``: cap the diagnosis's BLAS threads (OPENBLAS/OMP/MKL_NUM_THREADS=K; default:
as installed). ``--composite-draws N``: with the composite structural null on.
Targets (issue 33): 40 000 samples in <= 15 s wall and <= 1 GB on 2 busy cores; 40 runs of 200
samples in <= 10 s; a progress line on stderr for anything longer than a few seconds.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
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
result = diagnose_runs(runs, rules=replace(RULES, composite_draws=int(sys.argv[1])), progress=True)
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

THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
# issue 33's targets: (wall s, peak MB) per row
TARGETS = {"40000 samples, 1 file": (15.0, 1024.0), "40 runs x 200 samples": (10.0, 1024.0)}


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


def _option(argv: list[str], name: str, default: str) -> str:
    return argv[argv.index(name) + 1] if name in argv else default


def measure(paths: list[Path], draws: str, env: dict[str, str]) -> dict[str, float | str]:
    """One diagnosis in a fresh process: its JSON line plus when stderr lines came (s after start)."""
    start = time.perf_counter()
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, draws, *map(str, paths)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    stamps: list[float] = []
    errors: list[str] = []

    def read_stderr() -> None:
        assert child.stderr is not None
        for line in child.stderr:
            stamps.append(time.perf_counter() - start)
            errors.append(line)

    reader = threading.Thread(target=read_stderr)
    reader.start()
    assert child.stdout is not None
    out = child.stdout.read()
    child.wait()
    reader.join()
    if child.returncode != 0:
        raise RuntimeError("".join(errors[-20:]))
    row: dict[str, float | str] = json.loads(out.strip().splitlines()[-1])
    ends = [0.0, *stamps, time.perf_counter() - start]
    row["first_line_s"] = stamps[0] if stamps else float("nan")
    row["longest_silence_s"] = max(b - a for a, b in zip(ends[:-1], ends[1:]))
    row["lines"] = len(stamps)
    return row


def main(argv: list[str]) -> int:
    if "-h" in argv or "--help" in argv:
        print(__doc__)
        return 0
    base_env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    env = dict(base_env)
    blas = _option(argv, "--blas-threads", "")
    if blas:
        env.update({k: blas for k in THREAD_VARIABLES})
    busy_env = dict(base_env, **{k: _option(argv, "--busy-threads", "1") for k in THREAD_VARIABLES})
    draws = _option(argv, "--composite-draws", "0")
    phases = [False, True]
    if "--idle-only" in argv:
        phases = [False]
    if "--busy-only" in argv:
        phases = [True]
    print(
        f"cores: {os.cpu_count()}; diagnosis BLAS threads: {blas or 'as installed'}; competing process: "
        f"{busy_env['OPENBLAS_NUM_THREADS']} BLAS thread(s); composite draws: {draws}"
    )
    print(
        f"{'data':>22} {'busy':>5} {'wall s':>7} {'CPU s':>7} {'peak MB':>8} {'wall/target':>11} "
        f"{'MB/target':>9} {'1st line s':>10} {'max silence s':>13} {'cause':>16}"
    )
    with tempfile.TemporaryDirectory() as tmp_name:
        tmp = Path(tmp_name)
        rows = [("40000 samples, 1 file", one_file(40_000, tmp)), ("40 runs x 200 samples", short_runs(40, 200, tmp))]
        for busy_phase in phases:
            busy = subprocess.Popen([sys.executable, "-c", BUSY], env=busy_env) if busy_phase else None
            try:
                for label, paths in rows:
                    row = measure(paths, draws, env)
                    wall_target, mb_target = TARGETS[label]
                    print(
                        f"{label:>22} {'yes' if busy else 'no':>5} {row['seconds']:>7.1f} {row['cpu_s']:>7.1f} "
                        f"{row['peak_mb']:>8.0f} {float(row['seconds']) / wall_target:>11.2f} "
                        f"{float(row['peak_mb']) / mb_target:>9.2f} {row['first_line_s']:>10.1f} "
                        f"{row['longest_silence_s']:>13.1f} {row['cause']:>16}",
                        flush=True,
                    )
            finally:
                if busy:
                    busy.terminate()
                    busy.wait()
    print("wall/target and MB/target <= 1 meet issue 33; 'max silence': the longest time without a stderr line")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
