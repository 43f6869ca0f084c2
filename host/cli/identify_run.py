"""The work behind ``pmactl identify`` (parsers in :mod:`host.cli.identify`)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError
from host.cli.options import expand_runs, read_measurement
from host.cli.outputs import strict_json
from host.data import Measurement


def read_columns(
    path: str | Path, wanted: list[str], mapping: dict[str, str] | None = None, fix: str = "--columns ROLE=NAME"
) -> dict[str, NDArray[np.float64]]:
    """The named columns of a CSV as float arrays (delimiter and decimal comma sniffed, names mapped
    by ``mapping`` as ``--columns`` gives them); one clear error for a missing column or bad row."""
    from host.data_format import sniff_layout

    path = Path(path)
    layout = sniff_layout(path)
    mapping = mapping or {}
    names = {role: mapping.get(role, role) for role in wanted}
    missing = [f"{role}" + (f" (as {name!r})" if name != role else "") for role, name in names.items()
               if name not in layout.header]  # fmt: skip
    if missing:
        raise DataError(f"{path}: column(s) {', '.join(missing)} missing; found {layout.header}. Pass {fix}")
    with path.open(encoding="utf-8-sig") as handle:
        lines = [line.replace(",", ".") if layout.decimal_comma else line for line in handle]
    table = np.atleast_2d(np.genfromtxt(lines, delimiter=layout.delimiter, skip_header=1, dtype=float))
    if table.size == 0 or table.shape[1] != len(layout.header):
        raise DataError(f"{path}: no data rows with {len(layout.header)} fields; check the file is complete")
    columns = {role: table[:, layout.header.index(name)] for role, name in names.items()}
    bad = np.flatnonzero(~np.all(np.isfinite(np.column_stack(list(columns.values()))), axis=1))
    if bad.size:
        raise DataError(f"{path}: {bad.size} row(s) with NaN or non-numbers (file line {int(bad[0]) + 2}); remove them")
    return columns


def _fotd_record(path: str, args: argparse.Namespace) -> Measurement:
    m = read_measurement(path, args)
    output_column = args.output_column
    if output_column == "y":
        return m
    if output_column not in m.extras:
        raise DataError(f"{path}: --output-column {output_column!r} not in the file; found {['y', *m.extras]}")
    units = {k: v for k, v in m.units.items() if k != "y"}
    if m.unit(output_column):
        units["y"] = m.unit(output_column)
    return Measurement(m.t, m.u, m.extras[output_column], source=m.source, notes=m.notes, units=units)


def run_fotd(args: argparse.Namespace) -> int:
    from host.identify.fotd import identify_fotd

    records = [_fotd_record(p, args) for p in expand_runs(args.runs, "RUN.csv")]
    fit = identify_fotd(records, args.method, hysteresis_phase=not args.no_hysteresis_phase)
    u_unit, y_unit = records[0].unit("u", "unit u"), records[0].unit("y", "unit y")
    if args.json:
        print(strict_json({**fit.as_dict(), "units": {"u": records[0].unit("u"), "y": records[0].unit("y")}}))
        return 0
    print(f"K e^(-sL)/(1+sT) by {fit.method} fit on {len(records)} record(s):")
    print(f"  gain K          {fit.gain:10.4g} +- {fit.gain_se:.2g}  ({y_unit} per {u_unit})")
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
    if fit.harmonics:
        print(f"  (mean y and Y in {y_unit}, U in {u_unit}, |G| in {y_unit} per {u_unit})")
    for note in fit.notes:
        print(f"  note: {note}")
    return 0


def run_force(args: argparse.Namespace) -> int:
    from host.cli.identify_static import run_force as run

    return run(args)


def run_maxwell_slip(args: argparse.Namespace) -> int:
    from host.cli.identify_static import run_maxwell_slip as run

    return run(args)
