"""The ``pmactl`` command line: one entry point, subcommands imported only when run.

``pmactl --help`` needs nothing beyond the standard library, so it works on an SBC with only
the ``edge`` extra; a host command there says which extra to install. Errors are one line on
stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from collections.abc import Callable, Sequence

from edge import cli as edge_cli
from host.cli.errors import OneLineParser, print_error
from host.cli.options import add_fit_options, add_hil_options, positive_rate, version


def _lazy(module: str, function: str = "run") -> Callable[[argparse.Namespace], int]:
    """A subcommand whose module is imported only when it runs (``--help`` stays dependency-free)."""

    def run(args: argparse.Namespace) -> int:
        return getattr(importlib.import_module(module), function)(args)

    return run


def _hil_serve(args: argparse.Namespace) -> int:
    from hil.serve import serve

    return serve(args.effect, args.seed, args.rate, args.duration, args.config)


def build_parser() -> argparse.ArgumentParser:
    from hil.effects import EFFECTS  # here, not at the top: pmactl edge never imports hil
    from hil.scenarios import SCENARIOS

    parser = OneLineParser(
        prog="pmactl",
        description="Pneumatic muscle actuator control: hysteresis identification, models, deployment.",
    )
    parser.add_argument("--version", action="version", version=f"pmactl {version()}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error (any position)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    demo = sub.add_parser("demo", help="identify every model on the shipped example data and compare them")
    demo.add_argument(
        "--out",
        metavar="DIR",
        default="pmactl-demo",
        help="write the bundles and figures here (default: ./pmactl-demo; new, empty, or an earlier demo's folder)",
    )
    demo.add_argument("--json", action="store_true", help="print the comparison as JSON (no progress lines)")
    demo.set_defaults(run=_lazy("host.cli.demo"))

    fit = sub.add_parser("fit", help="identify a hysteresis model from a measured-data CSV")
    add_fit_options(fit)
    fit.add_argument(
        "--parameterisation",
        choices=["free", "exponential"],
        default="free",
        help="pi and mpi: free play weights or seed 000's beta/delta/mu form",
    )
    fit.add_argument(
        "--preisach-method",
        choices=["lsq", "forc"],
        default="lsq",
        help="preisach only: least squares on any data, or first-order reversal curves",
    )
    fit.add_argument(
        "--calibration",
        type=float,
        default=0.1,
        metavar="FRACTION",
        help="share of each test record (after it starts moving) used to estimate its "
        "initial state and offset; never scored (default 0.1)",
    )
    fit.add_argument("--units", default="u,y", metavar="U,Y", help="units of input and output for the bundle manifest")
    fit.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    fit.add_argument(
        "--save", metavar="DIR", help="write the lookup-table bundle (model + inverse) here; its parent must exist"
    )
    fit.set_defaults(run=_lazy("host.cli.fit"))

    importlib.import_module("host.cli.diagnose").register(sub)

    edge_cli.register(sub)

    hil = sub.add_parser("hil", help="the emulated rig: recordings with hidden effects")
    hil_sub = hil.add_subparsers(dest="hil_command", required=True, metavar="HIL_COMMAND")
    rec = hil_sub.add_parser("record", help="run a test protocol on the emulated rig and write a measured-data CSV")
    rec.add_argument("--scenario", required=True, choices=list(SCENARIOS), help="test protocol the rig runs")
    rec.add_argument("--seed", type=int, default=0, help="random seed (protocol details and effect parameters)")
    rec.add_argument("--duration", type=float, default=120.0, metavar="S", help="seconds of recording (default 120)")
    rec.add_argument(
        "--effect",
        default="none",
        choices=list(EFFECTS),
        help="hidden effect, parameters drawn from physical ranges (default none)",
    )
    rec.add_argument(
        "--rate", type=positive_rate, default=100.0, metavar="HZ", help="sample rate, divides 1000 (default 100)"
    )
    rec.add_argument(
        "--decoy-columns", action="store_true", help="let load and temperature columns vary without any physical effect"
    )
    rec.add_argument(
        "--rig",
        choices=["muscle", "joint"],
        default="muscle",
        help="one muscle, or two on a pulley (writes t,u,y,u1,u2,p1,p2,theta)",
    )
    rec.add_argument(
        "--joint-command",
        choices=["differential", "angle"],
        default="differential",
        help="joint only: u is the differential pressure [bar], or a commanded angle [deg] through "
        "the edge's static inversion (what the joint controller's Preisach map is fitted on)",
    )
    rec.add_argument("--out", required=True, metavar="CSV", help="output CSV; the truth goes to <name>.truth.json")
    rec.set_defaults(run=_lazy("host.cli.hil", "run_record"))
    srv = hil_sub.add_parser("serve", help="real-time mode: serve the emulated rig's serial DAQ on a pseudo-terminal")
    add_hil_options(srv, EFFECTS)
    srv.add_argument("--rate", type=positive_rate, default=1000.0, metavar="HZ", help="sample frames per second")
    srv.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: until SIGTERM)")
    srv.add_argument("--config", metavar="RIG.toml", help="wire sensors and valve as this rig config says")
    srv.set_defaults(run=_hil_serve)
    importlib.import_module("host.cli.bundle").register(sub)
    importlib.import_module("host.cli.deploy").register(sub)
    importlib.import_module("host.cli.sweep").register(sub)
    importlib.import_module("host.cli.identify").register(sub)
    importlib.import_module("host.cli.train").register(sub)
    importlib.import_module("host.cli.simulate").register(sub)
    importlib.import_module("host.cli.quantise").register(sub)
    return parser


def _edge_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="pmactl", description="pmactl edge runtime")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    edge_cli.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pmactl`` console script.

    Whatever reaches here is one line on stderr and exit status 2 (130 on Ctrl-C); ``--debug``
    anywhere on the line re-raises instead, with the traceback.
    """
    arguments = list(sys.argv[1:] if argv is None else argv)
    debug = "--debug" in arguments
    arguments = [a for a in arguments if a != "--debug"]
    # the SBC path: pmactl edge ... parses with the edge subcommands alone (no hil, no host tools)
    parser = _edge_parser() if arguments[:1] == ["edge"] else build_parser()
    args = parser.parse_args(arguments)
    run: Callable[[argparse.Namespace], int] = args.run
    warnings.showwarning = _one_line_warning
    try:
        return run(args)
    except KeyboardInterrupt:
        print(f"pmactl {args.command}: interrupted", file=sys.stderr)
        return 130
    except Exception as exc:  # noqa: BLE001 - every error is one line; --debug shows the traceback
        if debug:
            raise
        print_error(args.command, exc)
        return 2


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
    print(f"pmactl: warning: {' '.join(str(message).split())}", file=sys.stderr)
