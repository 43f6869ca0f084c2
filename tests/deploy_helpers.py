"""Shared set-up for the signing and deploy tests: small bundles, keys, a CLI runner."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from edge.runtime.bundle import resolve_release
from host.cli import main
from models_export.bundle import write_bundle
from models_export.signing import keygen, sign_release
from tests.strategies import random_dpi


def bundle(directory: Path, seed: int = 1, key: Path | None = None) -> Path:
    """A DPI bundle in bar -> mm (what the edge runs), signed with ``key`` when given."""
    model = random_dpi(np.random.default_rng(seed))
    model.reset(model.input_range[0], "descending")
    inverse = model.inverse()
    inverse.reset(inverse.input_range[0], "descending")
    write_bundle(directory, model, inverse, units=("bar", "mm"))
    if key is not None:
        sign_release(directory, key)
    return directory


def keys(directory: Path) -> tuple[Path, Path]:
    return keygen(directory)


def release_id(directory: Path) -> str:
    return resolve_release(directory).name


def current(target: Path) -> str | None:
    try:
        return Path(os.readlink(target / "current")).name
    except FileNotFoundError:
        return None


def cli(capsys, *argv: str) -> tuple[int, str, str]:
    """``pmactl ARGV`` in this process: exit status, stdout, stderr."""
    status = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return status, captured.out, captured.err
