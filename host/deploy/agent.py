"""The target side of ``pmactl deploy``: ``python -m host.deploy.agent COMMAND --root DIR ...``.

Runs on the rig with the ``edge`` extra only and prints one JSON object on stdout (exit 0 when
``ok``, 1 otherwise). Commands:

* ``prepare``: make ``releases/``, remove stale incoming uploads, make a fresh incoming directory.
* ``install``: fsync the upload, verify it (manifest id, signature, checksums, roles, golden
  vectors), publish it as ``releases/<id>``, health-check it, flip ``current``, check it again
  through ``current`` as the edge loads it (plus an optional command), roll back by itself when
  that fails, prune old releases.
* ``rollback``: check ``previous`` and flip back to it.
* ``releases``: list the releases. ``abort``: remove an incoming upload.

Trusted keys: the target keeps its own, ``DIR/trusted_keys/*.pub`` (``pmactl.pub`` files). When
any are there, install and rollback require a signature by one of them, whatever keys the
deployer passes. When none are there, the deployer's ``--trusted-key`` values are used, and a
successful install with them writes them there (trust on first deploy); a later deploy never
changes that directory: only someone with a shell on the rig does.

Install and rollback hold an exclusive lock on ``DIR/.pmactl-deploy.lock``, so two deploys to
one rig cannot interleave their flips.
"""

from __future__ import annotations

import argparse
import base64
import fcntl
import hashlib
import json
import shutil
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path

from edge.errors import BundleError, PmactlError
from edge.runtime.bundle import CURRENT, MANIFEST, RELEASES, key_id, read_public_key
from host.deploy.health import DEFAULT_TICK_LIMIT_US, health_check, verify_release
from models_export import store

LOCK = store.LOCK
INCOMING_STALE_S = 600.0  # an upload untouched this long was abandoned (its connection died)
POST_FLIP_TIMEOUT_S = 120.0


class StepFailed(Exception):
    """A step failed; ``step`` names it."""

    def __init__(self, step: str, message: str) -> None:
        super().__init__(message)
        self.step = step


class Steps:
    """Runs named steps, recording each one's outcome and duration."""

    def __init__(self) -> None:
        self.done: list[dict[str, object]] = []

    def run(self, name: str, action: Callable[[], object]) -> object:
        start = time.perf_counter()
        try:
            detail = action()
        except (PmactlError, OSError, subprocess.SubprocessError, StepFailed) as exc:
            self.done.append({"step": name, "ok": False, "seconds": time.perf_counter() - start, "error": str(exc)})
            raise StepFailed(name, str(exc)) from exc
        self.done.append({"step": name, "ok": True, "seconds": time.perf_counter() - start, "detail": detail})
        return detail


@contextmanager
def locked(root: Path) -> Iterator[None]:
    with (root / LOCK).open("a") as handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as exc:
            raise StepFailed("lock", f"{root}: another deploy or rollback is running; retry when it ends") from exc
        yield


def _state(root: Path) -> dict[str, str | None]:
    return {"current": store.link_target(root, CURRENT), "previous": store.link_target(root, store.PREVIOUS)}


def _refuse_foreign_target(root: Path) -> None:
    if store.may_hold_store(root):
        return
    if not root.is_dir():
        raise StepFailed("prepare", f"{root}: exists and is not a directory; deploy to a new or empty directory")
    foreign = store.foreign_entries(root) or sorted(p.name for p in root.iterdir())
    shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
    raise StepFailed(
        "prepare",
        f"{root}: is a directory that is not a pmactl deploy target (it holds {shown}); "
        "deploy to a new or empty directory (nothing changed)",
    )


def prepare(root: Path) -> dict[str, object]:
    _refuse_foreign_target(root)
    (root / RELEASES).mkdir(parents=True, exist_ok=True)
    removed = store.remove_stale_staging(root, INCOMING_STALE_S)
    staging = store.new_staging(root, store.INCOMING_PREFIX)
    usage = shutil.disk_usage(root)
    return {"ok": True, "staging": str(staging), "free_bytes": usage.free, "removed_stale": removed, **_state(root)}


def target_keys(root: Path) -> list[tuple[str, bytes]]:
    """The keys the target itself trusts: ``root/trusted_keys/*.pub``, sorted by file name."""
    folder = root / store.TRUSTED_KEYS
    if not folder.is_dir():
        return []
    return [read_public_key(path) for path in sorted(folder.glob("*.pub"))]


def _effective_trust(
    root: Path, given: Sequence[tuple[str, bytes]] | None
) -> tuple[Sequence[tuple[str, bytes]] | None, bool]:
    """``(keys to verify with, True when they are the target's own)``."""
    own = target_keys(root)
    return (own, True) if own else (given, False)


def pin_keys(root: Path, keys: Sequence[tuple[str, bytes]]) -> list[str]:
    """Write ``keys`` as ``root/trusted_keys/<key id>.pub`` (PEM), each atomically; returns the ids."""
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PublicKey

    folder = root / store.TRUSTED_KEYS
    folder.mkdir(mode=0o755, exist_ok=True)
    for kid, raw in keys:
        pem = Ed25519PublicKey.from_public_bytes(raw).public_bytes(
            serialization.Encoding.PEM, serialization.PublicFormat.SubjectPublicKeyInfo
        )
        temporary = folder / f".{kid}.pub.tmp"
        temporary.write_bytes(pem)
        store.fsync_path(temporary)
        temporary.rename(folder / f"{kid}.pub")
    store.fsync_path(folder)
    return [kid for kid, _ in keys]


def _check_upload(
    staging: Path, release_id: str, trusted: Sequence[tuple[str, bytes]] | None, own: bool, root: Path
) -> dict[str, object]:
    actual = hashlib.sha256((staging / MANIFEST).read_bytes()).hexdigest()[:16]
    if actual != release_id:
        raise StepFailed("verify", f"manifest arrived as release {actual}, not {release_id}: corrupted in transit")
    try:
        _, report = verify_release(staging, trusted)
    except BundleError as exc:
        if own:
            raise BundleError(f"{exc} (this target trusts only {root / store.TRUSTED_KEYS}/*.pub)") from exc
        raise
    return report.as_dict()


def _post_flip_command(command: str | None) -> str | None:
    if not command:
        return None
    done = subprocess.run(command, shell=True, capture_output=True, text=True, timeout=POST_FLIP_TIMEOUT_S)
    if done.returncode != 0:
        last = (done.stderr.strip() or done.stdout.strip() or "no output").splitlines()[-1]
        raise StepFailed("post-flip", f"command {command!r} exited {done.returncode}: {last}")
    return f"command {command!r} exited 0"


def install(
    root: Path,
    staging: Path,
    release_id: str,
    trusted: Sequence[tuple[str, bytes]] | None,
    tick_limit_us: float,
    keep: int,
    post_flip: str | None,
) -> dict[str, object]:
    if not _is_incoming(root, staging):
        return {"ok": False, "failed_step": "install", "error": f"{staging}: not an incoming upload of {root}"}
    if not store.is_store(root):
        error = f"{root}: not a pmactl deploy target; run prepare first"
        return {"ok": False, "failed_step": "install", "error": error}
    steps = Steps()
    before = _state(root)
    result: dict[str, object] = {"ok": False, "release": release_id, "rolled_back": False, "steps": steps.done}
    existed = (root / RELEASES / release_id).exists()
    flipped = False
    given = trusted
    try:
        with locked(root):
            try:
                trusted, own = _effective_trust(root, given)
            except BundleError as exc:
                raise StepFailed("verify", str(exc)) from exc
            steps.run("fsync", lambda: store.fsync_tree(staging))
            steps.run("verify", lambda: _check_upload(staging, release_id, trusted, own, root))
            release = steps.run("publish", lambda: str(store.publish(root, staging, release_id)))
            steps.run(
                "health", lambda: health_check(Path(str(release)), trusted, tick_limit_us=tick_limit_us).as_dict()
            )
            steps.run("flip", lambda: store.flip(root, release_id))
            flipped = True
            steps.run("post-flip health", lambda: health_check(root, trusted, tick_limit_us=tick_limit_us).as_dict())
            steps.run("post-flip", lambda: _post_flip_command(post_flip))
            steps.run("prune", lambda: store.prune(root, keep))
            result["ok"] = True
            if not own and given:  # trust on first deploy; never changed by a later one
                result["pinned_keys"] = pin_keys(root, given)
            result["trusted_keys"] = [kid for kid, _ in trusted or ()]
    except StepFailed as exc:
        result.update(failed_step=exc.step, error=str(exc))
        if flipped:
            store.restore(root, before["current"], before["previous"])
            result["rolled_back"] = True
            if post_flip:  # let the old release start again the way the new one was started
                subprocess.run(post_flip, shell=True, capture_output=True, timeout=POST_FLIP_TIMEOUT_S)
        if not existed and before["current"] != release_id:
            shutil.rmtree(root / RELEASES / release_id, ignore_errors=True)  # never half-installed
        shutil.rmtree(staging, ignore_errors=True)
    result.update(_state(root))
    return result


def rollback(root: Path, trusted: Sequence[tuple[str, bytes]] | None, tick_limit_us: float) -> dict[str, object]:
    steps = Steps()
    before = _state(root)
    result: dict[str, object] = {"ok": False, "rolled_back": False, "steps": steps.done}
    try:
        with locked(root):
            try:
                trusted = _effective_trust(root, trusted)[0]
            except BundleError as exc:
                raise StepFailed("rollback", str(exc)) from exc
            if before["previous"] is None:
                raise StepFailed("rollback", f"{root}: no previous release to roll back to")
            target = root / RELEASES / str(before["previous"])
            steps.run("health", lambda: health_check(target, trusted, tick_limit_us=tick_limit_us).as_dict())
            steps.run("flip", lambda: store.flip(root, str(before["previous"])))
            result.update(ok=True, rolled_back=True)
    except StepFailed as exc:
        result.update(failed_step=exc.step, error=str(exc))
    result.update(_state(root))
    return result


def releases(root: Path) -> dict[str, object]:
    return {"ok": True, "releases": [r.as_dict() for r in store.list_releases(root)], **_state(root)}


def _is_incoming(root: Path, staging: Path) -> bool:
    """True when ``staging`` is one of ``prepare``'s upload directories of ``root`` (never
    anything else: install and abort delete or rename it)."""
    return (
        staging.parent == root / RELEASES
        and staging.name.startswith(store.INCOMING_PREFIX)
        and staging.is_dir()
        and not staging.is_symlink()
    )


def abort(root: Path, staging: Path) -> dict[str, object]:
    if not _is_incoming(root, staging):
        return {"ok": False, "error": f"{staging}: not an incoming upload of {root}"}
    shutil.rmtree(staging, ignore_errors=True)
    return {"ok": True}


def _trusted(values: Sequence[str] | None) -> list[tuple[str, bytes]] | None:
    if not values:
        return None
    raws = [base64.b64decode(v) for v in values]
    return [(key_id(raw), raw) for raw in raws]


def parser() -> argparse.ArgumentParser:
    top = argparse.ArgumentParser(prog="python -m host.deploy.agent")
    sub = top.add_subparsers(dest="command", required=True)
    for name in ("prepare", "install", "rollback", "releases", "abort"):
        command = sub.add_parser(name)
        command.add_argument("--root", required=True, type=Path)
        if name in ("install", "abort"):
            command.add_argument("--staging", required=True, type=Path)
        if name in ("install", "rollback"):
            command.add_argument("--trusted-key", action="append", help="raw Ed25519 public key, base64")
            command.add_argument("--tick-limit-us", type=float, default=DEFAULT_TICK_LIMIT_US)
        if name == "install":
            command.add_argument("--id", required=True)
            command.add_argument("--keep", type=int, default=store.DEFAULT_KEEP)
            command.add_argument("--post-flip")
    return top


def main(argv: Sequence[str] | None = None) -> int:
    args = parser().parse_args(argv)
    # a dropped SSH connection must not stop an install between its flip and its checks
    signal.signal(signal.SIGHUP, signal.SIG_IGN)
    root = args.root.expanduser()
    try:
        if args.command == "prepare":
            result = prepare(root)
        elif args.command == "install":
            result = install(
                root,
                args.staging.expanduser(),
                args.id,
                _trusted(args.trusted_key),
                args.tick_limit_us,
                args.keep,
                args.post_flip,
            )
        elif args.command == "rollback":
            result = rollback(root, _trusted(args.trusted_key), args.tick_limit_us)
        elif args.command == "releases":
            result = releases(root)
        else:
            result = abort(root, args.staging.expanduser())
    except (PmactlError, OSError, StepFailed) as exc:
        result = {"ok": False, "failed_step": getattr(exc, "step", args.command), "error": str(exc)}
    except Exception as exc:  # noqa: BLE001 - the host needs an answer it can show, not a traceback
        result = {"ok": False, "failed_step": args.command, "error": f"agent error {type(exc).__name__}: {exc}"}
    try:
        print(json.dumps(result, default=str))
        sys.stdout.flush()
    except BrokenPipeError:
        pass  # the host went away; the outcome is on disk (current, previous) for pmactl releases
    return 0 if result.get("ok") else 1


if __name__ == "__main__":
    sys.exit(main())
