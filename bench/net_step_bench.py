"""Per-step time of each net on the edge: onnxruntime (as the edge binds it) against the fused numpy step.

Usage: python bench/net_step_bench.py [--steps 20000] [--rounds 5]

Nets: the correction's shape 3-16-16-1 (normalisation and output scale inside the graph, exported
by torch as ``host.train.correction`` does), Ai2019's BP net 2-5-10-1 (hand-built graph), and
the LSTM-NARMAX step graph of ``models_export.onnx_step`` (hidden 7). The fused step is compiled
from the ONNX file (``edge.control.fused_graph``); its parity is measured against torch on a free
run of 2 000 steps. Timings: the two evaluators alternate in ``--rounds`` rounds of ``--steps``
steps in one process; the table gives the median per step, wall and CPU (``time.process_time``),
and the ratio fused / onnxruntime of each round's pair, median over rounds.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import torch
from torch import nn

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
from edge.control.fused_graph import mlp_from_graph, narmax_from_graph  # noqa: E402
from edge.control.neural import NeuralCorrection  # noqa: E402
from edge.control.onnx_graph import read_graph  # noqa: E402
from host.train.lstm_narmax import NarmaxWeights  # noqa: E402
from models_export.onnx_step import (  # noqa: E402
    NARMAX_SPEC,
    OnnxStepper,
    export_module,
    export_step,
    initial_state,
    simulate_torch,
)
from tests.onnx_models import mlp  # noqa: E402

Step = Callable[[], float]


class Correction(nn.Module):
    def __init__(self) -> None:
        super().__init__()
        torch.manual_seed(0)
        self.net = nn.Sequential(nn.Linear(3, 16), nn.Tanh(), nn.Linear(16, 16), nn.Tanh(), nn.Linear(16, 1))
        self.register_buffer("mean", torch.tensor([[40.0, 0.0, 3.0]]))
        self.register_buffer("inv_std", torch.tensor([[0.05, 0.02, 0.5]]))
        self.register_buffer("scale", torch.tensor(0.2))

    def forward(self, x):  # noqa: ANN001, ANN201
        return self.net((x - self.mean) * self.inv_std) * self.scale


def timed(run: Callable[[], None], steps: int) -> tuple[float, float]:
    wall, cpu = time.perf_counter(), time.process_time()
    run()
    return 1e6 * (time.perf_counter() - wall) / steps, 1e6 * (time.process_time() - cpu) / steps


def compare(
    name: str, ort_run: Callable[[], None], fused_run: Callable[[], None], steps: int, rounds: int, diff: float
) -> None:
    ort, fused = [], []
    for _ in range(rounds):
        ort.append(timed(ort_run, steps))
        fused.append(timed(fused_run, steps))
    med = lambda rows, i: statistics.median(r[i] for r in rows)  # noqa: E731
    ratio = lambda i: statistics.median(f[i] / o[i] for f, o in zip(fused, ort))  # noqa: E731
    kept = "numpy-fused" if ratio(1) < 1 else "onnxruntime"
    print(
        f"| {name} | {med(ort, 0):.2f} | {med(ort, 1):.2f} | {med(fused, 0):.2f} | {med(fused, 1):.2f} "
        f"| {ratio(0):.2f} | {ratio(1):.2f} | {diff:.1e} | {kept} |"
    )


def mlp_rows(scratch: Path, steps: int, rounds: int) -> None:
    rng = np.random.default_rng(1)
    module = Correction().eval()
    corr = export_module(module, (torch.zeros(1, 3),), scratch / "corr.onnx", ["features"], ["correction_bar"])
    bp, _ = mlp(scratch / "bp.onnx")
    nets = [
        ("correction MLP 3-16-16-1", corr, ["reference_mm", "reference_rate_mm_s", "feedforward_bar"], module),
        ("BP net 2-5-10-1 (Ai2019)", bp, ["reference_mm", "feedforward_bar"], None),
    ]
    for name, path, features, torch_module in nets:
        edge = NeuralCorrection(path, {"features": features, "input": "features", "output": "correction_bar"})
        fused = mlp_from_graph(read_graph(path), "features", "correction_bar", len(features))
        x = rng.normal(0, 20, (2000, len(features))).astype(np.float32)
        rows = [r for r in x.tolist()]
        if torch_module is not None:
            with torch.no_grad():
                reference = torch_module(torch.from_numpy(x))[:, 0].numpy()
        else:
            reference = np.array([edge._onnx_step(r) for r in rows])  # hand-built graph: no torch twin
        diff = float(np.max(np.abs(np.array([fused.step(r) for r in rows]) - reference)) / np.ptp(reference))
        work = [rows[i % len(rows)] for i in range(steps)]
        onnx_step, fused_step = edge._onnx_step, fused.step

        def ort_run(work: list[list[float]] = work, step: Callable[..., float] = onnx_step) -> None:
            for r in work:
                step(r)

        def fused_run(work: list[list[float]] = work, step: Callable[..., float] = fused_step) -> None:
            for r in work:
                step(r)

        compare(name, ort_run, fused_run, steps, rounds, diff)


def narmax_row(scratch: Path, steps: int, rounds: int) -> None:
    rng = np.random.default_rng(2)
    weights = NarmaxWeights(
        rng.normal(0, 0.4, (28, 5)).astype(np.float32),
        rng.normal(0, 0.4, (28, 7)).astype(np.float32),
        rng.normal(0, 0.4, 28).astype(np.float32),
        rng.normal(0, 0.4, 7).astype(np.float32),
        0.05,
        rng.normal(0, 1, 5).astype(np.float32),
        rng.uniform(0.5, 2, 5).astype(np.float32),
        0.3,
    )
    path, _ = export_step("lstm-narmax", weights, scratch / "step.onnx")
    t = np.arange(max(steps, 2000)) / 1000.0
    u = 2 * np.sin(2 * np.pi * 0.7 * t) + 0.5 * np.sin(2 * np.pi * 3.1 * t)
    n = np.tanh(u)
    fused = narmax_from_graph(read_graph(path))
    reference = simulate_torch("lstm-narmax", weights, u[:2000], n[:2000])
    diff = float(np.max(np.abs(fused.simulate(u[:2000], n[:2000]) - reference)) / np.ptp(reference))
    stepper = OnnxStepper(path, NARMAX_SPEC)
    pairs = list(zip(u[:steps].tolist(), n[:steps].tolist()))

    def ort_run() -> None:
        stepper.set_state(initial_state("lstm-narmax", weights, pairs[0][0], pairs[0][1]))
        for a, b in pairs:
            stepper.step(a, b)

    def fused_run() -> None:
        fused.reset(pairs[0][0], pairs[0][1])
        for a, b in pairs:
            fused.step(a, b)

    compare("LSTM-NARMAX step (hidden 7)", ort_run, fused_run, steps, rounds, diff)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    print(f"\n**Per-step time [us], median of {args.rounds} interleaved rounds of {args.steps} steps**\n")
    print(
        "| net | onnxruntime wall | onnxruntime CPU | fused wall | fused CPU | ratio wall | ratio CPU "
        "| max diff vs torch / range | faster |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|---:|---|")
    with tempfile.TemporaryDirectory() as scratch:
        mlp_rows(Path(scratch), args.steps, args.rounds)
        narmax_row(Path(scratch), args.steps, args.rounds)
    print("\n(BP net: hand-built graph without a torch twin; its diff is against onnxruntime)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
