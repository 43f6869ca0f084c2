"""Load and verify a model bundle (see ``models_export.bundle`` for the layout); numpy + cryptography.

A *release* is one directory holding ``manifest.json`` and the files it names. A *bundle
directory* (what ``pmactl fit --save`` writes and ``pmactl deploy`` fills on the rig) keeps
releases under ``releases/<id>/`` and points ``current`` at one of them; :func:`load_bundle`
accepts either and resolves ``current`` once, so a re-save that flips it mid-load is never seen
half-way. Loading checks, in order: the signature (when trusted keys are given), that every file
named is a plain file inside the release, every checksum, the roles of the two tables against
the ranges the manifest records, and the golden vectors recorded at export.
"""

from __future__ import annotations

import base64
import hashlib
import json
import math
import os
import stat
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from edge import __version__
from edge.errors import BundleError
from edge.hysteresis.lut import CompiledModel, LookupTable, read_table

if TYPE_CHECKING:
    from edge.control.net_narmax import NetForward, NetInverse
    from edge.control.net_state_space import StateSpaceForward

FORMAT = "pmactl-bundle"
FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)  # v1: the flat layout without golden vectors, still loadable
MANIFEST = "manifest.json"
LOAD_ATTEMPTS = 20  # a release pruned while it is read: follow `current` again, under 1 s of back-off in all
SIGNATURE = "signature.json"
CURRENT = "current"
RELEASES = "releases"
ROLES = ("forward", "inverse", "correction", "golden", "forward_net", "inverse_net", "operator")
NET_ROLES = {"forward": "forward_net", "inverse": "inverse_net"}  # manifest "nets" key -> file role
NET_GOLDEN_RTOL = 1e-4  # float32 nets: the fused and onnxruntime evaluators round differently
RANGE_TOLERANCE = 1e-6  # share of a range's span; the tables are compiled from one model
GOLDEN_RTOL = 1e-9  # tables are float64 and deterministic: a replay reproduces to rounding


@dataclass
class Bundle:
    """A verified bundle: the manifest and the evaluators of its tables.

    ``path`` is the release directory actually loaded (``current`` resolved), ``release_id``
    the first 16 hex digits of the manifest's SHA-256, ``signer`` the key id that signed it
    (``None`` when unsigned or when no trusted keys were asked for).
    """

    path: Path
    manifest: dict[str, object]
    forward: CompiledModel
    inverse: CompiledModel
    correction_path: Path | None = None
    manifest_sha256: str = ""
    signer: str | None = None
    net_paths: dict[str, Path] = field(default_factory=dict)  # "forward" / "inverse" -> the ONNX step graph
    net_golden_samples: int = 0  # net golden inputs replayed on load

    @property
    def release_id(self) -> str:
        return self.manifest_sha256[:16]

    @property
    def units(self) -> tuple[str, str]:
        """(input unit, output unit) as the fit recorded them."""
        model = self.manifest.get("model")
        units = model.get("units") if isinstance(model, dict) else None
        if not isinstance(units, dict):
            return "?", "?"
        return str(units.get("input", "?")), str(units.get("output", "?"))

    @property
    def identity(self) -> dict[str, object]:
        """What a log or telemetry header needs to tell which model ran."""
        model = self.manifest.get("model")
        return {
            "bundle_id": self.manifest_sha256,
            "release": str(self.path),
            "kind": model.get("kind") if isinstance(model, dict) else None,
            "units": list(self.units),
            "created_utc": self.manifest.get("created_utc"),
            "signer": self.signer,
        }

    @property
    def correction_spec(self) -> dict[str, object] | None:
        spec = self.manifest.get("correction")
        return dict(spec) if isinstance(spec, dict) else None

    def net_spec(self, which: str) -> dict[str, object]:
        """The manifest's description of the ``forward`` or ``inverse`` net (empty when absent)."""
        nets = self.manifest.get("nets")
        spec = nets.get(which) if isinstance(nets, dict) else None
        return dict(spec) if isinstance(spec, dict) else {}

    @property
    def feedforward_roles(self) -> list[str]:
        """The feedforward roles this bundle can fill (``edge.control.net_roles``)."""
        from edge.control.net_roles import feedforward_roles

        return feedforward_roles("inverse" in self.net_paths, self.correction_path is not None)

    def feedforward(self, role: str, period_s: float) -> CompiledModel | NetInverse:
        """The feedforward inverse of ``role`` (``table`` or ``net``, a correction is separate) at
        loop period ``period_s`` [s]; a fresh net evaluator each call, the table is shared."""
        if not role.startswith("net"):
            return self.inverse
        from edge.control.net_roles import net_inverse

        if "inverse" not in self.net_paths:
            raise BundleError(
                f"{self.path}: holds no inverse net; train one with pmactl train --model lstm-narmax --save"
            )
        return net_inverse(self.net_paths["inverse"], self.net_spec("inverse"), self.inverse, period_s)

    def forward_net(self, period_s: float) -> NetForward | StateSpaceForward:
        """The forward net (pressure [bar] -> contraction [mm]) at loop period ``period_s`` [s]."""
        from edge.control.net_roles import net_forward

        if "forward" not in self.net_paths:
            raise BundleError(
                f"{self.path}: holds no forward net; train one with pmactl train --model lstm-narmax --save"
            )
        return net_forward(self.net_paths["forward"], self.net_spec("forward"), self.path, period_s)

    def require_units(self, input_unit: str, output_unit: str) -> None:
        """Refuse a bundle fitted in other units than the runtime's (a silent 10x error otherwise)."""
        if self.units != (input_unit, output_unit):
            raise BundleError(
                f"{self.path}: model maps {self.units[0]} -> {self.units[1]}, the edge needs {input_unit} -> "
                f"{output_unit}; re-fit with pmactl fit --units {input_unit},{output_unit} --save"
            )


def sha256_file(path: Path) -> str:
    """Hex SHA-256 of a file."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 16), b""):
            digest.update(block)
    return digest.hexdigest()


def resolve_release(directory: str | Path) -> Path:
    """The release directory behind ``directory``: itself when it holds a manifest, else the
    target of its ``current`` link, resolved once."""
    root = Path(directory)
    if (root / MANIFEST).exists() or (root / MANIFEST).is_symlink():
        return root
    link = root / CURRENT
    if link.is_symlink() or link.exists():
        try:
            return link.resolve(strict=True)
        except OSError as exc:
            raise BundleError(f"{link}: points at a release that is missing ({exc}); run pmactl rollback") from exc
    if not root.exists():
        raise BundleError(f"{root}: no such bundle directory; write one with pmactl fit --save")
    raise BundleError(
        f"{root}: no {MANIFEST} and no {CURRENT} release; point at a directory written by pmactl fit --save"
    )


def load_bundle(directory: str | Path, *, trusted_keys: Sequence[str | Path] | None = None) -> Bundle:
    """Read and verify the bundle at ``directory`` (a release, or a directory with ``current``).

    With ``trusted_keys`` (paths of ``pmactl.pub`` files), an unsigned bundle, one signed by
    another key, or one changed after signing is refused with one :class:`BundleError` line.
    """
    keys = None if trusted_keys is None else [read_public_key(Path(p)) for p in trusted_keys]
    return load_release(directory, keys)


def load_release(directory: str | Path, trusted: Sequence[tuple[str, bytes]] | None = None) -> Bundle:
    """:func:`load_bundle` with the trusted keys given as ``(key id, raw Ed25519 key)`` pairs."""
    if trusted is not None and not trusted:
        raise BundleError("trusted keys: the list is empty; name at least one pmactl.pub or leave it unset")
    via_current = not (Path(directory) / MANIFEST).exists()
    for attempt in range(LOAD_ATTEMPTS):
        release = resolve_release(directory)
        try:
            return _load(release, trusted)
        except BundleError:
            # A re-save prunes releases that are neither current nor previous, so a reader slowed
            # by a busy machine can lose the release it resolved, file by file (rmtree) or whole.
            # Any error on a release `current` no longer names is that race, not a broken bundle.
            if not via_current or not _superseded(directory, release):
                raise
            if attempt == LOAD_ATTEMPTS - 1:
                raise BundleError(
                    f"{directory}: rewritten {LOAD_ATTEMPTS} times while loading; stop the re-saves, then retry"
                ) from None
        time.sleep(min(0.05, 0.001 * 2**attempt))
    raise AssertionError("unreachable")


def _superseded(directory: str | Path, release: Path) -> bool:
    """True when ``directory``'s ``current`` no longer names ``release`` (or names nothing)."""
    try:
        return resolve_release(directory) != release
    except BundleError:
        return True


def _load(release: Path, trusted: Sequence[tuple[str, bytes]] | None) -> Bundle:
    manifest_path = release / MANIFEST
    raw = _read_plain(release, MANIFEST)
    manifest_sha256 = hashlib.sha256(raw).hexdigest()
    signer = verify_signature(release, raw, trusted) if trusted is not None else None
    manifest = _parse_manifest(manifest_path, raw)
    files = manifest["files"]
    assert isinstance(files, dict)
    tables: dict[str, LookupTable] = {}
    paths: dict[str, Path] = {}
    for name, entry in files.items():
        path = _confined(release, name, manifest_path)
        if not isinstance(entry, dict) or entry.get("role") not in ROLES:
            raise BundleError(f"{manifest_path}: entry {name!r} needs a role among {ROLES}; re-export the bundle")
        role = entry["role"]
        if role in paths:
            raise BundleError(f"{manifest_path}: two files have the role {role}; re-export the bundle")
        if _sha256_plain(release, name) != entry.get("sha256"):
            raise BundleError(f"{path}: checksum mismatch (corrupt or edited); re-copy the bundle")
        paths[role] = path
        if role in ("forward", "inverse"):
            tables[role] = read_table(path)
    missing = {"forward", "inverse"} - set(tables)
    if missing:
        raise BundleError(f"{manifest_path}: no {' or '.join(sorted(missing))} table listed; re-export the bundle")
    correction_path = paths.get("correction")
    if ("correction" in manifest) != (correction_path is not None):
        raise BundleError(f"{manifest_path}: correction entry and correction file do not go together; re-export")
    forward, inverse = CompiledModel(tables["forward"]), CompiledModel(tables["inverse"])
    check_roles(manifest_path, manifest, forward, inverse)
    net_paths = _net_paths(manifest_path, manifest, paths)
    if "golden" in paths:
        replay_table_golden(paths["golden"], forward, inverse)
    elif manifest["format_version"] != 1:
        raise BundleError(f"{manifest_path}: no golden vectors listed; re-export the bundle with pmactl fit --save")
    bundle = Bundle(release, manifest, forward, inverse, correction_path, manifest_sha256, signer, net_paths)
    if net_paths:
        if "golden" not in paths:
            raise BundleError(f"{manifest_path}: nets without golden vectors; re-export the bundle")
        bundle.net_golden_samples = replay_net_golden(paths["golden"], bundle)
    return bundle


def _net_paths(manifest_path: Path, manifest: dict[str, object], paths: dict[str, Path]) -> dict[str, Path]:
    """The nets' files by manifest key; a ``nets`` entry and its files must go together."""
    nets = manifest.get("nets", {})
    if not isinstance(nets, dict) or set(nets) - set(NET_ROLES):
        raise BundleError(f"{manifest_path}: 'nets' must map forward/inverse to net entries; re-export the bundle")
    found = {}
    for which, role in NET_ROLES.items():
        entry = nets.get(which)
        if (entry is not None) != (role in paths):
            raise BundleError(f"{manifest_path}: the {which} net entry and its file do not go together; re-export")
        if entry is not None:
            if not isinstance(entry, dict) or entry.get("file") != paths[role].name:
                raise BundleError(f"{manifest_path}: the {which} net entry names another file; re-export the bundle")
            found[which] = paths[role]
    needs_operator = "forward" in found and nets["forward"].get("model") != "state-space"  # its state holds the memory
    if needs_operator != ("operator" in paths):
        raise BundleError(f"{manifest_path}: a forward net needs its operator table and back; re-export the bundle")
    return found


def replay_net_golden(path: Path, bundle: Bundle) -> int:
    """Replay the nets' recorded inputs through fresh edge evaluators (one net step per input);
    returns the inputs replayed."""
    try:
        with np.load(path, allow_pickle=False) as data:
            vectors = {k: np.asarray(data[k], dtype=float) for k in data.files}
    except (OSError, ValueError) as exc:
        raise BundleError(f"{path}: golden vectors unreadable ({exc}); re-export the bundle") from exc
    replayed = 0
    for which in bundle.net_paths:
        try:
            u, expected = vectors[f"{which}_net_input"], vectors[f"{which}_net_output"]
        except KeyError as exc:
            raise BundleError(f"{path}: no golden vectors for the {which} net; re-export the bundle") from exc
        step_s = float(bundle.net_spec(which).get("step_s", 0.0))  # type: ignore[arg-type]
        model = bundle.feedforward("net", step_s) if which == "inverse" else bundle.forward_net(step_s)
        model.reset()
        got = model.simulate(u)
        model.reset()
        mismatch = golden_mismatch(got, expected, NET_GOLDEN_RTOL)
        if mismatch:
            raise BundleError(
                f"{path.parent}: the {which} net does not reproduce its golden vectors ({mismatch}): "
                "it was changed after export; re-export the bundle"
            )
        replayed += int(u.size)
    return replayed


def _read_plain(release: Path, name: str) -> bytes:
    try:
        if not stat.S_ISREG(os.lstat(release / name).st_mode):
            raise BundleError(f"{release / name}: not a plain file (a link or a device); re-export the bundle")
        return (release / name).read_bytes()
    except FileNotFoundError as exc:
        raise BundleError(f"{release}: no {name}; point at a directory written by pmactl fit --save") from exc
    except OSError as exc:
        raise BundleError(f"{release / name}: unreadable ({exc}); check the permissions or re-copy") from exc


def _sha256_plain(release: Path, name: str) -> str:
    try:
        return sha256_file(release / name)
    except OSError as exc:
        raise BundleError(f"{release / name}: unreadable ({exc}); re-copy the bundle") from exc


def _parse_manifest(manifest_path: Path, raw: bytes) -> dict[str, object]:
    try:
        manifest = json.loads(raw)
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BundleError(f"{manifest_path}: unreadable manifest ({exc}); re-export the bundle") from exc
    if not isinstance(manifest, dict):
        raise BundleError(
            f"{manifest_path}: the manifest is a JSON {type(manifest).__name__}, not an object; re-export the bundle"
        )
    if manifest.get("format") != FORMAT:
        raise BundleError(
            f"{manifest_path}: format {manifest.get('format')!r} is not {FORMAT}; "
            "point at a directory written by pmactl fit --save"
        )
    check_format_version(manifest_path, manifest.get("format_version"))
    if not isinstance(manifest.get("files"), dict):
        found = type(manifest.get("files")).__name__
        raise BundleError(f"{manifest_path}: 'files' must map file names to entries, found a {found}; re-export")
    return manifest


def check_format_version(manifest_path: Path, version: object) -> None:
    """Refuse a ``format_version`` this pmactl does not read, naming it and the fix.

    A bool is refused too (JSON ``true`` would otherwise pass as version 1).
    """
    if type(version) is int and version in READABLE_VERSIONS:
        return
    readable = ", ".join(str(v) for v in READABLE_VERSIONS)
    if type(version) is int and version > FORMAT_VERSION:
        fix = f"a newer pmactl wrote it: upgrade pmactl here (pip install -U pmactl; this is {__version__})"
    else:
        fix = "re-export it with pmactl fit --save"
    raise BundleError(
        f"{manifest_path}: manifest format_version {version!r} is not one this pmactl reads ({readable}); {fix}"
    )


def _confined(release: Path, name: object, manifest_path: Path) -> Path:
    """``release / name`` if ``name`` is a plain file directly inside the release, else one error."""
    if (
        not isinstance(name, str)
        or name in ("", ".", "..", MANIFEST, SIGNATURE)
        or "/" in name
        or "\\" in name
        or "\0" in name
    ):
        raise BundleError(
            f"{manifest_path}: file name {name!r} is not a plain name inside the bundle; only files in the "
            "bundle directory itself may be named, re-export the bundle"
        )
    path = release / name
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError as exc:
        raise BundleError(f"{release}: file {name} listed in the manifest is missing; re-copy the bundle") from exc
    if not stat.S_ISREG(mode):
        kind = "a symbolic link" if stat.S_ISLNK(mode) else "not a plain file"
        raise BundleError(f"{path}: is {kind}; a bundle holds plain files only, re-copy it without links")
    return path


def _finite(value: object, sign: float) -> float:
    return sign * math.inf if value is None else float(value)  # type: ignore[arg-type]


def _close(a: float, b: float, span: float) -> bool:
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= RANGE_TOLERANCE * max(span, 1e-12)


def check_roles(
    manifest_path: Path, manifest: dict[str, object], forward: CompiledModel, inverse: CompiledModel
) -> None:
    """The forward table's input range is the model's input range, the inverse's input range is
    the forward's reachable output range; swapped roles fail both."""
    model = manifest.get("model")
    if not isinstance(model, dict):
        raise BundleError(f"{manifest_path}: no 'model' object (kind, units, ranges); re-export the bundle")
    try:
        recorded_in = tuple(_finite(v, s) for v, s in zip(model["input_range"], (-1, 1)))
        recorded_out = tuple(_finite(v, s) for v, s in zip(model["reachable_output_range"], (-1, 1)))
    except (KeyError, TypeError, ValueError) as exc:
        raise BundleError(f"{manifest_path}: model ranges unreadable ({exc}); re-export the bundle") from exc
    checks = (("forward", forward, recorded_in, "input range"), ("inverse", inverse, recorded_out, "output range"))
    for role, table, recorded, what in checks:
        lo, hi = table.input_range
        span = (hi - lo) if math.isfinite(hi - lo) else 1.0
        if len(recorded) != 2 or not all(_close(a, b, span) for a, b in zip(table.input_range, recorded)):
            raise BundleError(
                f"{manifest_path}: the {role} table takes [{lo:.6g}, {hi:.6g}], not the model's {what} "
                f"{list(recorded)}: roles swapped or tables mixed up; re-export the bundle"
            )
    reach = reachable_output_range(forward, inverse)
    lo, hi = inverse.input_range
    if not (_close(reach[0], lo, hi - lo) and _close(reach[1], hi, hi - lo)):
        raise BundleError(
            f"{manifest_path}: the forward table reaches [{reach[0]:.6g}, {reach[1]:.6g}] but the inverse takes "
            f"[{lo:.6g}, {hi:.6g}]: the tables are not each other's inverse; re-export the bundle"
        )


def reachable_output_range(forward: CompiledModel, inverse: CompiledModel, points: int = 65) -> tuple[float, float]:
    """Output extremes of ``forward`` over a full input cycle (lo -> hi -> lo), state restored.

    An unbounded forward input is swept over the inputs the inverse produces at its range ends.
    """
    lo, hi = forward.input_range
    if not (math.isfinite(lo) and math.isfinite(hi)):
        ends = inverse.simulate(np.array(inverse.input_range))
        inverse.reset()
        lo, hi = float(min(ends)), float(max(ends))
    sweep = np.concatenate([np.linspace(lo, hi, points), np.linspace(hi, lo, points)])
    out = forward.simulate(sweep)
    forward.reset()
    return float(out.min()), float(out.max())


def replay_table_golden(path: Path, forward: CompiledModel, inverse: CompiledModel) -> None:
    """Replay the recorded inputs through fresh tables; refuse any output that differs."""
    try:
        with np.load(path, allow_pickle=False) as data:
            vectors = {k: np.asarray(data[k], dtype=float) for k in data.files}
    except (OSError, ValueError) as exc:
        raise BundleError(f"{path}: golden vectors unreadable ({exc}); re-export the bundle") from exc
    for role, table in (("forward", forward), ("inverse", inverse)):
        try:
            u, expected = vectors[f"{role}_input"], vectors[f"{role}_output"]
        except KeyError as exc:
            raise BundleError(f"{path}: no golden vectors for the {role} table; re-export the bundle") from exc
        got = table.simulate(u)
        table.reset()
        mismatch = golden_mismatch(got, expected, GOLDEN_RTOL)
        if mismatch:
            raise BundleError(
                f"{path.parent}: the {role} table does not reproduce its golden vectors ({mismatch}): "
                "it was changed after export; re-export the bundle"
            )


def golden_mismatch(got: np.ndarray, expected: np.ndarray, rtol: float) -> str:
    """Empty when ``got`` reproduces ``expected`` within ``rtol`` of its scale, else what differs."""
    if got.shape != expected.shape:
        return f"{got.shape} outputs for {expected.shape} recorded"
    scale = max(1.0, float(np.max(np.abs(expected))) if expected.size else 1.0)
    error = np.abs(got - expected)
    if np.all(np.isfinite(got)) and float(error.max(initial=0.0)) <= rtol * scale:
        return ""
    worst = int(np.nanargmax(np.where(np.isfinite(error), error, np.inf)))
    return f"sample {worst}: {got[worst]:.9g} instead of {expected[worst]:.9g}"


# -- signatures (Ed25519 over the manifest bytes; the manifest holds every file's SHA-256) ------


def key_id(raw_public_key: bytes) -> str:
    """Short name of a public key: the first 16 hex digits of its SHA-256."""
    return hashlib.sha256(raw_public_key).hexdigest()[:16]


def read_public_key(path: Path) -> tuple[str, bytes]:
    """``(key id, raw 32-byte key)`` from a ``pmactl.pub`` (PEM SubjectPublicKeyInfo) file."""
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

    try:
        key = serialization.load_pem_public_key(path.read_bytes())
    except (OSError, ValueError) as exc:
        raise BundleError(f"{path}: not a readable public key ({exc}); use the pmactl.pub from pmactl keygen") from exc
    if not isinstance(key, Ed25519PublicKey):
        raise BundleError(f"{path}: not an Ed25519 public key; use the pmactl.pub from pmactl keygen")
    raw = key.public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    return key_id(raw), raw


def read_signature(release: Path) -> dict[str, str] | None:
    """The release's signature record, ``None`` when unsigned; one error when unreadable."""
    path = release / SIGNATURE
    if not (path.exists() or path.is_symlink()):
        return None
    try:
        record = json.loads(_read_plain(release, SIGNATURE))
        if not isinstance(record, dict) or record.get("algorithm") != "ed25519":
            raise ValueError("not an ed25519 signature record")
        return {k: str(record[k]) for k in ("algorithm", "key_id", "public_key", "signature")}
    except (KeyError, ValueError) as exc:
        raise BundleError(f"{path}: unreadable signature ({exc}); sign again with pmactl bundle sign") from exc


def verify_signature(release: Path, manifest_bytes: bytes, trusted: Sequence[tuple[str, bytes]] | None) -> str:
    """Key id of the valid signature over ``manifest_bytes``; with ``trusted``, only those keys count."""
    from cryptography.exceptions import InvalidSignature
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

    record = read_signature(release)
    names = ", ".join(k for k, _ in trusted or ())
    if record is None:
        raise BundleError(
            f"{release}: unsigned, but only bundles signed by {names} are trusted; "
            "sign it with pmactl bundle sign DIR --key pmactl.key"
        )
    raw = base64.b64decode(record["public_key"])
    if trusted is not None and raw not in {k for _, k in trusted}:
        raise BundleError(
            f"{release}: signed by key {key_id(raw)}, which is not trusted ({names}); "
            "sign it with a trusted key or add its pmactl.pub to the trusted keys"
        )
    try:
        Ed25519PublicKey.from_public_bytes(raw).verify(base64.b64decode(record["signature"]), manifest_bytes)
    except (InvalidSignature, ValueError) as exc:
        raise BundleError(
            f"{release}: the signature does not match the manifest: changed after signing; re-export or sign it again"
        ) from exc
    return key_id(raw)
