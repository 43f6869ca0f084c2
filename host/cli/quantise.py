"""``pmactl quantise``: int8 variants of a bundle's correction net, kept only if they earn it."""

from __future__ import annotations

import argparse

from host.cli.bundle import add_key_option, report_signing, signing_state
from host.cli.lazy import lazy
from host.cli.options import add_data_options, expand_runs, read_measurement
from host.cli.outputs import strict_json


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl quantise`` to the command line."""
    quantise = sub.add_parser(
        "quantise", help="measure int8 variants of a bundle's correction; keep one only if as accurate and faster"
    )
    quantise.add_argument("bundle", metavar="DIR", help="bundle with a correction (pmactl train --model correction)")
    quantise.add_argument(
        "--calibration",
        required=True,
        action="append",
        metavar="CSV",
        help="recording (t,u,y) for calibration and scoring",
    )
    quantise.add_argument("--json", action="store_true", help="print one JSON object")
    add_key_option(quantise, "that holds the measured, chosen variant")
    add_data_options(quantise, units=False)
    quantise.set_defaults(run=lazy("host.cli.quantise"))


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from edge.runtime.bundle import load_bundle
    from host.train.correction import correction_features
    from models_export.quantise import quantise_bundle

    load_bundle(args.bundle)  # an unknown format or a broken bundle is refused before any measurement
    signed_before = signing_state(args.bundle, args.key)  # so is an unusable --key
    paths = expand_runs(args.calibration, "--calibration")
    pairs = [correction_features(args.bundle, read_measurement(path, args)) for path in paths]
    features = np.concatenate([p[0] for p in pairs])
    target = np.concatenate([p[1] for p in pairs])
    report = quantise_bundle(args.bundle, features, target)
    if args.json:
        print(strict_json(report))
        report_signing(args.bundle, args.key, signed_before, json_output=True)
        return 0
    print(f"{'variant':<26} {'RMSE [bar]':>11} {'vs f32':>8} {'us/step':>8} {'cpu us/step':>11}")
    variants: dict[str, dict[str, float]] = report["variants"]  # type: ignore[assignment]
    for name, m in variants.items():
        print(
            f"{name:<26} {m['rmse_bar']:>11.5f} {m['rmse_ratio']:>8.3f} {m['us_per_step_wall']:>8.2f} "
            f"{m['us_per_step_cpu']:>11.2f}"
        )
    print(f"kept: {report['kept']} ({report['reason']})")
    report_signing(args.bundle, args.key, signed_before, json_output=False)
    return 0
