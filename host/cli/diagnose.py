"""``pmactl diagnose``: name what the simulation gets wrong on a recording and measure the fix."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from edge.errors import DataError
from host.data import load_measurement
from host.diagnose.run import CAUSES, diagnose


def run(args: argparse.Namespace) -> int:
    measurement = load_measurement(args.data)
    result = diagnose(measurement, folds=args.folds)
    name = Path(args.data).name
    print(f"{name}: cause {result.cause}")
    print(f"  {result.reason}")
    print(
        f"  held-out RMSE: baseline {result.baseline_rmse:.4g}, extended {result.extended_rmse:.4g} "
        f"(gain {result.gain:.0%})"
    )
    print(f"  {'candidate':<18} {'gain':>7}  per fold")
    for cause in CAUSES:
        folds = " ".join(f"{g:+.1%}" for g in result.fold_gains[cause])
        print(f"  {cause:<18} {result.scores[cause]:>+7.1%}  {folds}")
    for note in measurement.notes:
        print(f"  note: {note}")
    try:
        if args.json:
            Path(args.json).parent.mkdir(parents=True, exist_ok=True)
            Path(args.json).write_text(json.dumps(result.as_json(), indent=2) + "\n")
            print(f"  JSON written to {args.json}")
        if args.report:
            from host.diagnose.report import write_report

            print(f"  report written to {write_report(result, args.report, name)}")
    except OSError as exc:
        raise DataError(f"cannot write the results ({exc}); choose a writable --json / --report path") from exc
    return 0
