"""Real-data table: identify every model on the piezo 20 Hz run, score the six validation runs.

Usage: python bench/piezo_table.py [DATA_DIR]   (default ../shared/data/piezo_dspace)

Prints a Markdown table (RMSE [um], RMSE as % of peak-to-peak, max error [um]) of every model
on every run, with the initial state and offset of each validation run estimated on its first
10 % after the input starts moving (those samples are not scored; see host/evaluate.py).
"""

from __future__ import annotations

import sys
from pathlib import Path

from host.data import load_measurement
from host.workflow import make_estimator, score_on

MODELS = ("pi", "mpi", "dpi", "preisach")
TRAIN = "20_hz_no_lp.csv"
VALIDATION = ("sine50_1", "sine100_1", "tri50_1", "tri100_1", "bigsine_1", "prbn_1")


def piezo_results(data_dir: Path) -> dict[str, dict[str, object]]:
    """``{model: {"fit_seconds", "train_pct", "runs": {run: Score}}}``."""
    train = load_measurement(data_dir / TRAIN)
    runs = [load_measurement(data_dir / f"{name}.csv") for name in VALIDATION]
    results: dict[str, dict[str, object]] = {}
    for model in MODELS:
        estimator = make_estimator(model).fit(train.u, train.y)
        residual = estimator.train_prediction_ - train.y[estimator.start_index_ :]
        train_pct = 100 * float((residual**2).mean() ** 0.5) / float(train.y.max() - train.y.min())
        scores = {r.name.removesuffix(".csv"): r.prediction.score for r in score_on(estimator.model_, runs)}
        results[model] = {"fit_seconds": estimator.fit_seconds_, "train_pct": train_pct, "runs": scores}
    return results


def main(argv: list[str]) -> int:
    default = Path(__file__).resolve().parents[2] / "shared" / "data" / "piezo_dspace"
    data_dir = Path(argv[0]) if argv else default
    results = piezo_results(data_dir)
    print("| model | fit [s] | train % p-p | " + " | ".join(VALIDATION) + " |")
    print("|---|---:|---:|" + "---:|" * len(VALIDATION))
    for model, result in results.items():
        cells = [
            f"{s.rmse:.3f} / {s.rmse_pct_pp:.2f} % / {s.max_error:.2f}"
            for s in result["runs"].values()  # type: ignore[union-attr]
        ]
        print(f"| {model} | {result['fit_seconds']:.2f} | {result['train_pct']:.2f} | " + " | ".join(cells) + " |")
    print("\ncells: RMSE [um] / RMSE as % of p-p / max error [um], on samples after the calibration window")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
