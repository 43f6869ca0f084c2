"""Ed25519 keys and signatures for bundles (``cryptography``).

``pmactl keygen`` writes ``pmactl.key`` (PKCS#8 PEM, mode 0600) and ``pmactl.pub`` (PEM
SubjectPublicKeyInfo). A signature covers the bytes of ``manifest.json``, which holds the
SHA-256 of every other file (golden vectors included), so it covers the whole release. It is
stored beside the manifest in ``signature.json``; the release id (the manifest's hash) does not
change when a release is signed.
"""

from __future__ import annotations

import base64
import json
import os
from pathlib import Path

from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

from edge.errors import BundleError
from edge.runtime.bundle import MANIFEST, SIGNATURE, key_id, read_signature, resolve_release
from models_export.store import fsync_path

PRIVATE_KEY = "pmactl.key"
PUBLIC_KEY = "pmactl.pub"


def keygen(directory: str | Path) -> tuple[Path, Path]:
    """Write a new key pair into ``directory``; never overwrites an existing key."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    private_path, public_path = out / PRIVATE_KEY, out / PUBLIC_KEY
    for path in (private_path, public_path):
        if path.exists() or path.is_symlink():
            raise BundleError(f"{path}: exists; keep it or move it away yourself (keygen never overwrites a key)")
    key = Ed25519PrivateKey.generate()
    private_pem = key.private_bytes(
        serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
    )
    fd = os.open(private_path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "wb") as handle:
        handle.write(private_pem)
    public_path.write_bytes(
        key.public_key().public_bytes(serialization.Encoding.PEM, serialization.PublicFormat.SubjectPublicKeyInfo)
    )
    return private_path, public_path


def read_private_key(path: Path) -> Ed25519PrivateKey:
    """The key in a ``pmactl.key`` file; one error if it is not one."""
    try:
        key = serialization.load_pem_private_key(path.read_bytes(), password=None)
    except (OSError, ValueError, TypeError) as exc:
        raise BundleError(f"{path}: not a readable private key ({exc}); make one with pmactl keygen --out DIR") from exc
    if not isinstance(key, Ed25519PrivateKey):
        raise BundleError(f"{path}: not an Ed25519 private key; make one with pmactl keygen --out DIR")
    if path.stat().st_mode & 0o077:
        raise BundleError(f"{path}: readable by others (mode {path.stat().st_mode & 0o777:o}); chmod 600 {path}")
    return key


def sign_release(directory: str | Path, key_path: str | Path) -> tuple[Path, str]:
    """Sign the release at ``directory`` (or its ``current``); returns (release, key id)."""
    release = resolve_release(directory)
    key = read_private_key(Path(key_path))
    manifest = (release / MANIFEST).read_bytes()
    raw = key.public_key().public_bytes(serialization.Encoding.Raw, serialization.PublicFormat.Raw)
    record = {
        "algorithm": "ed25519",
        "key_id": key_id(raw),
        "public_key": base64.b64encode(raw).decode(),
        "signature": base64.b64encode(key.sign(manifest)).decode(),
        "signed_file": MANIFEST,
    }
    temporary = release / f".{SIGNATURE}.tmp"
    with temporary.open("w") as handle:
        handle.write(json.dumps(record, indent=2) + "\n")
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(temporary, release / SIGNATURE)
    fsync_path(release)
    return release, key_id(raw)


def signer_of(directory: str | Path) -> str | None:
    """Key id named by the signature of the release at ``directory`` (or its ``current``),
    ``None`` when it is unsigned. The signature is not verified here (loading does that)."""
    record = read_signature(resolve_release(directory))
    if record is None:
        return None
    try:
        return key_id(base64.b64decode(record["public_key"], validate=True))
    except ValueError as exc:
        raise BundleError(
            f"{resolve_release(directory) / SIGNATURE}: unreadable public key ({exc}); "
            "sign again with pmactl bundle sign"
        ) from exc


def sign_command(directory: str | Path) -> str:
    """The command that signs the current release of ``directory`` (``pmactl bundle sign``)."""
    import shlex

    return f"pmactl bundle sign {shlex.quote(str(directory))} --key {PRIVATE_KEY}"


def after_new_release(
    directory: str | Path, key_path: str | Path | None, signed_before: str | None
) -> tuple[str, bool]:
    """Sign the release a command just wrote at ``directory``, or say that it is unsigned.

    With ``key_path`` the new current release is signed (:func:`sign_release`). Without it,
    a store whose previous release was signed (``signed_before``: its key id) now runs an
    unsigned release, which a rig that trusts keys refuses: the returned line says so and
    gives the command. Returns (one line for the user, True when it is a warning); the line
    is empty when the store was never signed and no key was given.
    """
    if key_path is not None:
        release, signer = sign_release(directory, key_path)
        was = f" (the previous release was signed by {signed_before})" if signed_before not in (None, signer) else ""
        return f"signed the new release {release.name} with key {signer}{was}", False
    if signed_before is None:
        return "", False
    release = resolve_release(directory)
    return (
        f"the new release {release.name} is UNSIGNED (the one before was signed by key {signed_before}); "
        f"sign it: {sign_command(directory)} (or pass --key next time)",
        True,
    )
