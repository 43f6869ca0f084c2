"""Check an output path before the work that fills it, so a bad path costs nothing.

A missing parent directory is refused rather than created (a typo should not grow a tree), a
read-only one is found by writing a probe file (``os.access`` says yes to root on read-only
mounts), a file where a directory is wanted (or the reverse) and an unknown figure format are
named with the fix.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Iterable
from pathlib import Path
from typing import Literal

from edge.errors import PmactlError

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")


class OutputPathError(PmactlError, OSError):
    """An output path pmactl cannot write (missing or read-only directory, wrong kind, format)."""


def check_output(
    path: str | Path,
    option: str,
    *,
    kind: Literal["file", "dir"] = "file",
    suffixes: Iterable[str] | None = None,
) -> Path:
    """``path`` if ``option``'s output can be written there; :class:`OutputPathError` otherwise."""
    target = Path(path)
    if suffixes is not None:
        allowed = tuple(suffixes)
        if target.suffix.lower() not in allowed:
            raise OutputPathError(
                f"{option} {path}: cannot write the format {target.suffix or '(no suffix)'!r}; "
                f"end the name in {', '.join(allowed)}"
            )
    if kind == "dir" and target.exists() and not target.is_dir():
        raise OutputPathError(f"{option} {path}: is a file, not a directory; give a new or existing directory")
    if kind == "file" and target.is_dir():
        raise OutputPathError(f"{option} {path}: is a directory; give a file name inside it")
    where = target if kind == "dir" and target.is_dir() else target.parent
    if not where.is_dir():
        raise OutputPathError(
            f"{option} {path}: directory {where} does not exist; create it (mkdir -p {where}) or choose another path"
        )
    try:
        handle, probe = tempfile.mkstemp(prefix=".pmactl-probe-", dir=where)
    except OSError as exc:
        raise OutputPathError(
            f"{option} {path}: cannot write into {where} ({exc.strerror}); choose a writable directory"
        ) from exc
    os.close(handle)
    os.unlink(probe)
    return target


def _finite_or_none(value: object) -> object:
    if isinstance(value, float):  # numpy's float64 is a float too
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _finite_or_none(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite_or_none(v) for v in value]
    if hasattr(value, "tolist") and hasattr(value, "dtype"):  # a numpy scalar or array
        return _finite_or_none(value.tolist())
    return value


def strict_json(value: object, **options: object) -> str:
    """``json.dumps`` that writes standard JSON: NaN and +-inf become null (``json`` writes them as
    ``NaN``/``-Infinity``, which other JSON readers refuse), numpy numbers become numbers."""
    return json.dumps(_finite_or_none(value), allow_nan=False, **options)  # type: ignore[arg-type]
