"""Benchmark of pmactl diagnose: wall time, CPU time and peak memory against data length.

Usage: python bench/diagnose_bench.py [--quick | --long] [--busy]

Each row records the mixed protocol on the HIL at 100 Hz (a creep effect hidden; the 2 000 000
sample row repeats a 40 000 sample recording end to end) and runs ``pmactl diagnose`` on it in a
fresh process with the default threading (no *_NUM_THREADS set), reporting wall time, the
process's CPU time (user + system) and its peak resident memory. With ``--busy`` another
CPU-bound process (numpy matrix products with its default BLAS threads) runs throughout, as on a
shared 2-core machine. Targets: 40 000 samples in <= 15 s and <= 1 GB; 2 000 000 samples finish
(decimated, with a warning). ``--quick`` stops at 40 000 samples; ``--long`` runs only the
2 000 000 sample row.
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

LENGTHS = (10_000, 40_000, 200_000, 2_000_000)

CHILD = """
import json, resource, sys, time, warnings
warnings.simplefilter("ignore")
from host.data import load_measurement
from host.diagnose.run import diagnose
start, cpu = time.perf_counter(), time.process_time()
m = load_measurement(sys.argv[1])
loaded = time.perf_counter() - start
result = diagnose(m, progress=False)
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


def recording(n: int, tmp: Path) -> Path:
    path = tmp / f"{n}.csv"
    if n <= 200_000:
        return write_recording(record("mixed", 1, n / 100.0, "creep"), path)
    base = record("mixed", 1, 400.0, "creep")
    reps = int(np.ceil(n / base.t.size))
    cols = [np.tile(v, reps)[:n] for v in (base.u, base.y, base.p, base.load, base.temperature)]
    t = np.arange(n) * 0.01
    np.savetxt(
        path,
        np.column_stack([t, *cols]),
        delimiter=",",
        header="t,u,y,p,load,temperature",
        comments="",
        fmt=["%.2f", "%.5f", "%.4f", "%.5f", "%.3f", "%.2f"],
    )
    return path


def main(argv: list[str]) -> int:
    lengths = [n for n in LENGTHS if n <= 40_000] if "--quick" in argv else list(LENGTHS)
    if "--long" in argv:
        lengths = [LENGTHS[-1]]
    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    busy = subprocess.Popen([sys.executable, "-c", BUSY], env=env) if "--busy" in argv else None
    print(f"another CPU-bound process running: {'yes' if busy else 'no'}; cores: {os.cpu_count()}")
    print(f"{'samples':>9} {'wall s':>7} {'CPU s':>7} {'load s':>7} {'peak MB':>8} {'cause':>10}")
    try:
        with tempfile.TemporaryDirectory() as tmp:
            for n in lengths:
                path = recording(n, Path(tmp))
                out = subprocess.run(
                    [sys.executable, "-c", CHILD, str(path)], capture_output=True, text=True, check=True, env=env
                )
                row = json.loads(out.stdout.strip().splitlines()[-1])
                print(
                    f"{n:>9} {row['seconds']:>7.1f} {row['cpu_s']:>7.1f} {row['load_s']:>7.1f} "
                    f"{row['peak_mb']:>8.0f} {row['cause']:>10}",
                    flush=True,
                )
    finally:
        if busy:
            busy.terminate()
            busy.wait()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
