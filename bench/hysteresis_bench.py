"""Benchmark of the hysteresis core: per-step cost and identification scaling.

Usage: python bench/hysteresis_bench.py [--quick]

Table 1: cost of one ``step()`` of each model at 25 operators (Preisach: 25 grid intervals),
forward and inverse, for the reference model object and its lookup-table form
(``CompiledModel``, what the edge runs), median and p99 in microseconds over 20 000 steps of
a random walk. Each step is timed individually with ``perf_counter_ns`` (timer overhead,
~0.05 us, included). DPI and Preisach models evaluate through the same kernel as their
table, so their two rows differ only by the wrapper.

Table 2: identification time against data length (10^3 .. 10^6 samples; --quick stops at
10^5) for each estimator with its defaults, on a PI-generated signal with noise.
"""

from __future__ import annotations

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
    print("\nIdentification time [s] against data length (default estimator settings)")
    print(f"{'model':<9} " + " ".join(f"{n:>10}" for n in lengths))
    data = {n: training_data(n) for n in lengths}
    for name in ESTIMATORS:
        cells = []
        for n in lengths:
            u, y = data[n]
            cells.append(make_estimator(name).fit(u, y).fit_seconds_)
        print(f"{name:<9} " + " ".join(f"{c:>10.3f}" for c in cells))


def main(argv: list[str]) -> int:
    step_table()
    fit_table(100_000 if "--quick" in argv else 1_000_000)
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
