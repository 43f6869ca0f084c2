"""Neural hysteresis models: Wu2025 Table 1 on HIL and real data, step latency, closed loop.

Usage: python bench/neural_bench.py [--data ../shared/data] [--epochs 150] [--only tables|latency|loop|tick|trainer]
       python bench/neural_bench.py --only trainer --before DIR [--seeds 0 1]

1. Table 1 (RMSE, MAXE % of p-p, MAE, ms per free run) of PI, MPI, Preisach, Hammerstein and
   LSTM-NARMAX, every test scored after its calibration window (host/evaluate.py):
   * HIL, ``--effect rate_dependence``, the ``sines`` protocol (0.05-1 Hz): train seed 1, test seed 2;
   * the real muscle, 2026-07-22 campaign joined: first 70 % train, last 30 % test;
   * the real piezo: train 20_hz_no_lp, test the six validation runs (cells averaged over runs).
2. Per-step latency of the exported step graphs: onnxruntime (one session, one thread, no
   spinning, bound preallocated arrays) against a numpy evaluator of the same weights, wall and
   CPU time, measured interleaved in one run.
3. Closed loop on the HIL through ``pmactl edge run``: PID, PID + feedforward, PID +
   feedforward + trained correction, on Ai2019's sine and Zhou2022's amplitude ramp.
4. Whole-tick compute with that correction (bench/edge_bench.py's breakdown).
5. ``--only trainer``: LSTM-NARMAX on the real piezo's 40 000-sample ``20_hz_no_lp`` record, CPU
   and wall time of ``train_model`` and the held-out error on the six validation runs, for this
   source and, with ``--before DIR`` (an older source tree, e.g. ``git archive 5690bbc | tar -x
   -C DIR``), for that one, alternating per seed in child processes of this one run.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from host.data import Measurement, load_measurement
from host.evaluate import predict_unknown_start
from host.train import score_model, train_model
from host.workflow import make_estimator

HERE = Path(__file__).resolve().parent
RATE_MODELS = ("pi", "mpi", "preisach")
PIEZO_RUNS = ("sine50_1", "sine100_1", "tri50_1", "tri100_1", "bigsine_1", "prbn_1")


def joined(folder: Path) -> Measurement:
    """A campaign's logs end to end on one uniform grid (as bench/diagnose_real.py)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        logs = [load_measurement(path) for path in sorted(folder.glob("*.csv"))]
    dt = logs[0].dt
    u = np.concatenate([np.interp(np.arange(0, m.t[-1] - m.t[0], dt) + m.t[0], m.t, m.u) for m in logs])
    y = np.concatenate([np.interp(np.arange(0, m.t[-1] - m.t[0], dt) + m.t[0], m.t, m.y) for m in logs])
    return Measurement(
        (np.arange(u.size) * dt).astype(np.float64), u.astype(np.float64), y.astype(np.float64), source=folder.name
    )


def hil(seed: int, scratch: Path) -> Measurement:
    out = scratch / f"rate_seed{seed}.csv"
    subprocess.run(
        [
            "pmactl",
            "hil",
            "record",
            "--scenario",
            "sines",
            "--effect",
            "rate_dependence",
            "--seed",
            str(seed),
            "--duration",
            "120",
            "--out",
            str(out),
        ],
        check=True,
        capture_output=True,
    )
    return load_measurement(out)


Row = tuple[str, float, float, float, float, float]


def _cells(prediction, measured: Measurement, ms: float) -> tuple[float, float, float, float]:  # noqa: ANN001
    end = prediction.window_end
    mae = float(np.mean(np.abs(prediction.y[end:] - measured.y[end:])))
    maxe = 100 * prediction.score.max_error / float(np.ptp(measured.y[end:]))
    return prediction.score.rmse, maxe, mae, ms


def table_rows(train: Measurement, test_sets: dict[str, list[Measurement]], epochs: int) -> dict[str, list[Row]]:
    """Per test set: (model, RMSE, MAXE %, MAE, ms per run, train s), averaged over its records."""
    rows: dict[str, list[Row]] = {name: [] for name in test_sets}
    for name in RATE_MODELS:
        start = time.perf_counter()
        model = make_estimator(name).fit(train.u, train.y).model_
        fit_s = time.perf_counter() - start
        for set_name, tests in test_sets.items():
            cells = []
            for m in tests:
                t0 = time.perf_counter()
                model.reset(float(m.u[0]), "descending")
                model.simulate(m.u)
                ms = 1e3 * (time.perf_counter() - t0)
                cells.append(_cells(predict_unknown_start(model, m.u, m.y), m, ms))
            rows[set_name].append((name, *np.mean(cells, axis=0), fit_s))
    for kind in ("hammerstein", "lstm-narmax"):
        trained = train_model(kind, [train], epochs=epochs if kind == "lstm-narmax" else 60)
        for set_name, tests in test_sets.items():
            cells = [_cells(r.prediction, m, r.ms_per_run) for r, m in zip(score_model(trained.model, tests), tests)]
            rows[set_name].append((kind, *np.mean(cells, axis=0), trained.fit_seconds))
    return rows


def print_table(title: str, rows: list[Row], unit: str) -> None:
    print(f"\n**{title}**\n")
    print(f"| model | RMSE [{unit}] | MAXE [% p-p] | MAE [{unit}] | ms per run | train [s] |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, rmse, maxe, mae, ms, fit in rows:
        print(f"| {name} | {rmse:.4g} | {maxe:.2f} | {mae:.4g} | {ms:.1f} | {fit:.1f} |")
    best_ri = min(r[1] for r in rows if r[0] in RATE_MODELS)
    lstm = next(r[1] for r in rows if r[0] == "lstm-narmax")
    print(f"\nLSTM-NARMAX vs best rate-independent model: {100 * (1 - lstm / best_ri):+.1f} % RMSE")


def tables(data: Path, epochs: int, scratch: Path) -> None:
    friction = {}
    records = {}
    for seed in (1, 2, 6):
        records[seed] = hil(seed, scratch)
        truth = json.loads((scratch / f"rate_seed{seed}.truth.json").read_text())
        friction[seed] = truth["parameters"]["rate_friction_s_per_m"]
    hil_rows = table_rows(records[1], {"2": [records[2]], "6": [records[6]]}, epochs)
    for seed in (2, 6):
        print_table(
            f"HIL rate_dependence, sines 0.05-1 Hz, train seed 1 (rate friction {friction[1]:.1f}), "
            f"test seed {seed} (rate friction {friction[seed]:.1f})",
            hil_rows[str(seed)],
            "mm",
        )
    muscle = data / "pam_muscle_sensory" / "2026-07-22_Literature_Comparison"
    if muscle.is_dir():
        record = joined(muscle)
        cut = int(0.7 * len(record))
        rows = table_rows(record.slice(0, cut), {"test": [record.slice(cut)]}, epochs)["test"]
        print_table("real muscle 2026-07-22, first 70 % train, last 30 % test", rows, "mm")
    piezo = data / "piezo_dspace"
    if piezo.is_dir():
        train = load_measurement(piezo / "20_hz_no_lp.csv")
        runs = {name: [load_measurement(piezo / f"{name}.csv")] for name in PIEZO_RUNS}
        per_run = table_rows(train, runs, epochs)
        mean_rows = [(rows[0][0], *np.mean([r[1:] for r in rows], axis=0)) for rows in zip(*per_run.values())]
        print_table("real piezo, train 20_hz_no_lp, mean over the six runs", mean_rows, "um")
        print("\nper run, RMSE [um]: | model | " + " | ".join(PIEZO_RUNS) + " |")
        for index, name in enumerate(r[0] for r in mean_rows):
            print(f"| {name} | " + " | ".join(f"{per_run[run][index][1]:.3f}" for run in PIEZO_RUNS) + " |")


def latency(scratch: Path, steps: int = 20_000, rounds: int = 3) -> None:
    """Per-step onnxruntime vs numpy for the trained step graphs (one HIL-trained model each)."""
    from host.train.hammerstein import arx_simulate  # noqa: F401  (the numpy side of Hammerstein)
    from host.train.lstm_narmax import simulate_numpy
    from models_export.onnx_step import export_step, simulate_onnx

    record = hil(1, scratch)
    u = record.u[:steps]
    print("\n**Per-step latency, wall / CPU [us]** (interleaved rounds, median)\n")
    print("| step graph | onnxruntime wall | onnxruntime CPU | numpy wall | numpy CPU | max abs diff / output range |")
    print("|---|---:|---:|---:|---:|---:|")
    for kind in ("lstm-narmax", "hammerstein"):
        model = train_model(kind, [record], epochs=10).model
        path, _ = export_step(kind, model.weights, scratch / f"{kind}.onnx")
        n = model.operator.operator.simulate(u, "descending")
        ort_t, np_t = [], []
        for _ in range(rounds):
            w, c = time.perf_counter(), time.process_time()
            y_ort = simulate_onnx(path, kind, model.weights, u, n)
            ort_t.append((time.perf_counter() - w, time.process_time() - c))
            w, c = time.perf_counter(), time.process_time()
            if kind == "lstm-narmax":
                y_np = simulate_numpy(model.weights, u, n)  # type: ignore[arg-type]
            else:
                y_np = _hammerstein_numpy_steps(model.weights, u, n)
            np_t.append((time.perf_counter() - w, time.process_time() - c))
        diff = float(np.max(np.abs(y_ort - y_np)) / np.ptp(y_ort))
        med = lambda ts, i: 1e6 * statistics.median(t[i] for t in ts) / u.size  # noqa: E731
        print(
            f"| {kind} | {med(ort_t, 0):.2f} | {med(ort_t, 1):.2f} | {med(np_t, 0):.2f} | {med(np_t, 1):.2f} "
            f"| {diff:.1e} |"
        )
    print("\n(onnxruntime times include copying the state outputs to the inputs each step, as the edge does)")
    correction_latency(scratch)


def correction_latency(scratch: Path, steps: int = 20_000, rounds: int = 3) -> None:
    """The edge's correction MLP (3-16-16-1): the edge's own NeuralCorrection vs a numpy twin."""
    from edge.control.neural import NeuralCorrection
    from host.train.correction import train_correction

    rng = np.random.default_rng(0)
    features = np.column_stack([rng.uniform(0, 70, 4000), rng.normal(0, 50, 4000), rng.uniform(0, 6, 4000)])
    target = 0.01 * features[:, 1] + 0.1 * np.sin(features[:, 0] / 10)
    model, *_ = train_correction(features, target, epochs=50)
    path = model.to_onnx(scratch / "corr.onnx")
    spec = {
        "features": ["reference_mm", "reference_rate_mm_s", "feedforward_bar"],
        "input": "features",
        "output": "correction_bar",
    }
    edge = NeuralCorrection(path, spec)
    layers = [
        (model.layers[k].astype(np.float32), model.layers[k + 1].astype(np.float32))
        for k in range(0, len(model.layers), 2)
    ]
    mean, inv_std, scale = model.mean.astype(np.float32), model.inv_std.astype(np.float32), model.scale

    def numpy_step(values: tuple[float, ...]) -> float:
        x = (np.array(values[:3], np.float32) - mean) * inv_std
        for i, (w, b) in enumerate(layers):
            x = w @ x + b
            if i < len(layers) - 1:
                x = np.tanh(x)
        return float(x[0] * scale)

    rows = [(r[0], r[1], r[2], 0.0, 0.0, 0.0) for r in features[np.arange(steps) % len(features)].tolist()]
    ort_t, np_t, diff = [], [], 0.0
    for _ in range(rounds):
        w, c = time.perf_counter(), time.process_time()
        a = [edge.step(r) for r in rows]
        ort_t.append((time.perf_counter() - w, time.process_time() - c))
        w, c = time.perf_counter(), time.process_time()
        b = [numpy_step(r) for r in rows]
        np_t.append((time.perf_counter() - w, time.process_time() - c))
        diff = max(diff, float(np.max(np.abs(np.array(a) - np.array(b)))))
    med = lambda ts, i: 1e6 * statistics.median(t[i] for t in ts) / steps  # noqa: E731
    print(
        f"| correction MLP 3-16-16-1 (edge NeuralCorrection) | {med(ort_t, 0):.2f} | {med(ort_t, 1):.2f} | "
        f"{med(np_t, 0):.2f} | {med(np_t, 1):.2f} | {diff / max(1e-12, float(np.ptp(a))):.1e} |"
    )


def _hammerstein_numpy_steps(w, u: np.ndarray, n: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """Hammerstein one step at a time in numpy (what an edge evaluator would do per tick)."""
    layers = w.layers
    y_lags = np.full(3, float(w.static(u[:1], n[:1])[0]), np.float32)
    v_lags = y_lags[:2].copy()
    a, b = w.a.astype(np.float32), w.b.astype(np.float32)
    out = np.empty(u.size)
    x = np.empty(2, np.float32)
    for k in range(u.size):
        x[0], x[1] = u[k], n[k]
        h = (x - w.mean) / w.std
        for i, (weight, bias) in enumerate(layers):
            h = weight @ h + bias
            if i < len(layers) - 1:
                h = np.tanh(h)
        v = np.float32(n[k] + h[0] * w.y_std)
        y = np.float32(a @ y_lags + b[0] * v + b[1:] @ v_lags)
        y_lags[1:] = y_lags[:2]
        y_lags[0] = y
        v_lags[1] = v_lags[0]
        v_lags[0] = v
        out[k] = y
    return out


def closed_loop(scratch: Path) -> None:
    """PID / + feedforward / + correction on the HIL, through the CLI only."""
    from host.train.correction import correction_bundle

    config = str(HERE.parent / "docs" / "examples" / "hil-rig.toml")
    bundle = scratch / "loop_bundle"
    subprocess.run(
        [
            "pmactl",
            "fit",
            "--model",
            "preisach",
            "--train",
            str(HERE.parent / "host" / "example_data" / "pma_triangles.csv"),
            "--units",
            "bar,mm",
            "--save",
            str(bundle),
        ],
        check=True,
        capture_output=True,
    )
    result = correction_bundle(bundle)
    print(
        f"\n**Closed loop on the HIL** (correction: tail RMSE {result.tail_rmse_bar:.4f} bar, "
        f"feedforward alone {result.tail_rmse_ff_bar:.4f} bar)\n"
    )
    print("| reference | PID RMS [mm] | + feedforward | + correction | ratio ff / PID | ratio ff+corr / PID |")
    print("|---|---:|---:|---:|---:|---:|")
    references = {
        "Ai2019 sine 30 sin(2 pi 0.2 t) + 40": ["--duration", "25", "--settle", "5"],
        "Zhou2022 amplitude ramp": [
            "--reference",
            "ramp-sine:peak=30,frequency=1,offset=40,rise=10,hold=1",
            "--settle",
            "1",
        ],
    }
    for name, extra in references.items():
        rms = []
        for flags in (["--no-feedforward", "--no-correction"], ["--no-correction"], []):
            out = subprocess.run(
                ["pmactl", "edge", "run", "--config", config, "--bundle", str(bundle), *extra, *flags, "--json"],
                check=True,
                capture_output=True,
                text=True,
            ).stdout
            rms.append(float(json.loads(out)["rms_error"]))
        print(
            f"| {name} | {rms[0]:.3f} | {rms[1]:.3f} | {rms[2]:.3f} | {rms[1] / rms[0]:.2f} | {rms[2] / rms[0]:.2f} |"
        )


def tick_compute(scratch: Path) -> None:
    """bench/edge_bench.py's per-tick breakdown, on a bundle carrying the trained correction."""
    from host.train.correction import correction_bundle

    sys.path.insert(0, str(HERE))
    import edge_bench

    bundle = scratch / "tick_bundle"
    subprocess.run(
        [
            "pmactl", "fit", "--model", "preisach", "--units", "bar,mm", "--save", str(bundle),
            "--train", str(HERE.parent / "host" / "example_data" / "pma_triangles.csv"),
        ],
        check=True,
        capture_output=True,
    )  # fmt: skip
    correction_bundle(bundle)
    print("\n**Whole-tick compute with the trained correction (3-16-16-1)**, via bench/edge_bench.py's breakdown")
    edge_bench.breakdown(bundle)


TRAINER_JOB = """
import json, sys, time
from pathlib import Path
import numpy as np
from host.data import load_measurement
from host.train import score_model, train_model
piezo, seed, epochs = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
train = load_measurement(piezo / "20_hz_no_lp.csv")
tests = [load_measurement(piezo / f"{name}.csv") for name in sys.argv[4:]]
wall, cpu = time.perf_counter(), time.process_time()
trained = train_model("lstm-narmax", [train], seed=seed, epochs=epochs)
wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
scores = [s.prediction.score for s in score_model(trained.model, tests)]
print(json.dumps({"wall": wall, "cpu": cpu, "pct_pp": float(np.mean([s.rmse_pct_pp for s in scores])),
                  "rmse": float(np.mean([s.rmse for s in scores])), "epochs": len(trained.model.curve.rows)}))
"""


def trainer(data: Path, epochs: int, before: Path | None, seeds: list[int]) -> None:
    """Old and new trainer side by side (see module docstring, item 5)."""
    import os

    piezo = data / "piezo_dspace"
    if not (piezo / "20_hz_no_lp.csv").is_file():
        print(f"\n(no piezo record under {piezo}: trainer comparison skipped)")
        return
    sources = {"this source": HERE.parent, **({"before": before} if before else {})}
    rows: dict[str, list[dict[str, float]]] = {name: [] for name in sources}
    for seed in seeds:
        for name, root in sources.items():
            env = {**os.environ, "PYTHONPATH": str(root)}
            out = subprocess.run(
                [sys.executable, "-c", TRAINER_JOB, str(piezo), str(seed), str(epochs), *PIEZO_RUNS],
                check=True, capture_output=True, text=True, env=env, cwd=root,
            ).stdout  # fmt: skip
            rows[name].append(json.loads(out.strip().splitlines()[-1]))
    print(f"\n**LSTM-NARMAX training on the piezo's 20_hz_no_lp (40 000 samples), --epochs {epochs}, seeds {seeds}**\n")
    print(
        "| source | seed | train CPU [s] | train wall [s] | epochs run | held-out RMSE [um] | held-out RMSE [% p-p] |"
    )
    print("|---|---:|---:|---:|---:|---:|---:|")
    for name, results in rows.items():
        for seed, r in zip(seeds, results):
            cells = f"{r['cpu']:.1f} | {r['wall']:.1f} | {r['epochs']:.0f} | {r['rmse']:.4f} | {r['pct_pp']:.3f}"
            print(f"| {name} | {seed} | {cells} |")
    if before:
        mean = lambda name, key: float(np.mean([r[key] for r in rows[name]]))  # noqa: E731
        print(
            f"\nCPU ratio before / this source: {mean('before', 'cpu') / mean('this source', 'cpu'):.1f}x; "
            f"held-out % p-p {mean('before', 'pct_pp'):.3f} -> {mean('this source', 'pct_pp'):.3f} (mean over seeds)"
        )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=HERE.parent.parent / "shared" / "data")
    parser.add_argument("--epochs", type=int, default=150, help="LSTM-NARMAX epochs (Hammerstein: 60)")
    parser.add_argument("--only", choices=["tables", "latency", "loop", "tick", "trainer"])
    parser.add_argument("--before", type=Path, help="trainer: an older source tree to compare with (see item 5)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1], help="trainer: seeds (default 0 1)")
    args = parser.parse_args()
    if args.only == "trainer":
        trainer(args.data.resolve(), args.epochs, args.before.resolve() if args.before else None, args.seeds)
        return 0
    with tempfile.TemporaryDirectory() as scratch_dir:
        scratch = Path(scratch_dir)
        if args.only in (None, "tables"):
            tables(args.data, args.epochs, scratch)
        if args.only in (None, "latency"):
            latency(scratch)
        if args.only in (None, "loop"):
            closed_loop(scratch)
        if args.only in (None, "tick"):
            tick_compute(scratch)
    return 0


if __name__ == "__main__":
    sys.exit(main())
