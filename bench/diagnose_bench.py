"""Benchmark of pmactl diagnose: wall time and peak memory against data length.

Usage: python bench/diagnose_bench.py [--quick]

Each row records the mixed protocol on the HIL at 100 Hz (a creep effect hidden), then runs
the diagnosis in a fresh process and reports its wall time and peak resident memory
(``getrusage`` of that process). Target: 40 000 samples in under 30 s
and under 1 GB on this 2-core machine. --quick stops at 40 000 samples.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from hil.record import record, write_recording

LENGTHS = (10_000, 40_000, 100_000, 200_000)

CHILD = """
import json, resource, sys, time
from host.data import load_measurement
from host.diagnose.run import diagnose
start = time.perf_counter()
result = diagnose(load_measurement(sys.argv[1]))
print(json.dumps({"seconds": time.perf_counter() - start, "cause": result.cause,
                  "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def main(argv: list[str]) -> int:
    lengths = [n for n in LENGTHS if n <= 40_000] if "--quick" in argv else list(LENGTHS)
    print(f"{'samples':>8} {'diagnose s':>11} {'peak MB':>8} {'cause':>8}   (record s)")
    with tempfile.TemporaryDirectory() as tmp:
        for n in lengths:
            start = time.perf_counter()
            path = write_recording(record("mixed", 1, n / 100.0, "creep"), Path(tmp) / f"{n}.csv")
            recorded = time.perf_counter() - start
            out = subprocess.run([sys.executable, "-c", CHILD, str(path)], capture_output=True, text=True, check=True)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            print(
                f"{n:>8} {row['seconds']:>11.1f} {row['peak_mb']:>8.0f} {row['cause']:>8}   ({recorded:.1f})",
                flush=True,
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
