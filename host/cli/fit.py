"""``pmactl fit``: identify one model, score it on held-out recordings, optionally bundle it."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from edge.errors import DataError
from host.cli.outputs import check_output
from host.data import load_measurement
from host.progress import Steps, wanted
from host.workflow import Estimator, TestResult, make_estimator, save_bundle, score_on
from models_export.bundle import check_save_target


def parse_units(text: str) -> tuple[str, str]:
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 2 or not all(parts):
        raise DataError(f"--units {text!r} must be two names separated by a comma, e.g. --units bar,mm")
    return parts[0], parts[1]


def fit_record(args: argparse.Namespace, samples: int, estimator: Estimator, results: list[TestResult]) -> dict:
    """What the bundle's manifest keeps about the fit."""
    return {
        "model": args.model,
        "train": Path(args.train).name,
        "samples": samples,
        "fit_seconds": estimator.fit_seconds_,
        "fit_cpu_seconds": estimator.fit_cpu_seconds_,
        "blas_threads": estimator.blas_threads_,
        "memory_known_from_sample": estimator.start_index_,
        "options": {
            "operators": args.operators,
            "parameterisation": args.parameterisation,
            "preisach_method": args.preisach_method,
        },
        "tests": [{"file": r.name, **r.prediction.score.as_dict()} for r in results],
    }


def run(args: argparse.Namespace) -> int:
    units = parse_units(args.units)
    if not 0 < args.calibration < 0.9:
        raise DataError(f"--calibration {args.calibration} must be between 0 and 0.9")
    if args.save:
        check_output(args.save, "--save", kind="dir")
        check_save_target(args.save)  # a foreign directory is refused before the fit, not after
    estimator = make_estimator(
        args.model,
        operators=args.operators,
        parameterisation=args.parameterisation,
        preisach_method=args.preisach_method,
    )
    with Steps(3 + len(args.test) + bool(args.save), wanted(args.json), f"pmactl fit {args.model}") as steps:
        steps.start(f"reading {Path(args.train).name}")
        train = load_measurement(args.train)
        tests = []
        for path in args.test:
            steps.start(f"reading {Path(path).name}")
            tests.append(load_measurement(path))
        steps.start(f"fitting on {len(train)} samples")
        estimator.fit(train.u, train.y)
        steps.start("scoring")
        results = score_on(estimator.model_, tests, args.calibration)
        if args.save:
            steps.start("writing the bundle")
            save_bundle(estimator, train, args.save, units, fit_record(args, len(train), estimator, results))
    if args.json:
        print(
            json.dumps(
                {
                    "model": args.model,
                    "fit_seconds": estimator.fit_seconds_,
                    "tests": [
                        {
                            "file": r.name,
                            "rmse": r.prediction.score.rmse,
                            "rmse_pct_pp": r.prediction.score.rmse_pct_pp,
                            "max_error": r.prediction.score.max_error,
                        }
                        for r in results
                    ],
                }
            )
        )
        return 0
    print(
        f"{args.model}: fitted on {Path(args.train).name} ({len(train)} samples) in {estimator.fit_seconds_:.3f} s; "
        f"memory known from sample {estimator.start_index_} ({estimator.start_branch_})"
    )
    for note in train.notes:
        print(f"  note: {note}")
    if results:
        print(
            f"{'test file':<28} {'scored':>7} {'start state':>11} {'offset':>9} {'RMSE':>9} {'% p-p':>7} {'max err':>9}"
        )
        for r in results:
            p, s = r.prediction, r.prediction.score
            print(
                f"{r.name:<28} {s.samples:>7} {p.branch:>11} {p.offset:>9.4g} "
                f"{s.rmse:>9.4g} {s.rmse_pct_pp:>7.2f} {s.max_error:>9.4g}"
            )
        print(
            f"(start state and offset estimated on the first {args.calibration:.0%} of each test after the input "
            "starts moving; those samples are not scored)"
        )
    else:
        print("no --test given: pass held-out recordings with --test to score the model")
    if args.save:
        print(f"bundle written to {args.save}")
    return 0
