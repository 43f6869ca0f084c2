"""``pmactl demo``: the whole path on the shipped example data (the work is in :mod:`host.demo`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from host.cli.lazy import lazy
from host.cli.outputs import OutputPathError, check_output

DEMO_MARKER = ".pmactl-demo"  # written into --out: the demo replaces only its own files in a folder it made


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl demo``."""
    demo = sub.add_parser("demo", help="identify every model on the shipped example data and compare them")
    demo.add_argument(
        "--out",
        metavar="DIR",
        default="pmactl-demo",
        help="write the bundles and figures here (default: ./pmactl-demo; new, empty, or an earlier demo's folder)",
    )
    demo.add_argument("--json", action="store_true", help="print the comparison as JSON (no progress lines)")
    demo.set_defaults(run=lazy("host.cli.demo"))


def run(args: argparse.Namespace) -> int:
    from host.demo import run_demo

    return run_demo(args)


def demo_directory(path: str) -> Path:
    """``--out`` if the demo may write there: new, empty, or made by an earlier demo (it holds
    :data:`DEMO_MARKER`). Anything else is the user's, and the demo would replace figures and
    telemetry in it, so it is refused with one line."""
    out = check_output(path, "--out", kind="dir")
    if out.is_dir() and any(out.iterdir()) and not (out / DEMO_MARKER).is_file():
        raise OutputPathError(
            f"--out {out}: holds files the demo did not write; give a new or empty directory "
            f"(an earlier demo's folder has {DEMO_MARKER} in it)"
        )
    out.mkdir(exist_ok=True)
    (out / DEMO_MARKER).write_text("written by pmactl demo; the next demo may replace what is here\n")
    return out
