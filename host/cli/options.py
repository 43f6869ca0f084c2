"""Argument definitions shared by the subcommands, with their ranges stated.

:func:`add_data_options` and :func:`read_measurement` are the one way a command reads a
measurement file as the lab wrote it (``--columns``, ``--time-unit``, ``--units``).

Only the standard library here: ``pmactl --help`` must work on an ``edge``-only install.
"""

from __future__ import annotations

import argparse
import math
from importlib import metadata
from typing import TYPE_CHECKING

from host.operator_ranges import MODELS, OPERATORS, OPERATORS_HELP

if TYPE_CHECKING:
    from host.data import Measurement
    from host.data_format import ReadOptions


def version() -> str:
    """The installed pmactl version (the source tree's when not installed)."""
    try:
        return metadata.version("pmactl")
    except metadata.PackageNotFoundError:
        return "unknown (not installed)"


def operator_count(text: str) -> int:
    """``--operators``: an integer within the widest range; the model's own range is checked in fit."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number; give e.g. --operators 25") from None
    lowest = min(low for _, low, _ in OPERATORS.values())
    highest = max(high for _, _, high in OPERATORS.values())
    if not lowest <= value <= highest:
        raise argparse.ArgumentTypeError(f"{value} is outside {lowest}-{highest}; {OPERATORS_HELP}")
    return value


def positive_rate(text: str) -> float:
    """A rate in Hz: finite and > 0."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number; give a rate in Hz, e.g. 100") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"{text} Hz must be a positive rate, e.g. 100 (divides 1000)")
    return value


def add_fit_options(fit: argparse.ArgumentParser) -> None:
    """``--model``, ``--train``, ``--test`` and ``--operators`` of ``pmactl fit``."""
    fit.add_argument(
        "--model",
        required=True,
        choices=MODELS,
        help="pi: Prandtl-Ishlinskii; mpi: modified PI (dead-zone output shaper); dpi: digitized dual PI; "
        "preisach: Everett map",
    )
    fit.add_argument("--train", required=True, metavar="CSV", help="training recording (t [s], u, y)")
    fit.add_argument("--test", action="append", default=[], metavar="CSV", help="held-out recording (repeatable)")
    fit.add_argument("--operators", type=operator_count, metavar="N", help=OPERATORS_HELP)


def add_hil_options(parser: argparse.ArgumentParser, effects: object) -> None:
    """``--effect`` and ``--seed`` of ``pmactl hil serve``."""
    parser.add_argument(
        "--effect",
        default="none",
        choices=list(effects),  # type: ignore[call-overload]
        help="hidden effect of the emulated rig, parameters drawn from physical ranges (default none)",
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed of the effect's parameters (default 0)")


TIME_UNIT_CHOICES = ("s", "ms", "us")  # host.data_format.TIME_UNITS (kept here: stdlib only)


def add_data_options(parser: argparse.ArgumentParser, *, units: bool = True) -> None:
    """``--columns``, ``--time-unit`` and (``units``) ``--units``: a measurement file as the lab wrote it.

    Read the files with :func:`read_measurement`. The delimiter (``,`` ``;`` tab) and a decimal
    comma are found in the file itself.
    """
    group = parser.add_argument_group("measurement files")
    group.add_argument(
        "--columns",
        metavar="ROLE=NAME,...",
        help="the file's own column names, e.g. t=time_s,u=pressure_bar,y=length_mm[,load=...,temperature=...] "
        "(default: columns named t, u, y)",
    )
    group.add_argument(
        "--time-unit",
        choices=TIME_UNIT_CHOICES,
        help="unit of the time column (default: a suffix in its header such as time_ms, else seconds)",
    )
    if units:
        group.add_argument(
            "--units",
            metavar="U,Y",
            help="units of input and output, e.g. bar,mm (or u=bar,y=mm,load=N); default: the header's "
            "suffixes such as pressure_bar; printed in tables and written into bundles",
        )


def read_options(args: argparse.Namespace) -> ReadOptions:
    """The :class:`host.data_format.ReadOptions` the data options of ``args`` give."""
    from host.data_format import ReadOptions, parse_columns, parse_units

    columns = parse_columns(args.columns) if getattr(args, "columns", None) else {}
    units_text = getattr(args, "units", None)
    return ReadOptions(columns, getattr(args, "time_unit", None), parse_units(units_text) if units_text else {})


def read_measurement(path: str, args: argparse.Namespace) -> Measurement:
    """Load ``path`` (a :class:`host.data.Measurement`) with the data options of ``args``."""
    from host.data import load_measurement

    return load_measurement(path, options=read_options(args))


def expand_runs(paths: list[str], option: str) -> list[str]:
    """``paths`` with glob patterns (``runs/*.csv``) expanded, sorted, for commands that take several
    runs; a pattern that matches nothing is refused with the option named (the shell would pass it
    on as a file name, and Windows shells do not expand it at all)."""
    import glob

    from edge.errors import DataError

    expanded: list[str] = []
    for path in paths:
        if glob.has_magic(path):
            matches = sorted(glob.glob(path))
            if not matches:
                raise DataError(f"{option} {path}: no file matches the pattern; check the folder and the name")
            expanded += matches
        else:
            expanded.append(path)
    return expanded
