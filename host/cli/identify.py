"""``pmactl identify``: dynamic and static models beyond hysteresis (PAMInertial, Ai2019 eqs 15-16).

* ``identify fotd RUN.csv [RUN.csv ...]``: first-order-plus-dead-time from sinusoid harmonics,
  or from step / ramp responses;
* ``identify force DATA.csv --model {tondu-lopez,sarosi}``: static muscle force law;
* ``identify maxwell-slip DATA.csv``: presliding friction as Maxwell-slip elements.

Subcommand modules are imported only when run (``pmactl --help`` needs no scipy).
"""

from __future__ import annotations

import argparse

from host.cli.lazy import lazy
from host.cli.options import add_data_options


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``pmactl identify`` and its subcommands to the top-level parser."""
    ident = sub.add_parser("identify", help="dead time, lag and gain; static force laws; Maxwell-slip friction")
    isub = ident.add_subparsers(dest="identify_command", required=True, metavar="IDENTIFY_COMMAND")

    fotd = isub.add_parser(
        "fotd",
        help="K e^{-sL}/(1+sT) from sinusoids at several frequencies (or a step/ramp response)",
        description="First harmonics of u and y by least-squares Fourier fit on every sinusoidal segment "
        "(a stepped sine, or one run per frequency), then K, T, L with standard errors by weighted nonlinear "
        "least squares, and the equivalent elliptic loss angle per frequency (PAMInertial).",
    )
    fotd.add_argument("runs", nargs="+", metavar="RUN.csv", help="recordings with t, u, y")
    fotd.add_argument(
        "--method",
        choices=["auto", "harmonic", "time"],
        default="auto",
        help="harmonic: frequency response; time: step/ramp response fit; auto: harmonic when sinusoids at "
        ">= 2 frequencies are found (default)",
    )
    fotd.add_argument(
        "--output-column",
        default="y",
        metavar="NAME",
        help="column to use as the output (default y; e.g. p for command -> measured pressure)",
    )
    fotd.add_argument(
        "--no-hysteresis-phase",
        action="store_true",
        help="do not fit a frequency-independent hysteresis loss angle beside K, T, L",
    )
    add_data_options(fotd)
    fotd.add_argument("--json", action="store_true", help="print one JSON object")
    fotd.set_defaults(run=lazy("host.cli.identify_run", "run_fotd"))

    force = isub.add_parser(
        "force",
        help="static muscle force F(p, contraction) by least squares",
        description="Fit a static force law to isometric / isotonic data: columns p [bar] (or u), "
        "contraction as y [mm] and a force column force [N] (or load [kg], converted with g).",
    )
    force.add_argument("data", metavar="DATA.csv", help="isometric or isotonic run (columns as described above)")
    force.add_argument(
        "--model",
        required=True,
        choices=["tondu-lopez", "sarosi"],
        help="static force law (PAMInertial eq 1 or Ai2019 eqs 15-16)",
    )
    force.add_argument(
        "--rest-length-mm", type=float, metavar="MM", help="rest length l0 [mm] (contraction ratio = y / l0)"
    )
    force.add_argument("--radius-mm", type=float, metavar="MM", help="tondu-lopez: inner radius r0 [mm] (area pi r0^2)")
    force.add_argument(
        "--columns",
        metavar="ROLE=NAME,...",
        help="the file's own names for p (or u), y and force (or load), e.g. p=pressure_bar,y=contraction_mm,"
        "force=force_N (default: columns named so)",
    )
    force.add_argument("--json", action="store_true", help="print one JSON object")
    force.set_defaults(run=lazy("host.cli.identify_run", "run_force"))

    slip = isub.add_parser(
        "maxwell-slip",
        help="presliding friction force vs position as N Maxwell-slip elements",
        description="Fit N elastoplastic elements (stiffness, break force) to force vs position; N chosen by "
        "held-out RMSE when not given.",
    )
    slip.add_argument("data", metavar="DATA.csv", help="columns t, x (position) and force (or u, y)")
    slip.add_argument("--elements", type=int, metavar="N", help="number of elements (default: held-out choice)")
    slip.add_argument("--position-column", default="x", metavar="NAME", help="position column [mm] (default x)")
    slip.add_argument("--force-column", default="force", metavar="NAME", help="force column [N] (default force)")
    slip.add_argument("--plot", metavar="OUT.png", help="write measured vs fitted loops here")
    slip.add_argument("--json", action="store_true", help="print one JSON object")
    slip.set_defaults(run=lazy("host.cli.identify_run", "run_maxwell_slip"))
