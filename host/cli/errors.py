"""How the command line turns any exception into one line a person can act on.

:func:`describe` names the problem and the fix for every exception that can reach the CLI:
pmactl's own errors already do; file-system errors get the path and what to check; a missing
package names the extra to install; anything else is said as an internal error with the way to
see the traceback (``--debug``). The CLI never prints a traceback without ``--debug``, so a new
failure is one line by construction rather than patched case by case.
"""

from __future__ import annotations

import argparse
import errno
import sys
from typing import NoReturn

from edge.errors import PmactlError

# the extra that brings each optional module (import name -> extra)
EXTRA_OF_MODULE = {
    **dict.fromkeys(("scipy", "matplotlib", "tqdm", "onnx", "asyncssh"), "host"),
    **dict.fromkeys(("onnxruntime", "smbus2", "serial", "gpiod", "threadpoolctl", "cryptography", "mcap"), "edge"),
    "torch": "train",
    "ray": "cluster",
    "mkdocs": "docs",
}

_OS_FIXES = {
    errno.ENOENT: "check the path exists",
    errno.EACCES: "check the permissions or choose another path",
    errno.EPERM: "check the permissions or choose another path",
    errno.EROFS: "the file system is read-only: choose another path",
    errno.ENOSPC: "the disk is full: free space or choose another path",
    errno.EISDIR: "it is a directory: give a file path",
    errno.ENOTDIR: "a part of the path is a file, not a directory",
    errno.EEXIST: "it already exists: remove it or choose another path",
}


class OneLineParser(argparse.ArgumentParser):
    """``argparse`` whose usage errors are one line (the usage is in ``--help``)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def describe(exc: BaseException) -> str:
    """One line naming what went wrong and the fix."""
    if isinstance(exc, PmactlError):
        text = str(exc)
    elif isinstance(exc, ModuleNotFoundError):
        text = _missing_module(exc)
    elif isinstance(exc, OSError):
        text = _os_error(exc)
    elif isinstance(exc, MemoryError):
        text = (
            "out of memory; make the job smaller (a shorter record or protocol, fewer --operators) "
            "or run it on a machine with more memory"
        )
    else:
        detail = str(exc) or "no message"
        text = (
            f"internal error {type(exc).__name__}: {detail}. This is a pmactl bug: rerun with --debug "
            "for the traceback and report it"
        )
    return " ".join(text.split())  # one line whatever the message held


def _missing_module(exc: ModuleNotFoundError) -> str:
    name = (exc.name or "").split(".")[0]
    extra = EXTRA_OF_MODULE.get(name)
    if extra is None:
        return f"{name or exc} is not installed; reinstall pmactl: pip install 'pmactl[edge,host]'"
    hint = " (for the CPU build of torch see the README's install section)" if extra == "train" else ""
    return f"needs the {extra} extra ({name} is not installed); install it with: pip install 'pmactl[{extra}]'{hint}"


def _os_error(exc: OSError) -> str:
    where = exc.filename if exc.filename is not None else "a file"
    reason = exc.strerror or str(exc)
    fix = _OS_FIXES.get(exc.errno or 0, "check the path and the device")
    return f"{where}: {reason}; {fix}"


def print_error(command: str, exc: BaseException) -> None:
    """The one line on stderr."""
    print(f"pmactl {command}: error: {describe(exc)}", file=sys.stderr)
