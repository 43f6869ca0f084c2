"""The ``pmactl`` command line: one entry point, subcommands imported only when run.

Adding a command: a module ``host/cli/NAME.py`` with ``register(sub)`` (its argparse
definitions, ``set_defaults(run=lazy("host.cli.NAME"))``) and ``run(args) -> int`` (the work,
importing what it needs inside), and one line in :data:`COMMAND_MODULES`.

``pmactl --help`` needs nothing beyond the standard library, so it works on an SBC with only
the ``edge`` extra; a host command there says which extra to install. Errors are one line on
stderr and exit status 2.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from collections.abc import Callable, Sequence
from typing import TextIO

from edge import cli as edge_cli
from host.cli.errors import OneLineParser, print_error
from host.cli.options import version

# Every command, in --help order: the module whose register(sub) adds it. A module's top level
# imports the standard library only (run() imports the work), so --help works on an edge install.
COMMAND_MODULES = (
    "host.cli.demo",
    "host.cli.fit",
    "host.cli.diagnose",
    "edge.cli",
    "host.cli.hil",
    "host.cli.bundle",
    "host.cli.deploy",
    "host.cli.sweep",
    "host.cli.identify",
    "host.cli.train",
    "host.cli.quantise",
    "host.cli.simulate",
)


def build_parser() -> argparse.ArgumentParser:
    """The whole ``pmactl`` command line: every module of :data:`COMMAND_MODULES` adds its commands."""
    parser = OneLineParser(
        prog="pmactl",
        description="Pneumatic muscle actuator control: hysteresis identification, models, deployment.",
    )
    parser.add_argument("--version", action="version", version=f"pmactl {version()}")
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error (any position)")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMAND_MODULES:
        importlib.import_module(module).register(sub)
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
    except BrokenPipeError:
        return _reader_went_away()
    except Exception as exc:  # noqa: BLE001 - every error is one line; --debug shows the traceback
        if debug:
            raise
        print_error(args.command, exc)
        return 2


def _reader_went_away() -> int:
    """``pmactl ... | head -1``: the reader closed the pipe; stop quietly, as a killed ``cat`` would.

    stdout is pointed at /dev/null so the interpreter's final flush does not report the pipe again.
    """
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return 141  # 128 + SIGPIPE, what the shell reports for a command the pipe ended


def _one_line_warning(
    message: Warning | str,
    category: type[Warning],
    filename: str,
    lineno: int,
    file: TextIO | None = None,
    line: str | None = None,
) -> None:
    print(f"pmactl: warning: {' '.join(str(message).split())}", file=sys.stderr)
