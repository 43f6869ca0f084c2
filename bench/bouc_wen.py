"""The Bouc-Wen hysteresis benchmark (Noël & Schoukens 2016): pmactl's models beside published ones.

Usage: python bench/bouc_wen.py [--realisations 5] [--seed 0] [--models state-space lstm-narmax arx pi mpi preisach]
                                [--ss-epochs 250] [--lstm-epochs 150] [--save DIR]

The data are regenerated from the published equations (:mod:`bench.bouc_wen_data`; nothing is
downloaded): ``--realisations`` random-phase multisines of 5 periods (8192 samples each at
750 Hz, 5-150 Hz, 50 N RMS) with noisy outputs to train on, the last 20 % of them held out for
early stopping; the multisine test (a new realisation, noise-free) scored on its steady-state
period, the sine-sweep test (our definition, see ``bouc_wen_data.SWEEP``) scored from rest.

Models, each trained on the same joined training record:

* ``state-space``: :func:`host.train.state_space.train_state_space`, called as
  :func:`host.train.train_model` calls a trainer (seeded, 20 % tail, ``split_record``);
* ``lstm-narmax``: :func:`host.train.train_model` exactly as ``pmactl train --model lstm-narmax``;
* ``arx``: a linear ARX, orders ``na, nb`` in 1..6 chosen on the held-out tail's simulation error;
* ``pi``, ``mpi``, ``preisach``: the rate-independent models as ``pmactl fit`` builds them.

Models with a hysteresis branch start in the branch that fits the test's unscored part best
(the multisine's first period; the sweep's first 10 %). No offset is fitted: the RMSE [m] is
the benchmark's figure of merit. CPU seconds (``time.process_time``) beside wall seconds.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.bouc_wen_data import Record, test_multisine, test_sweep, training_records  # noqa: E402

PUBLISHED = (  # multisine test RMSE [m]; the sweep numbers could not be checked here
    ("PNLSS (Noël et al. 2017, MSSP)", 1.21e-5),
    ("dynoNet (Forgione & Piga 2021, IJACSP)", 4.52e-5),
)
MODELS = ("state-space", "lstm-narmax", "arx", "pi", "mpi", "preisach")
TAIL_FRACTION = 0.2
Simulate = Callable[[NDArray[np.float64], str], NDArray[np.float64]]


@dataclass
class Result:
    name: str
    multisine_rmse: float
    sweep_rmse: float
    cpu_s: float
    wall_s: float


def _measurement(records: list[Record]):  # noqa: ANN202 (host.data.Measurement, imported lazily)
    from host.data import Measurement
    from host.train import join

    parts = [Measurement(r.t, r.u, r.y, source=r.name, units={"u": "N", "y": "m"}) for r in records]
    return join(parts)


def rmse_on(simulate: Simulate, test: Record, branches: tuple[str, ...]) -> float:
    """RMSE [m] on the scored part, starting in the branch that fits the unscored part best."""
    calibration = slice(0, test.score_from) if test.score_from > 0 else slice(0, test.u.size // 10)
    best = None
    for branch in branches:
        y = simulate(test.u, branch)
        fit = float(np.mean((y[calibration] - test.y[calibration]) ** 2))
        if best is None or fit < best[0]:
            best = (fit, y)
    assert best is not None
    return float(np.sqrt(np.mean((best[1][test.score_from :] - test.y[test.score_from :]) ** 2)))


def fit_arx(u: NDArray[np.float64], y: NDArray[np.float64], tail: int) -> tuple[Simulate, tuple[int, int]]:
    """Linear ARX (delay 1) by least squares; orders by the held-out tail's simulation error."""
    from scipy.signal import lfilter

    def fit(na: int, nb: int, end: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        lag = max(na, nb)
        rows = [y[lag - i : end - i] for i in range(1, na + 1)] + [u[lag - i : end - i] for i in range(1, nb + 1)]
        theta, *_ = np.linalg.lstsq(np.column_stack(rows), y[lag:end], rcond=None)
        return np.concatenate([[1.0], -theta[:na]]), np.concatenate([[0.0], theta[na:]])

    best = None
    for na in range(1, 7):
        for nb in range(1, 7):
            den, num = fit(na, nb, tail)
            if np.max(np.abs(np.roots(den))) >= 1.0:
                continue
            error = float(np.sqrt(np.mean((lfilter(num, den, u)[tail:] - y[tail:]) ** 2)))
            if best is None or error < best[0]:
                best = (error, na, nb, num, den)
    assert best is not None
    _, na, nb, num, den = best
    return (lambda signal, _branch: np.asarray(lfilter(num, den, signal))), (na, nb)


def onnx_parity(model, test: Record, save: Path | None) -> None:  # noqa: ANN001 (NeuralStateSpace)
    """Export the step graph and print its onnxruntime free run's largest difference from numpy's."""
    import tempfile

    from host.train.state_space import save_state_space, simulate_onnx

    with tempfile.TemporaryDirectory() as scratch:
        folder = save_state_space(model, save or Path(scratch) / "state-space", {"bench": "bouc_wen"})
        onnx_run = simulate_onnx(folder / "step.onnx", test.u, model.weights.state_order)
    difference = float(np.max(np.abs(onnx_run - model.simulate(test.u))))
    print(
        f"state-space step.onnx (onnxruntime, float32) vs numpy free run on the {test.name}: max |diff| "
        f"{difference:.2e} m ({difference / float(np.ptp(test.y)):.1e} of the output range)"
    )


def run(
    models: tuple[str, ...], realisations: int, seed: int, ss_epochs: int, lstm_epochs: int, save: Path | None = None
) -> list[Result]:
    from host.train import train_model
    from host.train.common import seed_everything, split_record
    from host.train.state_space import train_state_space
    from host.workflow import make_estimator

    t0 = time.process_time()
    train = _measurement(training_records(realisations, seed))
    tests = (test_multisine(seed), test_sweep())
    print(
        f"data: {len(train)} training samples ({realisations} x 5 periods), generated in "
        f"{time.process_time() - t0:.1f} s CPU",
        flush=True,
    )
    tail = len(train) - int(round(TAIL_FRACTION * len(train)))
    results = []
    for name in models:
        cpu, wall = time.process_time(), time.perf_counter()
        branches: tuple[str, ...] = ("ascending", "descending")
        if name == "state-space":
            seed_everything(seed)
            trained, _ = train_state_space(
                train.u,
                train.y,
                lambda s: split_record(len(train), s, TAIL_FRACTION, train.source),
                seed=seed,
                epochs=ss_epochs,
            )
            simulate: Simulate = trained.simulate
            branches = ("rest",)
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall  # the training time so far;
            onnx_parity(trained, tests[0], save)  # the check is not training: its time is left out
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        elif name == "lstm-narmax":
            simulate = train_model("lstm-narmax", [train], seed=seed, epochs=lstm_epochs).model.simulate
        elif name == "arx":
            simulate, orders = fit_arx(train.u, train.y, tail)
            branches = ("rest",)
            print(f"arx orders na={orders[0]}, nb={orders[1]}")
        else:
            model = make_estimator(name).fit(train.u, train.y).model_

            def simulate(signal: NDArray[np.float64], branch: str, model=model) -> NDArray[np.float64]:  # noqa: ANN001
                model.reset(float(signal[0]), branch)  # type: ignore[arg-type]
                return np.asarray(model.simulate(signal))

        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        ms, sw = (rmse_on(simulate, test, branches) for test in tests)
        results.append(Result(name, ms, sw, cpu, wall))
        print(f"{name}: multisine {ms:.3e} m, sweep {sw:.3e} m, {cpu:.1f} s CPU ({wall:.1f} s wall)", flush=True)
    return results


def print_table(results: list[Result], command: str) -> None:
    print(f"\n`{command}`\n")
    print("| model | multisine test RMSE [m] | sine-sweep RMSE [m] | training CPU [s] | wall [s] |")
    print("|---|---:|---:|---:|---:|")
    for r in results:
        print(f"| pmactl {r.name} | {r.multisine_rmse:.3e} | {r.sweep_rmse:.3e} | {r.cpu_s:.1f} | {r.wall_s:.1f} |")
    for name, value in PUBLISHED:
        print(f"| {name} | {value:.3e} | (not checked) | | |")
    for r in results:
        if r.name == "state-space":
            ratios = ", ".join(f"{r.multisine_rmse / value:.2f}x {name.split()[0]}" for name, value in PUBLISHED)
            print(f"\nstate-space multisine RMSE: {ratios} (< 1 is better)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--realisations", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--models", nargs="+", default=list(MODELS), choices=MODELS)
    parser.add_argument("--ss-epochs", type=int, default=250)
    parser.add_argument("--lstm-epochs", type=int, default=150)
    parser.add_argument("--save", type=Path, help="write the state-space model here (step.onnx, model.json)")
    args = parser.parse_args()
    import torch

    torch.set_num_threads(1)
    results = run(tuple(args.models), args.realisations, args.seed, args.ss_epochs, args.lstm_epochs, args.save)
    print_table(results, "python " + " ".join(sys.argv))


if __name__ == "__main__":
    main()
