"""``pmactl train``: the neural hysteresis models and the edge's correction (host/train)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import TYPE_CHECKING

from edge.errors import DataError
from host.cli.bundle import add_key_option, report_signing, signing_state
from host.cli.lazy import lazy
from host.cli.options import add_data_options, expand_runs, read_measurement, read_options
from host.cli.outputs import OutputPathError, check_output, strict_json

if TYPE_CHECKING:
    from host.data import Measurement
    from host.train import Trained
    from host.train.net_bundle import NetBundle

DEFAULT_EPOCHS = {"hammerstein": 60, "lstm-narmax": 150, "state-space": 250, "correction": 300}
BUNDLE_MODELS = ("lstm-narmax", "hammerstein", "state-space")  # --save writes a bundle store


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl train`` to the command line."""
    train = sub.add_parser(
        "train", help="train a neural hysteresis model (torch: the train extra) or the edge's correction (no torch)"
    )
    train.add_argument(
        "--model",
        required=True,
        choices=["hammerstein", "lstm-narmax", "state-space", "correction"],
        help="hammerstein (Ai2019: MPI + BP net + ARX), lstm-narmax (Wu2025), state-space (linear model + tanh "
        "net on simulation error: the Bouc-Wen benchmark's winner), or correction "
        "(the edge's inverse correction, added to --bundle)",
    )
    train.add_argument(
        "--train", required=True, action="append", metavar="CSV", help="training recording (t,u,y); repeat to join"
    )
    train.add_argument("--test", action="append", default=[], metavar="CSV", help="held-out recording (repeatable)")
    train.add_argument("--seed", type=int, default=0, help="random seed (default 0): same seed, same model")
    train.add_argument(
        "--epochs",
        type=int,
        help="training epochs (default: hammerstein 60, lstm-narmax 150, state-space 250, correction 300)",
    )
    train.add_argument(
        "--calibration",
        type=float,
        default=0.1,
        metavar="FRACTION",
        help="share of each test record after the input moves used for its start state and offset (never scored)",
    )
    train.add_argument("--bundle", metavar="DIR", help="correction only: the bundle whose feedforward it corrects")
    train.add_argument("--json", action="store_true", help="print one JSON object (no progress bar)")
    train.add_argument(
        "--save",
        metavar="DIR",
        help="lstm-narmax, hammerstein, state-space: write a bundle store (tables, the forward net and an inverse "
        "LSTM-NARMAX trained with --epochs too; new release in an existing store); correction: the training curve",
    )
    add_key_option(
        train, "(of --save for lstm-narmax, hammerstein and state-space, of --bundle for --model correction)"
    )
    add_data_options(train)
    train.set_defaults(run=lazy("host.cli.train"))


def run(args: argparse.Namespace) -> int:
    read_options(args)  # a malformed --columns or --units is refused before any file is read
    args.train, args.test = expand_runs(args.train, "--train"), expand_runs(args.test, "--test")
    if args.epochs is not None and args.epochs < 1:
        raise DataError(f"--epochs {args.epochs} must be at least 1")
    if args.epochs is None:
        args.epochs = DEFAULT_EPOCHS[args.model]
    if args.model in BUNDLE_MODELS:
        signed_before = _check_store(args.save, args.key) if args.save else None
    elif args.save:
        _check_save(args.save)  # before training: a bad path costs nothing and nothing is half-written
    if args.model == "correction":
        return _run_correction(args)
    if args.bundle:
        raise DataError("--bundle applies to --model correction only; use --save DIR for a trained model")
    if args.key and not (args.model in BUNDLE_MODELS and args.save):
        raise DataError(
            f"--key signs a bundle's new release, and --model {args.model} writes none here (--save writes one); "
            "drop --key"
        )
    if not 0 < args.calibration < 0.9:
        raise DataError(f"--calibration {args.calibration} must be between 0 and 0.9")
    import numpy as np

    from host.train import score_model, train_model
    from host.workflow import warn_extrapolation

    records = [read_measurement(path, args) for path in args.train]
    tests = [read_measurement(path, args) for path in args.test]
    y_unit = records[0].unit("y")
    warn_extrapolation(np.concatenate([r.u for r in records]), tests, records[0].unit("u"))
    trained = train_model(args.model, records, seed=args.seed, epochs=args.epochs, quiet=args.json)
    results = score_model(trained.model, tests, args.calibration)
    tests_json = [
        {
            "file": r.name,
            "rmse": r.prediction.score.rmse,
            "rmse_pct_pp": r.prediction.score.rmse_pct_pp,
            "max_error": r.prediction.score.max_error,
            "mae": r.mae,
            "ms_per_run": r.ms_per_run,
        }
        for r in results
    ]
    written = None
    if args.save:
        record = {
            "model": args.model,
            "train": [Path(p).name for p in args.train],
            "seed": args.seed,
            "epochs": args.epochs,
            "fit_seconds": trained.fit_seconds,
            "tests": tests_json,
        }
        written = _save_bundle(args, trained, records, record, tests)
    if args.json:
        # the documented keys only (tests/test_train.py); warnings went to stderr
        out: dict[str, object] = {"model": args.model, "fit_seconds": trained.fit_seconds, "tests": tests_json}
        if written is not None:
            out["bundle"] = written.as_dict()
        print(strict_json(out))
        if written is not None:
            report_signing(args.save, args.key, signed_before, json_output=True)
        return 0
    print(
        f"{args.model}: trained on {', '.join(Path(p).name for p in args.train)} ({trained.samples} samples; memory "
        f"known from sample {trained.memory_start}, early stopping on samples {trained.tail_start}+) "
        f"in {trained.fit_seconds:.1f} s, seed {args.seed}"
    )
    if results:
        unit = f" [{y_unit}]" if y_unit else ""
        print(
            f"{'test file':<28} {'scored':>7} {'RMSE' + unit:>12} {'% p-p':>7} {'max err' + unit:>14} "
            f"{'MAE' + unit:>12} {'ms/run':>8}"
        )
        for r, j in zip(results, tests_json):
            print(
                f"{r.name:<28} {r.prediction.score.samples:>7} {j['rmse']:>12.4g} {j['rmse_pct_pp']:>7.2f} "
                f"{j['max_error']:>14.4g} {j['mae']:>12.4g} {j['ms_per_run']:>8.1f}"
            )
    else:
        print("no --test given: pass held-out recordings with --test to score the model")
    if written is not None:
        inv = written.inverse
        print(
            f"bundle written to {args.save}: {written.table_model} tables, forward {args.model}, inverse LSTM-NARMAX; "
            "inverse "
            f"net held-out command RMSE {inv.tail_rmse_bar:.4f} bar (table alone {inv.tail_rmse_table_bar:.4f} bar)"
        )
        for score in written.inverse_tests:
            print(
                f"  inverse on held-out {score.name}: command RMSE {score.rmse_bar:.4f} bar "
                f"(table alone {score.table_rmse_bar:.4f} bar, {score.samples} samples)"
            )
        report_signing(args.save, args.key, signed_before, json_output=False)
    return 0


def _check_store(path: str, key: str | None) -> str | None:
    """Refuse a --save target that cannot hold a bundle store, or a bad --key, before training;
    returns the key id that signed the store's current release (``None``: unsigned or new)."""
    from models_export.bundle import check_save_target
    from models_export.store import is_store

    check_output(path, "--save", kind="dir")
    check_save_target(path)
    if Path(path).is_dir() and is_store(Path(path)):
        return signing_state(path, key)
    if key is not None:
        from models_export.signing import read_private_key

        read_private_key(Path(key))  # a new store has no signer: only the key is checked
    return None


def _save_bundle(
    args: argparse.Namespace,
    trained: Trained,
    records: list[Measurement],
    record: dict[str, object],
    tests: list[Measurement],
) -> NetBundle:
    from host.cli.fit import bundle_units
    from host.train.net_bundle import save_net_bundle

    units = bundle_units(records[0])
    return save_net_bundle(trained, records, args.save, units, record, epochs=args.epochs, quiet=args.json, tests=tests)


def _check_save(path: str) -> None:
    """Refuse a --save folder that cannot be written, has no parent, or already holds a model."""
    from models_export.store import is_store

    check_output(path, "--save", kind="dir")
    if Path(path).is_dir() and is_store(Path(path)):
        raise OutputPathError(
            f"--save {path}: is a bundle directory (releases/, current); a trained model goes to a folder of its "
            "own, choose a new one (for the correction, the bundle is --bundle)"
        )
    if (Path(path) / "model.json").exists():
        raise OutputPathError(
            f"--save {path}: already holds a model (model.json); choose a new folder, or move the old model away first"
        )


def _run_correction(args: argparse.Namespace) -> int:
    from host.train.correction import train_correction_into

    if not args.bundle:
        raise DataError("--model correction needs --bundle DIR: the bundle whose feedforward it corrects")
    signed_before = signing_state(args.bundle, args.key)  # a bad --key is refused before training
    records = [read_measurement(path, args) for path in args.train]
    result = train_correction_into(args.bundle, records, seed=args.seed, epochs=args.epochs, quiet=args.json)
    if args.save:
        Path(args.save).mkdir(exist_ok=True)
        result.curve.save_png(Path(args.save) / "training_curve.png", "correction training")
    if args.json:
        print(strict_json(result.as_dict()))
        report_signing(args.bundle, args.key, signed_before, json_output=True)
        return 0
    print(
        f"correction trained on {', '.join(Path(p).name for p in args.train)} in {result.fit_seconds:.1f} s: "
        f"held-out tail RMSE {result.tail_rmse_bar:.4f} bar (feedforward alone {result.tail_rmse_ff_bar:.4f} bar); "
        f"added to {args.bundle} (features {', '.join(result.features)})"
    )
    print(
        f"training data {result.coverage_line()}; the edge warns before arming when a reference leaves that "
        "(record sines over the working range: pmactl edge record --protocol sines)"
    )
    report_signing(args.bundle, args.key, signed_before, json_output=False)
    return 0
