"""Argument definitions shared by the ``fit`` and ``hil`` subcommands, with their ranges stated.

Only the standard library here: ``pmactl --help`` must work on an ``edge``-only install.
"""

from __future__ import annotations

import argparse
import math
from importlib import metadata

MODELS = ("pi", "mpi", "dpi", "preisach")
# (default, smallest, largest): plays / digits, or Preisach grid intervals. 100 plays resolve
# 0.5 % of the input range, below what a 12-bit sensor's loop shape shows; 60 Preisach
# intervals are 1830 Everett cells (~30 MB of normal equations), 100 would be 5050 (~200 MB).
OPERATORS = {"pi": (25, 1, 100), "mpi": (25, 1, 100), "dpi": (25, 1, 100), "preisach": (20, 2, 60)}
OPERATORS_HELP = (
    "play operators (pi, mpi), digits (dpi) or grid intervals (preisach); default 25 (pi, mpi, dpi) or 20 "
    "(preisach), range 1-100 (pi, mpi, dpi) or 2-60 (preisach)"
)


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
