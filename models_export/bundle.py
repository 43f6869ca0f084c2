"""Write a model bundle: lookup tables, golden vectors and a JSON manifest with checksums.

A bundle directory keeps complete releases and points ``current`` at one
(:mod:`models_export.store`)::

    DIR/current -> releases/<id>     <id>: first 16 hex digits of the manifest's SHA-256
    DIR/releases/<id>/manifest.json  format, model kind, units, ranges, files with sha256, fit
                                     record, provenance (training data sha256, pmactl version)
                     forward.npz     lookup table of the identified model (input u -> output y)
                     inverse.npz     lookup table of its inverse (desired y -> input u)
                     golden.npz      inputs and outputs of both tables (and the correction)
                     correction.onnx optional neural correction (``add_correction``)
                     forward_net.onnx, inverse_net.onnx, operator.npz
                                     optional LSTM-NARMAX step graphs (``pmactl train --save``)
                                     and the forward net's operator table (:class:`NetPart`)
                     signature.json  optional Ed25519 signature (``pmactl bundle sign``)

Every write makes a new release beside the old ones and flips ``current`` by rename, so a
reader never sees a half-written bundle and the previous release stays in ``previous``.
Nothing that is not a pmactl bundle is ever deleted or moved: such a destination is refused.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import json
import math
import platform
import shutil
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from edge import __version__
from edge.errors import BundleError
from edge.hysteresis.base import HysteresisModel
from edge.hysteresis.lut import CompiledModel, read_table, write_table
from edge.runtime.bundle import CURRENT, FORMAT, FORMAT_VERSION, MANIFEST, RELEASES, load_bundle, sha256_file
from models_export import store
from models_export.golden import GOLDEN_FILE, correction_vectors, net_vectors, table_vectors, write_golden

CORRECTION_FILE = "correction.onnx"
OPERATOR_FILE = "operator.npz"


@dataclass
class NetPart:
    """A net a bundle holds: its exported step graph and the manifest description.

    ``which``: ``forward`` (pressure -> contraction) or ``inverse`` (target -> command);
    ``spec``: inputs, output, state, ``step_s`` [s] (the sample period it was trained at),
    ``u_range`` and ``n_range`` (training ranges of its inputs), training record;
    ``operator``: the forward net's operator model, in its rest state, and ``warp``
    (centre, half range) of its input.
    """

    which: str
    onnx_path: Path
    spec: dict[str, object]
    operator: HysteresisModel | None = None
    warp: tuple[float, float] = (0.0, 0.0)


PROTECTED_FIELDS = ("format", "format_version", "files", "model", "created_utc")
sha256_of = sha256_file  # the name callers used before


def _json_range(values: tuple[float, float]) -> list[float | None]:
    return [v if math.isfinite(v) else None for v in values]


def check_save_target(directory: str | Path) -> Path:
    """``directory`` if a bundle may be written there (new, empty, or a pmactl bundle directory),
    else one :class:`BundleError` line; nothing is touched either way."""
    target = Path(directory)
    if target.is_symlink() and not target.exists():
        raise BundleError(f"{target}: is a dangling link; choose a new directory for the bundle (nothing written)")
    if not target.exists():
        return target
    if not target.is_dir():
        raise BundleError(
            f"{target}: exists and is not a directory; choose a new directory for the bundle (nothing written)"
        )
    if store.is_store(target):
        return target
    entries = sorted(p.name for p in target.iterdir())
    if not entries:
        return target
    if MANIFEST in entries:
        raise BundleError(
            f"{target}: is a bundle in the older single-directory layout; save to a new directory "
            "(this one still loads) (nothing written)"
        )
    shown = ", ".join(entries[:3]) + (", ..." if len(entries) > 3 else "")
    raise BundleError(
        f"{target}: is a directory that is not a pmactl bundle (it holds {shown}); choose a new or empty "
        "directory (nothing written)"
    )


def provenance_record(training_data: Iterable[str | Path] = ()) -> dict[str, object]:
    """Where a bundle came from: pmactl and Python versions, host, and each training file's SHA-256."""
    files = []
    for item in training_data:
        path = Path(item)
        try:
            files.append({"file": path.name, "sha256": sha256_file(path), "bytes": path.stat().st_size})
        except OSError as exc:
            raise BundleError(f"{path}: training data unreadable for the provenance record ({exc})") from exc
    return {
        "pmactl_version": __version__,
        "python": platform.python_version(),
        "host": platform.node(),
        "training_data": files,
    }


def write_bundle(
    directory: str | Path,
    forward: HysteresisModel,
    inverse: HysteresisModel,
    *,
    units: tuple[str, str] = ("u", "y"),
    fit_record: dict[str, object] | None = None,
    training_data: Iterable[str | Path] = (),
    provenance: Mapping[str, object] | None = None,
    keep: int = store.DEFAULT_KEEP,
    nets: Sequence[NetPart] = (),
) -> Path:
    """Write ``forward`` and ``inverse`` (in their current states) as a new release at ``directory``.

    ``nets``: LSTM-NARMAX step graphs to hold as well (``pmactl train --save``).

    ``training_data``: files the model was fitted on (their SHA-256 goes into the provenance);
    ``provenance``: extra provenance fields; ``keep``: releases kept (current and previous always).
    Returns ``directory``.
    """
    target = check_save_target(directory)

    def build(staging: Path) -> dict[str, object]:
        files: dict[str, object] = {}
        for role, model in (("forward", forward), ("inverse", inverse)):
            path = write_table(model.compile(), staging / f"{role}.npz")
            files[path.name] = {"role": role, "kind": model.kind, "sha256": sha256_file(path)}
        net_entries = _write_nets(staging, nets, files)
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "created_utc": _now(),
            "pmactl_version": __version__,
            "model": {
                "kind": forward.kind,
                "units": {"input": units[0], "output": units[1]},
                "input_range": _json_range(forward.input_range),
                "reachable_output_range": _json_range(inverse.input_range),
            },
            "files": files,
            "fit": fit_record or {},
            "provenance": {**provenance_record(training_data), **(provenance or {})},
            **({"nets": net_entries} if net_entries else {}),
        }

    return _new_release(target, build, keep)


def _write_nets(staging: Path, nets: Sequence[NetPart], files: dict[str, object]) -> dict[str, object]:
    """Copy each net's graph (and the forward net's operator table) into ``staging``; their entries."""
    entries: dict[str, object] = {}
    for part in nets:
        if part.which not in ("forward", "inverse") or part.which in entries:
            raise BundleError(f"net {part.which!r}: a bundle holds one forward and one inverse net")
        name = f"{part.which}_net.onnx"
        shutil.copyfile(part.onnx_path, staging / name)
        files[name] = {"role": f"{part.which}_net", "kind": "onnx", "sha256": sha256_file(staging / name)}
        spec: dict[str, object] = {"file": name, **part.spec}
        if part.which == "forward" and part.spec.get("model") != "state-space":  # a state-space net has no operator
            if part.operator is None:
                raise BundleError("the forward net needs its operator model (NetPart.operator)")
            path = write_table(part.operator.compile(), staging / OPERATOR_FILE)
            files[OPERATOR_FILE] = {"role": "operator", "kind": part.operator.kind, "sha256": sha256_file(path)}
            spec["operator"] = {"file": OPERATOR_FILE, "warp_centre": part.warp[0], "warp_half_range": part.warp[1]}
        entries[part.which] = spec
    return entries


def add_correction(directory: str | Path, model_path: str | Path, spec: dict[str, object]) -> Path:
    """Add (or replace) the ONNX correction of the bundle at ``directory`` as a new release.

    ``spec`` is the manifest's ``correction`` entry without ``file`` (features, input, output,
    optional state; see :mod:`edge.control.neural`). Golden vectors of the correction are
    recorded. Any signature is dropped (the manifest changes): sign the new release again.
    """

    def change(staging: Path, manifest: dict[str, object]) -> None:
        files = manifest["files"]
        assert isinstance(files, dict)
        for name in [n for n, e in files.items() if e.get("role") == "correction"]:
            del files[name]
            (staging / name).unlink(missing_ok=True)
        shutil.copyfile(model_path, staging / CORRECTION_FILE)
        digest = sha256_file(staging / CORRECTION_FILE)
        files[CORRECTION_FILE] = {"role": "correction", "kind": "onnx", "sha256": digest}
        manifest["correction"] = {"file": CORRECTION_FILE, **spec}

    return _derive(directory, change)


def replace_net(directory: str | Path, which: str, model_path: str | Path, quantisation: dict[str, object]) -> Path:
    """Replace the ``which`` (forward/inverse) net's step graph by ``model_path`` (a quantised variant
    of it, same inputs, outputs and state) as a new release; ``quantisation`` goes into its
    ``nets`` entry. Golden vectors are recorded again by the edge's evaluators; any signature is
    dropped (sign the new release again)."""

    def change(staging: Path, manifest: dict[str, object]) -> None:
        nets, files = manifest.get("nets"), manifest["files"]
        assert isinstance(files, dict)
        if not isinstance(nets, dict) or not isinstance(nets.get(which), dict):
            raise BundleError(f"{directory}: holds no {which} net to replace")
        name = str(nets[which]["file"])
        shutil.copyfile(model_path, staging / name)
        files[name] = {**files[name], "sha256": sha256_file(staging / name)}
        nets[which]["quantisation"] = quantisation

    return _derive(directory, change)


def update_manifest(directory: str | Path, **fields: object) -> Path:
    """Set top-level manifest fields (e.g. ``quantisation={...}``) in a new release, atomically.

    The files stay as they are; ``format``, ``format_version``, ``files``, ``model`` and
    ``created_utc`` are written by pmactl alone and refused here. A field set to ``None`` is
    removed. Any signature is dropped (the manifest changes): sign the new release again.
    """
    refused = sorted(set(fields) & set(PROTECTED_FIELDS))
    if refused:
        raise BundleError(f"update_manifest: {', '.join(refused)} are written by pmactl itself; set other fields")
    try:
        json.dumps(fields)
    except (TypeError, ValueError) as exc:
        raise BundleError(f"update_manifest: fields must be JSON values ({exc})") from exc

    def change(staging: Path, manifest: dict[str, object]) -> None:
        for key, value in fields.items():
            if value is None:
                manifest.pop(key, None)
            else:
                manifest[key] = value

    return _derive(directory, change)


def _now() -> str:
    return dt.datetime.now(dt.UTC).isoformat(timespec="microseconds")


def _derive(directory: str | Path, change: Callable[[Path, dict[str, object]], None]) -> Path:
    """A new release from the current one: its files copied, ``change`` applied, golden vectors
    and manifest written again."""
    target = Path(directory)
    if not store.is_store(target):
        raise BundleError(f"{target}: not a bundle directory with releases; write one with pmactl fit --save")
    source = load_bundle(target)  # verified before anything is derived from it

    def build(staging: Path) -> dict[str, object]:
        manifest = json.loads(json.dumps(source.manifest))
        files = manifest["files"]
        for name, entry in list(files.items()):
            if entry.get("role") == "golden":
                del files[name]
            else:
                shutil.copyfile(source.path / name, staging / name)
        change(staging, manifest)
        manifest["created_utc"] = _now()
        manifest["derived_from"] = source.manifest_sha256
        return manifest

    return _new_release(target, build, store.DEFAULT_KEEP)


def _new_release(target: Path, build: Callable[[Path], dict[str, object]], keep: int) -> Path:
    """Run ``build`` into a staging directory, add golden vectors, publish, flip ``current``."""
    if keep < 2:
        raise BundleError(f"keep={keep}: keep at least 2 releases (the current and the one to roll back to)")
    created = [p for p in (target, target / RELEASES) if not p.exists()]
    staging = store.new_staging(target)
    try:
        manifest = build(staging)
        _add_golden(staging, manifest)
        text = json.dumps(manifest, indent=2) + "\n"
        (staging / MANIFEST).write_text(text)
        release_id = hashlib.sha256(text.encode()).hexdigest()[:16]
        store.publish(target, staging, release_id)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        for path in reversed(created):  # only directories this call made, and only when empty
            if not any(path.iterdir()):
                path.rmdir()
        raise
    store.flip(target, release_id)
    store.prune(target, keep)
    return target


def _add_golden(staging: Path, manifest: dict[str, object]) -> None:
    files = manifest["files"]
    assert isinstance(files, dict)
    by_role = {entry["role"]: name for name, entry in files.items()}
    forward = CompiledModel(read_table(staging / by_role["forward"]))
    inverse = CompiledModel(read_table(staging / by_role["inverse"]))
    vectors = table_vectors(forward, inverse)
    if "correction" in by_role:
        spec = manifest["correction"]
        assert isinstance(spec, dict)
        vectors.update(correction_vectors(staging / by_role["correction"], spec, inverse))
    nets = manifest.get("nets")
    if isinstance(nets, dict) and nets:
        inverse.reset()
        vectors.update(net_vectors(staging, nets, inverse))
    manifest["roles"] = roles_of(manifest)
    path = write_golden(staging / GOLDEN_FILE, vectors)
    files[GOLDEN_FILE] = {"role": "golden", "kind": "npz", "sha256": sha256_file(path)}


def roles_of(manifest: Mapping[str, object]) -> dict[str, list[str]]:
    """The roles a release's parts can fill, as the manifest records them (``roles``)."""
    from edge.control.net_roles import feedforward_roles

    nets = manifest.get("nets")
    nets = nets if isinstance(nets, dict) else {}
    return {
        "feedforward": feedforward_roles("inverse" in nets, "correction" in manifest),
        "forward": ["table", *(["net"] if "forward" in nets else [])],
    }


__all__ = [
    "NetPart",
    "roles_of",
    "CURRENT",
    "add_correction",
    "check_save_target",
    "provenance_record",
    "update_manifest",
    "write_bundle",
]
