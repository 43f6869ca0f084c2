"""``pmactl demo``: the whole path on the shipped example data.

For every model: identify on the training recording, score on the held-out one (initial state
and offset estimated, see :mod:`host.evaluate`), write the bundle, load it back the way the
edge does (numpy only, checksums verified) and check that the lookup tables reproduce the
reference model and that the inverse table undoes the forward table.
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

from edge.runtime.bundle import load_bundle
from host.data import load_measurement
from host.examples import example_path
from host.workflow import make_estimator, rest_state, save_bundle, score_on

MODELS = ("pi", "mpi", "dpi", "preisach")


def run(args: argparse.Namespace) -> int:
    train = load_measurement(example_path("train"))
    test = load_measurement(example_path("test"))
    out = Path(args.out) if args.out else Path(tempfile.mkdtemp(prefix="pmactl-demo-"))
    rows = []
    for name in MODELS:
        estimator = make_estimator(name).fit(train.u, train.y)
        [result] = score_on(estimator.model_, [test])
        bundle_dir = save_bundle(estimator, train, out / name, ("bar", "mm"), {"model": name})
        bundle = load_bundle(bundle_dir)
        # parity: reference model vs its lookup table, both from the rest state, on the test input
        forward, inverse = rest_state(estimator.model_, float(train.u.min()))
        reference = forward.simulate(test.u)
        table = bundle.forward.simulate(test.u)
        round_trip = bundle.inverse.simulate(table)
        score = result.prediction.score
        rows.append(
            {
                "model": name,
                "fit_seconds": estimator.fit_seconds_,
                "rmse_mm": score.rmse,
                "rmse_pct_pp": score.rmse_pct_pp,
                "max_error_mm": score.max_error,
                "table_vs_reference_mm": float(np.abs(reference - table).max()),
                "inverse_round_trip_bar": float(
                    np.abs(round_trip - np.clip(test.u, *bundle.forward.input_range)).max()
                ),
                "bundle": str(bundle_dir),
            }
        )
    if args.json:
        print(json.dumps({"train": train.source, "test": test.source, "models": rows}, indent=2))
        return 0
    print("pmactl demo: muscle pressure [bar] -> contraction [mm], example data shipped with pmactl")
    print(f"  train: {Path(train.source).name} ({len(train)} samples: triangles 0->1,2,3,4 bar at 0.05 Hz)")
    print(f"  test:  {Path(test.source).name} ({len(test)} samples: slow sine + faster sine, minor loops)")
    print()
    print(
        f"{'model':<9} {'fit [s]':>8} {'RMSE [mm]':>10} {'% p-p':>7} {'max [mm]':>9} "
        f"{'table-ref [mm]':>15} {'inv(fwd) [bar]':>15}"
    )
    for r in rows:
        print(
            f"{r['model']:<9} {r['fit_seconds']:>8.3f} {r['rmse_mm']:>10.4f} {r['rmse_pct_pp']:>7.2f} "
            f"{r['max_error_mm']:>9.3f} {r['table_vs_reference_mm']:>15.2e} {r['inverse_round_trip_bar']:>15.2e}"
        )
    print()
    print("RMSE etc.: held-out test, after estimating its initial state and offset on its first 10 %.")
    print("table-ref: lookup table (as the edge loads it) vs reference model; inv(fwd): inverse table")
    print(f"applied to the forward table's output, against the input. Bundles: {out}")
    return 0
