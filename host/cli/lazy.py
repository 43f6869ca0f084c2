"""The one way a subcommand names the code it runs without importing it: ``lazy(module)``.

``pmactl --help`` and the parsing of every command need only the standard library (an
``edge``-only install has no scipy); the module that does the work is imported when the
command runs, and a missing extra is then one line naming it (:mod:`host.cli.errors`).
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable


def lazy(module: str, function: str = "run") -> Callable[[argparse.Namespace], int]:
    """A ``run(args)`` that imports ``module`` and calls its ``function`` when the command runs."""

    def run(args: argparse.Namespace) -> int:
        return int(getattr(importlib.import_module(module), function)(args))

    return run
