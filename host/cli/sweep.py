"""``pmactl sweep``: run a regression matrix or parameter sweep, locally or on a Ray cluster."""

from __future__ import annotations

import argparse
import os
import shlex
import signal
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from host.cli.outputs import strict_json

if TYPE_CHECKING:
    from host.sweep.matrix import Matrix


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``pmactl sweep`` to the command line."""
    sweep = sub.add_parser(
        "sweep",
        help="run a matrix of pmactl jobs (HIL regression, fits, diagnoses): local pool or Ray cluster",
        description="Each cell of MATRIX.toml runs as pmactl subprocesses with its own seed; one row per cell goes "
        "to DIR/results.csv and a pass/fail summary to DIR/summary.md. Run the same command again to resume.",
    )
    sweep.add_argument("matrix", metavar="MATRIX.toml", help="the matrix (docs/examples/*.sweep.toml)")
    sweep.add_argument("--out", metavar="DIR", help="results folder (default: sweeps/<matrix name>)")
    sweep.add_argument(
        "--ray",
        metavar="ADDRESS",
        help="run the cells as Ray tasks: 'local' (a fresh Ray instance on this machine), 'auto' (the cluster "
        "started with `ray start`), HOST:PORT or ray://HOST:10001; needs pmactl[cluster]",
    )
    sweep.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="cells at once (default: CPU count / CPUs per cell; on Ray: what the cluster fits)",
    )
    sweep.add_argument("--retry-errors", action="store_true", help="also rerun cells that ended in an error last time")
    sweep.add_argument("--list", action="store_true", help="print each cell's commands and exit without running")
    sweep.add_argument("--json", action="store_true", help="print the outcome as one JSON object (no progress bar)")
    sweep.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from host.sweep.backends import make_backend
    from host.sweep.engine import run_sweep
    from host.sweep.matrix import load_matrix

    matrix = load_matrix(args.matrix)
    if args.list:
        try:
            return _list(matrix)
        except BrokenPipeError:  # pmactl sweep --list | head
            sys.stdout = open(os.devnull, "w")  # noqa: SIM115 - stays open until exit
            return 0
    out = Path(args.out) if args.out else Path("sweeps") / matrix.name
    backend = make_backend(args.ray, args.workers, matrix.resources)
    previous = signal.signal(signal.SIGTERM, _interrupt)  # after ray.init, which installs its own
    try:
        result = run_sweep(
            matrix, out, backend, progress=not args.json and sys.stderr.isatty(), retry_errors=args.retry_errors
        )
    finally:
        signal.signal(signal.SIGTERM, previous)
        backend.close()
    counts = result.counts()
    summary = {
        "matrix": str(matrix.path),
        "out": str(out),
        "backend": result.backend,
        "cells": len(matrix.cells),
        **counts,
        "ran": result.ran,
        "resumed": result.resumed,
        "retried": result.retried,
        "not_run": len(matrix.cells) - len(result.rows),
        "wall_s": round(result.wall_s, 3),
        "cpu_s": round(sum(float(r["cpu_s"] or 0) for r in result.rows), 3),
        "interrupted": result.interrupted,
        "tables": [str(p) for p in result.tables],
    }
    if args.json:
        print(strict_json(summary))
    else:
        print(
            f"{summary['cells']} cells: {counts['pass']} pass, {counts['fail']} fail, {counts['error']} error"
            f" ({result.ran} ran, {result.resumed} from earlier runs, {result.retried} retried)"
            f" in {result.wall_s:.1f} s on {result.backend}"
        )
        for path in result.tables:
            print(f"  {path}")
    if result.interrupted:
        print(
            f"pmactl sweep: interrupted with {summary['not_run']} cells not run; run the same command to resume",
            file=sys.stderr,
        )
        return 130
    return 0 if counts["pass"] == len(matrix.cells) else 1


def _list(matrix: Matrix) -> int:
    print(f"{matrix.name}: {len(matrix.cells)} cells of kind {matrix.kind.name}; axes {', '.join(matrix.axes)}")
    for cell in matrix.cells:
        labels = ", ".join(f"{k}={v}" for k, v in cell.labels.items() if k != "seed")
        print(f"[{cell.index}] {labels}{', ' if labels else ''}seed={cell.seed} key={cell.key}")
        for command in cell.commands(1, str(matrix.path)):
            prefix = [] if command["program"] else ["pmactl"]
            print("    " + shlex.join(prefix + command["argv"]))
        for name in cell.files:
            print(f"    (writes {name})")
    return 0


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt
