"""Argument definitions shared by the ``fit`` and ``hil`` subcommands, with their ranges stated.

Only the standard library here: ``pmactl --help`` must work on an ``edge``-only install.
"""

from __future__ import annotations

import argparse
import math
from importlib import metadata

from host.operator_ranges import MODELS, OPERATORS, OPERATORS_HELP


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
