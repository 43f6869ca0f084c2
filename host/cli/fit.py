"""``pmactl fit``: identify one model, score it on held-out recordings, optionally bundle it."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

from edge.errors import DataError
from host.cli.lazy import lazy
from host.cli.options import add_data_options, add_fit_options, expand_runs, read_measurement, read_options
from host.cli.outputs import FIGURE_SUFFIXES, check_output, strict_json

if TYPE_CHECKING:
    from host.data import Measurement
    from host.evaluate import Score
    from host.workflow import Estimator, TestResult


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl fit``."""
    fit = sub.add_parser("fit", help="identify a hysteresis model from a measured-data CSV")
    add_fit_options(fit)
    fit.add_argument(
        "--parameterisation",
        choices=["free", "exponential"],
        default="free",
        help="pi and mpi: free play weights or Ai2019's beta/delta/mu form",
    )
    fit.add_argument(
        "--preisach-method",
        choices=["lsq", "forc"],
        default="lsq",
        help="preisach only: least squares on any data, or first-order reversal curves",
    )
    fit.add_argument(
        "--calibration",
        type=float,
        default=0.1,
        metavar="FRACTION",
        help="share of each test record (after it starts moving) used to estimate its "
        "initial state and offset; never scored (default 0.1)",
    )
    add_data_options(fit)
    fit.add_argument(
        "--plot", metavar="OUT.png", help="write measured vs model loops of each --test here (.png, .pdf or .svg)"
    )
    fit.add_argument(
        "--adapt",
        action="store_true",
        help="also score each --test with the edge's online adaptation ([adapt], default settings) replayed over it",
    )
    fit.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    fit.add_argument(
        "--save", metavar="DIR", help="write the lookup-table bundle (model + inverse) here; its parent must exist"
    )
    fit.set_defaults(run=lazy("host.cli.fit"))


class UnitsUnknownWarning(UserWarning):
    """A bundle written without units for its input and output."""


def bundle_units(train: Measurement) -> tuple[str, str]:
    """(u, y) units for the bundle: from --units or the header; a warning names the fix when unknown."""
    missing = [role for role in ("u", "y") if not train.unit(role)]
    if missing:
        warnings.warn(
            f"--save without units: the {' and '.join(missing)} unit(s) of {Path(train.source).name} are unknown "
            "(no --units, no suffix such as pressure_bar in the header), so the bundle says 'u'/'y' and the edge "
            "will refuse it against a rig config in bar and mm; pass --units bar,mm",
            UnitsUnknownWarning,
            stacklevel=2,
        )
    return train.unit("u", "u"), train.unit("y", "y")


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


def adapted_scores(results: list[TestResult], tests: list[Measurement], train: Measurement) -> list[Score]:
    """Each test scored with the edge's online adaptation replayed over it (:mod:`host.adapt_score`)."""
    import numpy as np

    from edge.control.adapt import AdaptSettings
    from host.adapt_score import adapted_score

    span = float(np.ptp(train.y))
    if not span > 0:
        raise DataError(f"{train.source}: the training output never moves; --adapt needs its span")
    return [adapted_score(r, m, span, AdaptSettings(enabled=True)) for r, m in zip(results, tests)]


def print_adapted(results: list[TestResult], adapted: list[Score], y_unit: str) -> None:
    """The table of held-out errors with online adaptation, beside the plain ones."""
    print(f"{'with --adapt':<28} {'scored':>7} {'RMSE' + y_unit:>12} {'% p-p':>7} {'plain % p-p':>12}")
    for r, s in zip(results, adapted):
        plain_pct = r.prediction.score.rmse_pct_pp
        print(f"{r.name:<28} {s.samples:>7} {s.rmse:>12.4g} {s.rmse_pct_pp:>7.2f} {plain_pct:>12.2f}")
    plain = sum(r.prediction.score.rmse_pct_pp for r in results) / len(results)
    mean = sum(s.rmse_pct_pp for s in adapted) / len(adapted)
    print(
        f"mean % p-p: {mean:.2f} adapted, {plain:.2f} plain (the rig's [adapt] estimator, default settings, replayed "
        "from where each input starts moving; each sample predicted from the samples before it; no calibrated offset)"
    )


def run(args: argparse.Namespace) -> int:
    from host.progress import Steps, wanted
    from host.workflow import make_estimator, save_bundle, score_on, warn_extrapolation
    from models_export.bundle import check_save_target

    read_options(args)  # a malformed --columns or --units is refused before any file is read
    if not 0 < args.calibration < 0.9:
        raise DataError(f"--calibration {args.calibration} must be between 0 and 0.9")
    if args.save:
        check_output(args.save, "--save", kind="dir")
        check_save_target(args.save)  # a foreign directory is refused before the fit, not after
    if args.adapt and not args.test:
        raise DataError("--adapt scores the --test recordings with online adaptation; pass at least one --test CSV")
    if args.plot:
        if not args.test:
            raise DataError("--plot draws the --test recordings' loops; pass at least one --test CSV")
        check_output(args.plot, "--plot", suffixes=FIGURE_SUFFIXES)
    estimator = make_estimator(
        args.model,
        operators=args.operators,
        parameterisation=args.parameterisation,
        preisach_method=args.preisach_method,
    )
    args.test = expand_runs(args.test, "--test")
    trains = expand_runs([args.train], "--train")
    if len(trains) > 1:
        raise DataError(f"--train {args.train} matches {len(trains)} files; fit on one recording (name it)")
    args.train = trains[0]
    with Steps(3 + len(args.test) + bool(args.save), wanted(args.json), f"pmactl fit {args.model}") as steps:
        steps.start(f"reading {Path(args.train).name}")
        train = read_measurement(args.train, args)
        tests = []
        for path in args.test:
            steps.start(f"reading {Path(path).name}")
            tests.append(read_measurement(path, args))
        extrapolating = warn_extrapolation(train.u, tests, train.unit("u"))
        steps.start(f"fitting on {len(train)} samples")
        estimator.fit(train.u, train.y)
        steps.start("scoring")
        results = score_on(estimator.model_, tests, args.calibration)
        adapted = adapted_scores(results, tests, train) if args.adapt else None
        if args.save:
            steps.start("writing the bundle")
            units = bundle_units(train)
            save_bundle(estimator, train, args.save, units, fit_record(args, len(train), estimator, results))
    if args.plot:
        from host.demo_figures import plot_test_loops

        plot_test_loops(Path(args.plot), args.model, tests, results, train.unit("u", "u"), train.unit("y", "y"))
    if args.json:
        print(
            strict_json(
                {
                    "model": args.model,
                    "fit_seconds": estimator.fit_seconds_,
                    "units": {"u": train.unit("u"), "y": train.unit("y")},
                    "warnings": extrapolating,
                    "tests": [
                        {
                            "file": r.name,
                            "rmse": r.prediction.score.rmse,
                            "rmse_pct_pp": r.prediction.score.rmse_pct_pp,
                            "max_error": r.prediction.score.max_error,
                            **({"adapted": adapted[i].as_dict()} if adapted else {}),
                        }
                        for i, r in enumerate(results)
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
        y_unit = f" [{train.unit('y')}]" if train.unit("y") else ""
        print(
            f"{'test file':<28} {'scored':>7} {'start state':>11} {'offset' + y_unit:>12} {'RMSE' + y_unit:>12} "
            f"{'% p-p':>7} {'max err' + y_unit:>14}"
        )
        for r in results:
            p, s = r.prediction, r.prediction.score
            print(
                f"{r.name:<28} {s.samples:>7} {p.branch:>11} {p.offset:>12.4g} "
                f"{s.rmse:>12.4g} {s.rmse_pct_pp:>7.2f} {s.max_error:>14.4g}"
            )
        print(
            f"(start state and offset estimated on the first {args.calibration:.0%} of each test after the input "
            "starts moving; those samples are not scored)"
        )
        if adapted:
            print_adapted(results, adapted, y_unit)
    else:
        print("no --test given: pass held-out recordings with --test to score the model")
    if args.plot:
        print(f"measured vs model loops written to {args.plot}")
    if args.save:
        print(f"bundle written to {args.save}")
    return 0
