"""``pmactl quantise``: int8 variants of a bundle's correction and nets, kept only if they earn it."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from edge.errors import DataError
from host.cli.bundle import add_key_option, report_signing, signing_state
from host.cli.lazy import lazy
from host.cli.options import add_data_options, expand_runs, read_measurement
from host.cli.outputs import strict_json

if TYPE_CHECKING:
    from host.data import Measurement

RATE_RTOL = 0.01  # a calibration recording may be sampled this much off the nets' step


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl quantise`` to the command line."""
    quantise = sub.add_parser(
        "quantise",
        help="measure int8 variants of a bundle's correction and nets; keep one only if as accurate and faster",
    )
    quantise.add_argument(
        "bundle",
        metavar="DIR",
        help="bundle with a correction (pmactl train --model correction) or nets (pmactl train --save)",
    )
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
    from edge.runtime.bundle import load_bundle

    bundle = load_bundle(args.bundle)  # an unknown format or a broken bundle is refused before any measurement
    if bundle.correction_path is None and not bundle.net_paths:
        raise DataError(
            f"{args.bundle}: no correction to quantise and no nets; train a correction with pmactl train "
            "--model correction, or nets with pmactl train --model lstm-narmax --save"
        )
    signed_before = signing_state(args.bundle, args.key)  # so is an unusable --key
    paths = expand_runs(args.calibration, "--calibration")
    records = [read_measurement(path, args) for path in paths]
    if bundle.net_paths:
        _check_rate(records, float(next(iter(bundle.manifest["nets"].values()))["step_s"]))  # type: ignore[attr-defined]
    out: dict[str, object] = {}
    if bundle.correction_path is not None:
        out["correction"] = _correction(args.bundle, records)
    if bundle.net_paths:
        out.update(_nets(args.bundle, records))
    changed = "correction" in out or bool(out.get("changed"))
    if args.json:
        print(strict_json(out["correction"] if list(out) == ["correction"] else out))
        if changed:
            report_signing(args.bundle, args.key, signed_before, json_output=True)
        return 0
    if "correction" in out:
        print("correction")
        _print_variants(out["correction"], "RMSE [bar]", "rmse_bar")  # type: ignore[arg-type]
    for which, report in (out.get("nets") or {}).items():  # type: ignore[attr-defined]
        unit = "[mm]" if which == "forward" else "[bar]"
        fused = report["fused_numpy_us_per_step_cpu"]
        print(f"{which} net ({report['model']})" + (f"; fused numpy step {fused:.2f} cpu us" if fused else ""))
        _print_variants(report, f"RMSE {unit}", "rmse")
    if bundle.net_paths and not out.get("changed"):
        print("nets: float32 kept, the bundle's nets are unchanged")
    if changed:
        report_signing(args.bundle, args.key, signed_before, json_output=False)
    return 0


def _check_rate(records: list[Measurement], step_s: float) -> None:
    for record in records:
        if abs(record.dt - step_s) > RATE_RTOL * step_s:
            raise DataError(
                f"{record.source}: sampled every {record.dt * 1e3:.4g} ms, the bundle's nets step every "
                f"{step_s * 1e3:.4g} ms; record the calibration at {1 / step_s:g} Hz (pmactl edge record --sample-hz)"
            )


def _correction(bundle: str, records: list[Measurement]) -> dict[str, object]:
    import numpy as np

    from host.train.correction import correction_features
    from models_export.quantise import quantise_bundle

    pairs = [correction_features(bundle, record) for record in records]
    return quantise_bundle(bundle, np.concatenate([p[0] for p in pairs]), np.concatenate([p[1] for p in pairs]))


def _nets(bundle: str, records: list[Measurement]) -> dict[str, object]:
    from host.train import join
    from models_export.quantise_nets import quantise_nets

    joined = join(records)
    return quantise_nets(bundle, joined.u, joined.y)


def _print_variants(report: dict[str, object], rmse_label: str, rmse_key: str) -> None:
    print(f"  {'variant':<26} {rmse_label:>11} {'vs f32':>8} {'us/step':>8} {'cpu us/step':>11}")
    variants: dict[str, dict[str, float]] = report["variants"]  # type: ignore[assignment]
    for name, m in variants.items():
        print(
            f"  {name:<26} {m[rmse_key]:>11.5f} {m['rmse_ratio']:>8.3f} {m['us_per_step_wall']:>8.2f} "
            f"{m['us_per_step_cpu']:>11.2f}"
        )
    print(f"  kept: {report['kept']} ({report['reason']})")
