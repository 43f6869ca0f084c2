"""Benchmark of the hysteresis core: per-step cost and identification scaling.

Usage: python bench/hysteresis_bench.py [--quick] [--busy-only]

Table 1: cost of one ``step()`` of each model at 25 operators (Preisach: 25 grid intervals),
forward and inverse, for the reference model object and its lookup-table form
(``CompiledModel``, what the edge runs), median and p99 in microseconds over 20 000 steps of
a random walk. Each step is timed individually with ``perf_counter_ns`` (timer overhead,
~0.05 us, included). DPI and Preisach models evaluate through the same kernel as their
table, so their two rows differ only by the wrapper.

Table 2: identification time against data length (10^3 .. 10^6 samples; --quick stops at
10^5) for each estimator with its defaults, on a PI-generated signal with noise, wall and CPU.

Table 3, the busy machine: the same fits while another CPU-bound process runs (one per
core but one, at least one), each configuration in a fresh process with no *_NUM_THREADS in
its environment: BLAS left at its default threads (one per core, as a user's shell has it),
against the threads sized by ``host.identify.threads`` (what every fit does now), and the
sized fits on the machine without the competitor as the reference. Wall and CPU seconds of
the fit itself (``fit_seconds_``, ``fit_cpu_seconds_``); CPU far above wall means threads
ran in parallel, wall far above CPU means the fit waited for a core. The machine is shared:
compare the columns of one run, not runs of different days.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import numpy as np

from edge.hysteresis.lut import CompiledModel
from host.identify import ESTIMATORS
from host.workflow import make_estimator, rest_state

STEPS = 20_000


def walk(n: int, lo: float, hi: float, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    steps = rng.normal(0.0, 0.02 * (hi - lo), n)
    return lo + (hi - lo) * (0.5 + 0.45 * np.sin(np.cumsum(steps) / (hi - lo) * 3.0))


def training_data(n: int) -> tuple[np.ndarray, np.ndarray]:
    """A slow sine with loops on top plus noise; output from a nonlinear PI-like plant."""
    t = np.linspace(0, 1, n)
    u = 2.0 - 2.0 * np.cos(2 * np.pi * 20 * t) * (0.4 + 0.6 * np.abs(np.sin(2 * np.pi * 3 * t)))
    from edge.hysteresis.pi import PIModel

    plant = PIModel(np.arange(12) * 0.15, 0.6 * np.exp(-0.4 * np.arange(12) * 0.15))
    plant.reset(0.0, "descending")
    y = np.tanh(plant.simulate(u) / 3.0) * 3.0 + np.random.default_rng(1).normal(0, 0.01, n)
    return u, y


def time_steps(step, inputs: np.ndarray) -> tuple[float, float]:
    clock = time.perf_counter_ns
    samples = np.empty(inputs.size)
    for i, value in enumerate(inputs.tolist()):
        start = clock()
        step(value)
        samples[i] = clock() - start
    return float(np.median(samples)) / 1e3, float(np.percentile(samples, 99)) / 1e3


def step_table() -> None:
    u, y = training_data(20_000)
    print(f"Per-step cost, 25 operators, {STEPS} steps [us]")
    print(f"{'model':<9} {'direction':<8} {'reference med':>14} {'p99':>7} {'table med':>10} {'p99':>7}")
    for name in ESTIMATORS:
        estimator = make_estimator(name, operators=25).fit(u, y)
        forward, inverse = rest_state(estimator.model_, float(u.min()))
        for direction, model in (("forward", forward), ("inverse", inverse)):
            lo, hi = model.memory_range
            inputs = walk(STEPS, lo, hi)
            compiled = CompiledModel(model.compile())
            ref_med, ref_p99 = time_steps(model.step, inputs)
            lut_med, lut_p99 = time_steps(compiled.step, inputs)
            print(f"{name:<9} {direction:<8} {ref_med:>14.2f} {ref_p99:>7.2f} {lut_med:>10.2f} {lut_p99:>7.2f}")


def fit_table(largest: int) -> None:
    lengths = [n for n in (1_000, 10_000, 100_000, 1_000_000) if n <= largest]
    print("\nIdentification time against data length (default estimator settings), wall / CPU [s]")
    print(f"{'model':<9} " + " ".join(f"{n:>15}" for n in lengths))
    data = {n: training_data(n) for n in lengths}
    for name in ESTIMATORS:
        cells = []
        for n in lengths:
            u, y = data[n]
            estimator = make_estimator(name).fit(u, y)
            cells.append(f"{estimator.fit_seconds_:.3f} / {estimator.fit_cpu_seconds_:.3f}")
        print(f"{name:<9} " + " ".join(f"{c:>15}" for c in cells))


THREAD_VARIABLES = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
BUSY_SIZES: tuple[tuple[int, dict[str, int]], ...] = (
    (10_000, {}),
    (100_000, {}),
    (20_000, {"preisach": 40}),
)  # the last: a finer Everett grid
# Measured 2026-11-24, 2 cores, load ~6 from other jobs (``python bench/hysteresis_bench.py --busy-only``):
# busy with BLAS default vs sized, wall / CPU [s]: dpi 10^4 4.06 / 0.90 vs 0.37 / 0.06; preisach 10^5
# 15.1 / 3.4 vs 4.7 / 0.7; preisach with 40 intervals on 2*10^4 72.4 / 16.6 vs 7.9 / 1.1.


def fit_worker(n: int, operators: dict[str, int]) -> None:
    """Child process: fit every model on ``n`` samples, print wall/CPU/threads as JSON."""
    u, y = training_data(n)
    names = list(operators) or list(ESTIMATORS)
    results = {}
    for name in names:
        estimator = make_estimator(name, operators=operators.get(name)).fit(u, y)
        results[name] = (estimator.fit_seconds_, estimator.fit_cpu_seconds_, estimator.blas_threads_)
    print(json.dumps(results))


def run_worker(n: int, operators: dict[str, int], sized: bool) -> dict[str, list[float]]:
    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    if sized:
        env.pop("PMACTL_BLAS_THREADS", None)
    else:
        env["PMACTL_BLAS_THREADS"] = "0"  # leave BLAS at its default: one thread per core
    args = [sys.executable, __file__, "--fit-worker", str(n), json.dumps(operators)]
    out = subprocess.run(args, env=env, capture_output=True, text=True, check=True).stdout
    return json.loads(out)


def busy_table() -> None:
    from host.identify.threads import available_cpus

    cpus = available_cpus()
    competitors = max(1, cpus - 1)
    print(f"\nBusy machine: {cpus} cores, {competitors} CPU-bound competitor(s); wall / CPU [s] of the fit")
    print(f"(1-minute load average before: {os.getloadavg()[0]:.1f}; 'as found' runs without our competitor)")
    print(
        f"{'model':<9} {'samples':>8} {'as found, sized':>16} {'busy, BLAS default':>20} {'busy, sized':>16} "
        f"{'threads':>8}"
    )
    idle = {n: run_worker(n, ops, sized=True) for n, ops in BUSY_SIZES}
    spinners = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(competitors)]
    try:
        time.sleep(1.0)  # let the scheduler see them
        default = {n: run_worker(n, ops, sized=False) for n, ops in BUSY_SIZES}
        sized = {n: run_worker(n, ops, sized=True) for n, ops in BUSY_SIZES}
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()
    for n, _ in BUSY_SIZES:
        for name in idle[n]:
            cells = [f"{r[n][name][0]:.3f} / {r[n][name][1]:.3f}" for r in (idle, default, sized)]
            print(
                f"{name:<9} {n:>8} {cells[0]:>16} {cells[1]:>20} {cells[2]:>16} "
                f"{int(default[n][name][2]) or 'default'!s:>4}/{int(sized[n][name][2])}"
            )


def main(argv: list[str]) -> int:
    if argv[:1] == ["--fit-worker"]:
        fit_worker(int(argv[1]), json.loads(argv[2]))
        return 0
    if "--busy-only" not in argv:
        step_table()
        fit_table(100_000 if "--quick" in argv else 1_000_000)
    busy_table()
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
