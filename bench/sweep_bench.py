"""Benchmark of pmactl sweep: the HIL regression matrix on 1 and 2 local workers and on Ray.

Usage: python bench/sweep_bench.py [--seeds 5] [--duration 25] [--modes 1,2,ray] [--keep DIR]

The matrix is docs/examples/hil-regression.sweep.toml's (6 hidden effects x seeds x the three
controllers, 25 s of lockstep tracking each) with one bundle fitted beforehand, as a pre-deploy
regression tests one bundle. Each mode runs ``pmactl sweep`` as a user would, in a fresh
process and output folder. Columns:

* wall: the whole command (Ray: including starting and stopping the local instance);
* cells CPU: the sum of the cells' own CPU time (user + system of their subprocesses);
* all CPU: CPU of every process the command waited for (the sweep, its cells; on Ray also the
  Ray daemons, while Ray's workers are reaped by its raylet and may be missed);
* speed-up: wall of 1 worker / wall of the mode, and efficiency = speed-up / workers.

Then the rows of every mode are compared without timing columns (same seeds, same values),
and the cost of the same matrix on N machines is worked out from the measured cell time.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from host.sweep.matrix import load_matrix  # noqa: E402
from host.sweep.report import comparable  # noqa: E402

MATRIX = """
kind = "hil-run"
timeout_s = 300
retries = 1

[axes]
effect = ["none", "rate_dependence", "creep", "transport_delay", "load_dependence", "temperature_drift"]
seed = "1..{seeds}"
controller = ["pid", "pid+ff", "pid+ff+nn"]

[values]
duration = {duration}
settle = 5

[paths]
bundle = "{bundle}"

[files.config]
template = "{{hil_config}}"
name = "rig.toml"
set = {{ "rig.io" = "sim://rig?adc=ADS1015&clock=lockstep&effect={{effect}}&seed={{seed}}" }}

[thresholds]
"run.faults.n" = {{ max = 0 }}
"run.rms_error" = [
    {{ max = 8.0, where = {{ controller = "pid" }} }},
    {{ max = 5.0, where = {{ controller = "pid+ff" }} }},
    {{ max = 5.0, where = {{ controller = "pid+ff+nn" }} }},
]
"""


def children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_mode(mode: str, matrix: Path, out: Path) -> dict[str, float | str]:
    args = [sys.executable, "-m", "host.cli", "sweep", str(matrix), "--out", str(out), "--json"]
    args += ["--ray", "local", "--workers", "2"] if mode == "ray" else ["--workers", mode]
    cpu0, t0 = children_cpu(), time.monotonic()
    done = subprocess.run(args, capture_output=True, text=True)
    wall, cpu = time.monotonic() - t0, children_cpu() - cpu0
    if done.returncode not in (0, 1):
        raise SystemExit(f"mode {mode}: pmactl sweep exited {done.returncode}: {done.stderr.strip()[-500:]}")
    summary = json.loads(done.stdout)
    with open(out / "results.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    cell_walls = sorted(float(r["elapsed_s"]) for r in rows)
    return {
        "mode": "Ray (local, 2 CPUs)" if mode == "ray" else f"local, {mode} worker{'s' if mode != '1' else ''}",
        "workers": 2.0 if mode == "ray" else float(mode),
        "wall": wall,
        "cells_cpu": sum(float(r["cpu_s"]) for r in rows),
        "all_cpu": cpu,
        "cell_wall_median": cell_walls[len(cell_walls) // 2],
        "cells": float(summary["cells"]),
        "pass": float(summary["pass"]),
        "fail": float(summary["fail"]),
        "error": float(summary["error"]),
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--duration", type=float, default=25.0)
    parser.add_argument("--modes", default="1,2,ray")
    parser.add_argument("--keep", metavar="DIR", help="keep the outputs here (default: a temporary folder)")
    args = parser.parse_args()
    root = Path(args.keep) if args.keep else Path(tempfile.mkdtemp(prefix="sweep-bench-"))
    root.mkdir(parents=True, exist_ok=True)
    bundle = root / "bundle"
    if not bundle.exists():
        train = REPO / "host" / "example_data" / "pma_triangles.csv"
        subprocess.run(
            [sys.executable, "-m", "host.cli", "fit", "--model", "preisach", "--train", str(train), "--units", "bar,mm",
             "--save", str(bundle)], check=True, capture_output=True,
        )  # fmt: skip
    matrix = root / "hil-regression-bench.sweep.toml"
    matrix.write_text(MATRIX.format(seeds=args.seeds, duration=args.duration, bundle=bundle))
    modes = args.modes.split(",")
    print(f"{os.cpu_count()} CPUs; matrix {len(load_matrix(matrix).cells)} cells; outputs in {root}")
    results = []
    for mode in modes:
        out = root / f"out-{mode}"
        if out.exists():
            raise SystemExit(f"{out} exists (a resumed run would measure nothing); remove it or use another --keep")
        results.append(run_mode(mode, matrix, out))
        r = results[-1]
        print(
            f"  {r['mode']}: {r['wall']:.1f} s wall, "
            f"{r['pass']:.0f} pass / {r['fail']:.0f} fail / {r['error']:.0f} error"
        )
    base = next((r for r in results if r["workers"] == 1.0), results[0])
    print()
    print("| mode | wall [s] | cells CPU [s] | all CPU [s] | median cell wall [s] | speed-up | efficiency |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for r in results:
        speedup = float(base["wall"]) / float(r["wall"])
        print(
            f"| {r['mode']} | {r['wall']:.1f} | {r['cells_cpu']:.1f} | {r['all_cpu']:.1f} "
            f"| {r['cell_wall_median']:.2f} | {speedup:.2f} | {speedup / float(r['workers']):.2f} |"
        )
    print()
    timing = load_matrix(matrix).timing_columns
    tables = {m: _comparable_rows(root / f"out-{m}", timing) for m in modes}
    first = modes[0]
    for mode in modes[1:]:
        same = tables[mode] == tables[first]
        print(f"rows of {mode} vs {first} without timing columns: {'identical' if same else 'DIFFERENT'}")
    _on_paper(base)
    return 0


def _comparable_rows(out: Path, timing: tuple[str, ...]) -> list[dict[str, str]]:
    with open(out / "results.csv", newline="") as f:
        return [comparable(r, timing) for r in sorted(csv.DictReader(f), key=lambda r: int(r["index"]))]


def _on_paper(base: dict[str, float | str]) -> None:
    """The same matrix on N machines: cells spread over N x cores slots, plus Ray's fixed costs.

    Two per-cell costs: this run's wall per cell at 1 worker (what this shared VM gave), and the
    cells' CPU per cell (what one free core needs; process start-up included).
    """
    cells = int(base["cells"])
    wall_cell, cpu_cell = float(base["wall"]) / cells, float(base["cells_cpu"]) / cells
    print()
    print(f"On paper ({cells} cells; per cell {wall_cell:.2f} s wall here at 1 worker, {cpu_cell:.2f} s CPU;")
    print("Ray: ~10 s to start or join, ~ms per task; physical rigs: pma_rig = 1 per machine, 30 s real time per cell)")
    print("| machines x cores | wall, this VM's cell time | wall, free cores | physical rigs |")
    print("|---|---:|---:|---:|")
    for machines, cores in ((1, 2), (2, 2), (4, 2), (8, 2), (4, 16), (16, 16)):
        rounds = math.ceil(cells / (machines * cores))
        ray = 10.0 if machines > 1 else 0.0
        physical = math.ceil(cells / machines) * 30.0
        print(
            f"| {machines} x {cores} | {rounds * wall_cell + ray:.0f} s | {rounds * cpu_cell + ray:.0f} s "
            f"| {physical / 60:.1f} min |"
        )


if __name__ == "__main__":
    raise SystemExit(main())
