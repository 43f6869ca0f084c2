"""Write a model bundle: forward and inverse lookup tables plus a JSON manifest with checksums.

Layout of a bundle directory::

    manifest.json   format, version, model kind, units, ranges, files with sha256, fit record
    forward.npz     lookup table of the identified model (input u -> output y)
    inverse.npz     lookup table of its inverse (desired y -> input u), clamped and flagged
    correction.onnx optional neural correction of the feedforward (``add_correction``)

The directory is written next to its destination and swapped in only when complete, so a
failed write leaves an existing bundle untouched.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import math
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from edge import __version__
from edge.hysteresis.base import HysteresisModel
from edge.hysteresis.lut import write_table
from edge.runtime.bundle import FORMAT, FORMAT_VERSION, MANIFEST

CORRECTION_FILE = "correction.onnx"


def sha256_of(path: Path) -> str:
    """Hex SHA-256 of a file."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 16), b""):
            digest.update(block)
    return digest.hexdigest()


def _json_range(values: tuple[float, float]) -> list[float | None]:
    return [v if math.isfinite(v) else None for v in values]


@contextmanager
def _staged(target: Path) -> Iterator[Path]:
    """A fresh directory beside ``target``, swapped in for it when the block completes and
    removed if it raises: a failed write never touches the existing bundle."""
    target.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        yield staging
        _swap_in(staging, target)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise


def write_bundle(
    directory: str | Path,
    forward: HysteresisModel,
    inverse: HysteresisModel,
    *,
    units: tuple[str, str] = ("u", "y"),
    fit_record: dict[str, object] | None = None,
) -> Path:
    """Write ``forward`` and ``inverse`` (in their current states) as a bundle at ``directory``."""
    target = Path(directory)
    with _staged(target) as staging:
        files = {}
        for role, model in (("forward", forward), ("inverse", inverse)):
            path = write_table(model.compile(), staging / f"{role}.npz")
            files[path.name] = {"role": role, "kind": model.kind, "sha256": sha256_of(path)}
        manifest = {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "created_utc": dt.datetime.now(dt.UTC).isoformat(timespec="seconds"),
            "pmactl_version": __version__,
            "model": {
                "kind": forward.kind,
                "units": {"input": units[0], "output": units[1]},
                "input_range": _json_range(forward.input_range),
                "reachable_output_range": _json_range(inverse.input_range),
            },
            "files": files,
            "fit": fit_record or {},
        }
        (staging / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")
    return target


def add_correction(directory: str | Path, model_path: str | Path, spec: dict[str, object]) -> Path:
    """Add (or replace) the ONNX correction of the bundle at ``directory``.

    ``spec`` is the manifest's ``correction`` entry without ``file`` (features, input, output,
    optional state; see :mod:`edge.control.neural`). The bundle is rewritten beside the old one
    and swapped in, so a failure leaves the old bundle as it was.
    """
    target = Path(directory)
    manifest = json.loads((target / MANIFEST).read_text())
    with _staged(target) as staging:
        files = {name: entry for name, entry in manifest["files"].items() if entry.get("role") != "correction"}
        for name in files:
            shutil.copy2(target / name, staging / name)
        shutil.copy2(model_path, staging / CORRECTION_FILE)
        files[CORRECTION_FILE] = {"role": "correction", "kind": "onnx", "sha256": sha256_of(staging / CORRECTION_FILE)}
        manifest["files"] = files
        manifest["correction"] = {"file": CORRECTION_FILE, **spec}
        (staging / MANIFEST).write_text(json.dumps(manifest, indent=2) + "\n")
    return target


def _swap_in(staging: Path, target: Path) -> None:
    """Replace ``target`` by ``staging``; the old bundle survives until the new one is in place."""
    if not target.exists():
        staging.rename(target)
        return
    retired = target.with_name(f".{target.name}.old")
    shutil.rmtree(retired, ignore_errors=True)
    target.rename(retired)
    staging.rename(target)
    shutil.rmtree(retired, ignore_errors=True)
