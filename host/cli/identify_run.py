"""The work behind ``pmactl identify`` (parsers in :mod:`host.cli.identify`)."""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError
from host.data import Measurement, load_measurement


def read_columns(path: str | Path, wanted: list[str]) -> dict[str, NDArray[np.float64]]:
    """The named columns of a CSV as float arrays; one clear error for a missing column or bad row."""
    path = Path(path)
    try:
        with path.open(newline="") as handle:
            header = [h.strip() for h in next(csv.reader(handle), [])]
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: cannot read file ({exc}); check the path and that it is a text CSV") from exc
    missing = [c for c in wanted if c not in header]
    if missing:
        raise DataError(
            f"{path}: column(s) {', '.join(missing)} missing; found {header}. Rename or pass the column option"
        )
    table = np.atleast_2d(np.genfromtxt(path, delimiter=",", skip_header=1, dtype=float))
    if table.size == 0 or table.shape[1] != len(header):
        raise DataError(f"{path}: no data rows with {len(header)} fields; check the delimiter is ','")
    columns = {c: table[:, header.index(c)] for c in wanted}
    bad = np.flatnonzero(~np.all(np.isfinite(np.column_stack(list(columns.values()))), axis=1))
    if bad.size:
        raise DataError(f"{path}: {bad.size} row(s) with NaN or non-numbers (file line {int(bad[0]) + 2}); remove them")
    return columns


def _fotd_record(path: str, output_column: str) -> Measurement:
    m = load_measurement(path)
    if output_column == "y":
        return m
    if output_column not in m.extras:
        raise DataError(f"{path}: --output-column {output_column!r} not in the file; found {['y', *m.extras]}")
    return Measurement(m.t, m.u, m.extras[output_column], source=m.source, notes=m.notes)


def run_fotd(args: argparse.Namespace) -> int:
    from host.identify.fotd import identify_fotd

    records = [_fotd_record(p, args.output_column) for p in args.runs]
    fit = identify_fotd(records, args.method, hysteresis_phase=not args.no_hysteresis_phase)
    if args.json:
        print(json.dumps(fit.as_dict()))
        return 0
    print(f"K e^(-sL)/(1+sT) by {fit.method} fit on {len(records)} record(s):")
    print(f"  gain K          {fit.gain:10.4g} +- {fit.gain_se:.2g}  (y per unit u)")
    print(f"  time constant T {fit.time_constant_s:10.4g} +- {fit.time_constant_se_s:.2g} s")
    print(f"  dead time L     {fit.dead_time_s:10.4g} +- {fit.dead_time_se_s:.2g} s")
    if fit.hysteresis_loss_angle_rad is not None:
        se = fit.hysteresis_loss_angle_se_rad or 0.0
        print(
            f"  hysteresis loss angle {math.degrees(fit.hysteresis_loss_angle_rad):.2f} +- {math.degrees(se):.2f} deg "
            "(frequency independent)"
        )
    if fit.harmonics:
        print(
            f"  {'f [Hz]':>8} {'periods':>7} {'mean y':>9} {'U':>8} {'Y':>8} {'|G|':>8} {'phase [deg]':>12} "
            f"{'loss [deg]':>10} {'model |G|':>9} {'model ph':>9}"
        )
        for h in fit.harmonics:
            g = complex(fit.response(h.frequency_hz))
            print(
                f"  {h.frequency_hz:8.3f} {h.periods:7d} {h.output_mean:9.4g} {h.input_amplitude:8.4g} "
                f"{h.output_amplitude:8.4g} {h.gain:8.4g} "
                f"{math.degrees(h.phase_rad):7.1f}+-{math.degrees(h.phase_se_rad):<4.1f}"
                f" {math.degrees(h.loss_angle_rad):10.1f} {abs(g):9.4g} {math.degrees(np.angle(g)):9.1f}"
            )
    for note in fit.notes:
        print(f"  note: {note}")
    return 0


def run_force(args: argparse.Namespace) -> int:
    from host.cli.identify_static import run_force as run

    return run(args)


def run_maxwell_slip(args: argparse.Namespace) -> int:
    from host.cli.identify_static import run_maxwell_slip as run

    return run(args)
