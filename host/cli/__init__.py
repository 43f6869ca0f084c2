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

from edge.errors import PmactlError
from hil.effects import EFFECTS
from hil.scenarios import SCENARIOS

HOST_ONLY_MODULES = {"scipy", "matplotlib"}
EDGE_MODULES = {"onnxruntime", "smbus2", "serial", "gpiod"}


def _lazy(module: str, function: str = "run") -> Callable[[argparse.Namespace], int]:
    """A subcommand whose module is imported only when it runs (``--help`` stays dependency-free)."""

    def run(args: argparse.Namespace) -> int:
        return getattr(importlib.import_module(module), function)(args)

    return run


def _hil_serve(args: argparse.Namespace) -> int:
    from hil.serve import serve

    return serve(args.effect, args.seed, args.rate, args.duration)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pmactl",
        description="Pneumatic muscle actuator control: hysteresis identification, models, deployment.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    demo = sub.add_parser("demo", help="identify every model on the shipped example data and compare them")
    demo.add_argument("--out", metavar="DIR", help="keep the bundles here (default: a temporary directory)")
    demo.add_argument("--json", action="store_true", help="print the comparison as JSON")
    demo.set_defaults(run=_lazy("host.cli.demo"))

    fit = sub.add_parser("fit", help="identify a hysteresis model from a measured-data CSV")
    fit.add_argument("--model", required=True, choices=["pi", "mpi", "dpi", "preisach"])
    fit.add_argument("--train", required=True, metavar="CSV", help="training recording (t,u,y)")
    fit.add_argument("--test", action="append", default=[], metavar="CSV", help="held-out recording (repeatable)")
    fit.add_argument("--operators", type=int, metavar="N", help="play operators / DPI digits / Preisach grid intervals")
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
    fit.add_argument("--save", metavar="DIR", help="write the lookup-table bundle (model + inverse) here")
    fit.set_defaults(run=_lazy("host.cli.fit"))

    diag = sub.add_parser(
        "diagnose", help="what the simulation gets wrong on a recording: name the cause, extend, measure the gain"
    )
    diag.add_argument("data", metavar="DATA.csv", help="measured data (t, u, y; optional load, temperature, p)")
    diag.add_argument("--report", metavar="DIR", help="write report.md and PNG figures here")
    diag.add_argument("--json", metavar="OUT.json", help="write the result as JSON")
    diag.add_argument("--folds", type=int, default=4, help="blocked held-out folds in time (default 4)")
    diag.set_defaults(run=_lazy("host.cli.diagnose"))

    edge = sub.add_parser("edge", help="the control loop that runs on the rig's computer")
    edge_sub = edge.add_subparsers(dest="edge_command", required=True, metavar="EDGE_COMMAND")
    erun = edge_sub.add_parser("run", help="run the fixed-rate control loop on the rig a config names")
    erun.add_argument("--config", required=True, metavar="RIG.toml", help="rig config (docs/examples/*.toml)")
    erun.add_argument("--bundle", required=True, metavar="DIR", help="model bundle written by pmactl fit --save")
    erun.add_argument("--duration", type=float, metavar="S", help="seconds to run (default: the reference's length)")
    erun.add_argument(
        "--reference",
        default="sine:amplitude=30,frequency=0.2,offset=40",
        metavar="SPEC",
        help="desired contraction: sine:amplitude=,frequency=,offset= | ramp-sine:peak=,frequency=,offset=,rise=,hold= "
        "| const:value= | a CSV with t,y_ref (default: seed 000's 30 sin(2 pi 0.2 t) + 40 mm)",
    )
    erun.add_argument("--no-feedforward", action="store_true", help="PID alone (no inverse-hysteresis feedforward)")
    erun.add_argument("--no-correction", action="store_true", help="ignore the bundle's ONNX correction")
    erun.add_argument("--settle", type=float, default=0.0, metavar="S", help="leave the first S seconds unscored")
    erun.add_argument("--telemetry", metavar="FILE", help="write per-tick telemetry here (+ FILE.events.jsonl)")
    erun.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    erun.set_defaults(run=_lazy("host.cli.edge"))
    etel = edge_sub.add_parser("telemetry", help="turn a telemetry file into CSV and a plot")
    etel.add_argument("file", metavar="FILE", help="telemetry written by pmactl edge run --telemetry")
    etel.add_argument("--csv", metavar="OUT.csv")
    etel.add_argument("--plot", metavar="OUT.png")
    etel.set_defaults(run=_lazy("host.cli.edge", "telemetry"))

    hil = sub.add_parser("hil", help="the emulated rig: recordings with hidden effects")
    hil_sub = hil.add_subparsers(dest="hil_command", required=True, metavar="HIL_COMMAND")
    rec = hil_sub.add_parser("record", help="run a test protocol on the emulated rig and write a measured-data CSV")
    rec.add_argument("--scenario", required=True, choices=list(SCENARIOS))
    rec.add_argument("--seed", type=int, default=0, help="random seed (protocol details and effect parameters)")
    rec.add_argument("--duration", type=float, default=120.0, metavar="S", help="seconds of recording (default 120)")
    rec.add_argument(
        "--effect",
        default="none",
        choices=list(EFFECTS),
        help="hidden effect, parameters drawn from physical ranges (default none)",
    )
    rec.add_argument("--rate", type=float, default=100.0, metavar="HZ", help="sample rate, divides 1000 (default 100)")
    rec.add_argument(
        "--decoy-columns", action="store_true", help="let load and temperature columns vary without any physical effect"
    )
    rec.add_argument("--out", required=True, metavar="CSV", help="output CSV; the truth goes to <name>.truth.json")
    rec.set_defaults(run=_lazy("host.cli.hil", "run_record"))
    srv = hil_sub.add_parser("serve", help="real-time mode: serve the emulated rig's serial DAQ on a pseudo-terminal")
    srv.add_argument("--effect", default="none", choices=list(EFFECTS))
    srv.add_argument("--seed", type=int, default=0)
    srv.add_argument("--rate", type=float, default=1000.0, metavar="HZ", help="sample frames per second")
    srv.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: until SIGTERM)")
    srv.set_defaults(run=_hil_serve)
    importlib.import_module("host.cli.train").register(sub)
    importlib.import_module("host.cli.quantise").register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pmactl`` console script."""
    args = build_parser().parse_args(argv)
    run: Callable[[argparse.Namespace], int] = args.run
    warnings.showwarning = _one_line_warning
    try:
        return run(args)
    except PmactlError as exc:
        print(f"pmactl {args.command}: error: {exc}", file=sys.stderr)
    except ModuleNotFoundError as exc:
        extra = "host" if exc.name in HOST_ONLY_MODULES else "edge" if exc.name in EDGE_MODULES else None
        if extra is None:
            raise
        print(
            f"pmactl {args.command}: error: needs the {extra} extra ({exc.name} is not installed); "
            f"install it with: pip install 'pmactl[{extra}]'",
            file=sys.stderr,
        )
    except KeyboardInterrupt:
        print(f"pmactl {args.command}: interrupted", file=sys.stderr)
        return 130
    return 2


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:  # noqa: ANN001
    print(f"pmactl: warning: {message}", file=sys.stderr)
