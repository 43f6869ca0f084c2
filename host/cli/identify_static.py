"""``pmactl identify force`` and ``pmactl identify maxwell-slip``: static laws from CSV columns."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from edge.errors import DataError
from host.cli.identify_run import read_columns
from host.cli.outputs import strict_json

GRAVITY = 9.81


def _positive_mm(value: float | None, option: str, what: str) -> None:
    """Refuse a length option that is NaN, infinite, zero or negative (``None``: not given, fine)."""
    if value is not None and not (math.isfinite(value) and value > 0):
        raise DataError(f"{option} {value}: must be a finite positive number ({what} in mm)")


def run_force(args: argparse.Namespace) -> int:
    from host.identify.force import FORCE_MODELS

    if args.rest_length_mm is None:
        raise DataError("pass --rest-length-mm (the muscle's rest length; contraction ratio = y / rest length)")
    _positive_mm(args.rest_length_mm, "--rest-length-mm", "the muscle's rest length")
    _positive_mm(args.radius_mm, "--radius-mm", "the muscle's inner radius")
    from host.data_format import parse_columns, sniff_layout

    mapping = parse_columns(args.columns) if args.columns else {}
    header = set(sniff_layout(Path(args.data)).header) | set(mapping)
    pressure_column = "p" if "p" in header else "u"
    force_column = "force" if "force" in header else "load"
    fix = "--columns p=NAME,y=NAME,force=NAME (force in N; or load=NAME in kg)"
    columns = read_columns(args.data, [pressure_column, "y", force_column], mapping, fix)
    force = columns[force_column] * (GRAVITY if force_column == "load" else 1.0)
    eps = columns["y"] / args.rest_length_mm
    kwargs = {"radius_m": args.radius_mm / 1e3} if args.model == "tondu-lopez" and args.radius_mm else {}
    model = FORCE_MODELS[args.model](**kwargs).fit(columns[pressure_column], eps, force)
    result = model.as_dict()
    spread = float(np.ptp(force))
    result.update(
        {
            "samples": int(force.size),
            "force_range_n": spread,
            "rmse_pct_range": 100 * float(str(result["rmse_n"])) / spread,
            "pressure_column": pressure_column,
            "force_column": force_column,
        }
    )
    if args.json:
        print(strict_json(result))
        return 0
    print(
        f"{args.model} static force on {Path(args.data).name} ({force.size} samples, pressure from "
        f"'{pressure_column}', force from '{force_column}'{' x g' if force_column == 'load' else ''}):"
    )
    for key, value in result.items():
        if key not in {"model", "samples", "pressure_column", "force_column"}:
            print(f"  {key:<28} {value:.6g}" if isinstance(value, float) else f"  {key:<28} {value}")
    return 0


def identifiable_elements(samples: int) -> int:
    """The most Maxwell-slip elements ``samples`` can identify.

    Each element has two parameters (stiffness, break force), the model two more (offset, linear
    term), and the held-out score fits them on the first 70 % after the warm-up: that window must
    hold at least as many samples as there are parameters.
    """
    from host.identify.maxwell_slip import TRAIN_SHARE, WARMUP

    fitted = int(TRAIN_SHARE * samples) - int(WARMUP * samples)
    return max(0, (fitted - 2) // 2)


def run_maxwell_slip(args: argparse.Namespace) -> int:
    from host.identify.maxwell_slip import despike, select_and_fit

    fix = "--position-column NAME --force-column NAME"
    columns = read_columns(args.data, [args.position_column, args.force_column], fix=fix)
    samples = columns[args.position_column].size
    limit = identifiable_elements(samples)
    if args.elements is not None and args.elements > limit:
        raise DataError(
            f"--elements {args.elements}: {samples} samples can identify at most {limit} element(s) (2 parameters "
            f"each, fitted on the first 70 %); pass --elements {limit} or fewer, or record more data"
        )
    if limit < 1:
        raise DataError(f"{args.data}: {samples} samples are too few to identify one element; record more data")
    result = select_and_fit(
        columns[args.position_column], columns[args.force_column], args.elements, max_elements=min(8, limit)
    )
    if args.plot:
        from host.identify.maxwell_slip import plot_loops

        plot_loops(
            [(Path(args.data).stem, despike(columns[args.position_column]), columns[args.force_column], result.model)],
            args.plot,
        )
    if args.json:
        print(strict_json(result.as_dict()))
        return 0
    print(
        f"Maxwell-slip on {Path(args.data).name}: {result.model.elements} element(s), "
        f"train RMSE {result.train_rmse:.4g} ({result.train_rmse_pct:.2f} % of range), "
        f"held-out RMSE {result.test_rmse:.4g} ({result.test_rmse_pct:.2f} % of range)"
    )
    if result.scan:
        print(f"  {'elements':>8} {'held-out RMSE':>14} {'% of range':>10}")
        for row in result.scan:
            print(f"  {row['elements']:>8} {row['test_rmse']:>14.4g} {row['test_rmse_pct']:>10.2f}")
    from host.data_format import header_unit

    position_unit = header_unit(args.position_column) or "unit of x"
    print(f"  {f'stiffness [N/{position_unit}]':>20} {'break force [N]':>16}")
    for k, f in zip(result.model.stiffness_, result.model.break_force_):
        print(f"  {k:>20.5g} {f:>16.5g}")
    print(f"  offset {result.model.offset_:.5g} N; {result.note}")
    if args.plot:
        print(f"  figure written to {args.plot}")
    return 0
