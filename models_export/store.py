"""A directory of releases with an atomic ``current`` link (standard library only).

Layout (the same for ``pmactl fit --save DIR`` and a deploy target)::

    DIR/releases/<id>/   one complete release each (manifest.json, tables, golden vectors, ...)
    DIR/current          symlink -> releases/<id>: what loads and runs
    DIR/previous         symlink -> the release ``current`` pointed at before the last flip

A release is written under ``releases/.staging-*``, fsynced, renamed to ``releases/<id>`` and
only then made current by renaming a fresh symlink over ``current`` (``rename(2)`` is atomic),
with the directory fsynced after each rename. A reader either sees the old release or the new
one, never a half-written one, and the previous release stays one flip away. This module runs
on the rig too (``host.deploy.agent``), so it needs nothing beyond the standard library.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from edge.errors import BundleError
from edge.runtime.bundle import CURRENT, FORMAT, MANIFEST, RELEASES, SIGNATURE

PREVIOUS = "previous"
STAGING_PREFIX = ".staging-"
INCOMING_PREFIX = ".incoming-"
STALE_SECONDS = 3600.0  # a staging directory older than this is a crashed write, safe to remove
DEFAULT_KEEP = 5
TRUSTED_KEYS = "trusted_keys"  # the target's own trusted pmactl.pub files (see host.deploy.agent)
LOCK = ".pmactl-deploy.lock"
RELEASE_ID = re.compile(r"[0-9a-f]{16}")
# what pmactl itself puts next to releases/ (temporary links are ".current.<pid>.<ns>")
OWN_ENTRIES = (RELEASES, CURRENT, PREVIOUS, TRUSTED_KEYS, LOCK)


def fsync_path(path: Path) -> None:
    """fsync a file or a directory (a directory's fsync makes renames inside it durable)."""
    fd = os.open(path, os.O_RDONLY | (os.O_DIRECTORY if path.is_dir() else 0))
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def fsync_tree(directory: Path) -> None:
    """fsync every plain file directly in ``directory``, then the directory itself."""
    for entry in directory.iterdir():
        if entry.is_file() and not entry.is_symlink():
            fsync_path(entry)
    fsync_path(directory)


def is_release_id(name: str) -> bool:
    """True for a release directory name: 16 lowercase hex digits."""
    return RELEASE_ID.fullmatch(name) is not None


def is_release(entry: Path) -> bool:
    """True when ``entry`` is a pmactl release: a release-id name and a manifest with our format."""
    if not is_release_id(entry.name) or entry.is_symlink() or not entry.is_dir():
        return False
    try:
        manifest = json.loads((entry / MANIFEST).read_text())
    except (OSError, ValueError):
        return False
    return isinstance(manifest, dict) and manifest.get("format") == FORMAT


def _is_own_link(directory: Path, name: str) -> bool:
    """True when ``directory/name`` is a symlink of the form ``releases/<id>``."""
    try:
        target = os.readlink(directory / name)
    except OSError:
        return False
    parts = Path(target).parts
    return len(parts) == 2 and parts[0] == RELEASES and is_release_id(parts[1])


def foreign_entries(directory: Path) -> list[str]:
    """Names in ``directory`` (and in its ``releases/``) that pmactl did not write, sorted."""
    foreign = []
    for entry in directory.iterdir():
        own_temp = entry.name.startswith((f".{CURRENT}.", f".{PREVIOUS}.")) and entry.is_symlink()
        if entry.name not in OWN_ENTRIES and not own_temp:
            foreign.append(entry.name)
    for name in (CURRENT, PREVIOUS):
        if ((directory / name).exists() or (directory / name).is_symlink()) and not _is_own_link(directory, name):
            foreign.append(name)
    releases = directory / RELEASES
    if releases.is_symlink() or (releases.exists() and not releases.is_dir()):
        foreign.append(RELEASES)
    elif releases.is_dir():
        for entry in releases.iterdir():
            ours = entry.name.startswith((STAGING_PREFIX, INCOMING_PREFIX)) or is_release(entry)
            if not ours:
                foreign.append(f"{RELEASES}/{entry.name}")
    return sorted(foreign)


def is_store(directory: Path) -> bool:
    """True when ``directory`` is a pmactl bundle store: ``current`` is a symlink into its real
    ``releases/``, or ``releases/`` is there and nothing in the directory is foreign (a first
    write that has not flipped yet). A user's folder that merely has a ``releases/`` is not one."""
    releases = directory / RELEASES
    if not releases.is_dir() or releases.is_symlink():
        return False
    return _is_own_link(directory, CURRENT) or not foreign_entries(directory)


def may_hold_store(directory: Path) -> bool:
    """True when a store may be made or updated at ``directory``: absent, a store, or holding
    nothing foreign (empty, or only ``trusted_keys/`` put there before the first deploy)."""
    if not directory.exists() and not directory.is_symlink():
        return True
    if not directory.is_dir():
        return False
    return is_store(directory) or not foreign_entries(directory)


def link_target(directory: Path, name: str) -> str | None:
    """Release id a link (``current`` / ``previous``) points at, ``None`` when absent."""
    try:
        return Path(os.readlink(directory / name)).name
    except (FileNotFoundError, OSError):
        return None


def new_staging(directory: Path, prefix: str = STAGING_PREFIX) -> Path:
    """A fresh directory under ``releases/`` to write a release into; stale ones are removed."""
    releases = directory / RELEASES
    releases.mkdir(parents=True, exist_ok=True)
    remove_stale_staging(directory)
    for attempt in range(100):
        staging = releases / f"{prefix}{os.getpid()}-{time.monotonic_ns()}-{attempt}"
        try:
            staging.mkdir()
            return staging
        except FileExistsError:
            continue
    raise BundleError(f"{releases}: cannot create a staging directory; check the directory")


def remove_stale_staging(directory: Path, older_than_s: float = STALE_SECONDS) -> list[str]:
    """Remove staging / incoming directories of crashed writes (only ours: by prefix, by age)."""
    removed: list[str] = []
    releases = directory / RELEASES
    if not releases.is_dir():
        return removed
    now = time.time()
    for entry in releases.iterdir():
        if entry.name.startswith((STAGING_PREFIX, INCOMING_PREFIX)) and not entry.is_symlink():
            if now - entry.stat().st_mtime > older_than_s:
                shutil.rmtree(entry, ignore_errors=True)
                removed.append(entry.name)
    return removed


def publish(directory: Path, staging: Path, release_id: str) -> Path:
    """fsync ``staging`` and rename it to ``releases/<release_id>`` (kept if already there)."""
    fsync_tree(staging)
    final = directory / RELEASES / release_id
    if final.exists():
        shutil.rmtree(staging)  # same manifest bytes, same release: keep the one in place
        return final
    os.rename(staging, final)
    fsync_path(final.parent)
    return final


def _refuse_foreign_link(directory: Path, name: str) -> None:
    path = directory / name
    if (path.exists() or path.is_symlink()) and not path.is_symlink():
        raise BundleError(
            f"{path}: is not a pmactl link (a file or directory is there); move it away and retry (nothing changed)"
        )


def _replace_link(directory: Path, name: str, release_id: str) -> None:
    _refuse_foreign_link(directory, name)
    temporary = directory / f".{name}.{os.getpid()}.{time.monotonic_ns()}"
    os.symlink(f"{RELEASES}/{release_id}", temporary)
    os.replace(temporary, directory / name)


def flip(directory: Path, release_id: str) -> str | None:
    """Make ``release_id`` current; ``previous`` gets the old current. Returns the old current."""
    if not (directory / RELEASES / release_id / MANIFEST).is_file():
        raise BundleError(f"{directory}: release {release_id} is not complete; nothing was changed")
    _refuse_foreign_link(directory, CURRENT)
    _refuse_foreign_link(directory, PREVIOUS)
    old = link_target(directory, CURRENT)
    if old is not None and old != release_id:
        _replace_link(directory, PREVIOUS, old)
    _replace_link(directory, CURRENT, release_id)
    fsync_path(directory)
    return old


def restore(directory: Path, current: str | None, previous: str | None) -> None:
    """Put ``current`` and ``previous`` back as they were (after a failed post-flip check)."""
    for name, release_id in ((CURRENT, current), (PREVIOUS, previous)):
        if release_id is None:
            _refuse_foreign_link(directory, name)
            (directory / name).unlink(missing_ok=True)
        else:
            _replace_link(directory, name, release_id)
    fsync_path(directory)


@dataclass
class Release:
    """One release in a store, as ``pmactl releases`` lists it."""

    id: str
    created_utc: str
    kind: str
    signer: str | None
    current: bool
    previous: bool

    def as_dict(self) -> dict[str, object]:
        return dict(self.__dict__)


def list_releases(directory: Path) -> list[Release]:
    """Complete releases, oldest first (by the manifest's creation time)."""
    releases = directory / RELEASES
    if not releases.is_dir():
        return []
    current, previous = link_target(directory, CURRENT), link_target(directory, PREVIOUS)
    found = []
    for entry in releases.iterdir():
        if not is_release(entry):  # only pmactl's own releases are listed (and so ever pruned)
            continue
        try:
            manifest = json.loads((entry / MANIFEST).read_text())
            signature = json.loads((entry / SIGNATURE).read_text()) if (entry / SIGNATURE).is_file() else {}
        except (OSError, ValueError):
            manifest, signature = {}, {}
        model = manifest.get("model", {}) if isinstance(manifest, dict) else {}
        found.append(
            Release(
                entry.name,
                str(manifest.get("created_utc", "?")) if isinstance(manifest, dict) else "?",
                str(model.get("kind", "?")) if isinstance(model, dict) else "?",
                signature.get("key_id") if isinstance(signature, dict) else None,
                entry.name == current,
                entry.name == previous,
            )
        )
    return sorted(found, key=lambda r: (r.created_utc, r.id))


def prune(directory: Path, keep: int) -> list[str]:
    """Remove the oldest releases beyond ``keep``; ``current`` and ``previous`` always stay."""
    if keep < 2:
        raise BundleError(f"--keep {keep}: keep at least 2 releases (the current and the one to roll back to)")
    releases = list_releases(directory)
    spare = [r for r in releases if not (r.current or r.previous)]
    excess = len(releases) - keep
    removed = []
    for release in spare[: max(excess, 0)]:
        shutil.rmtree(directory / RELEASES / release.id)
        removed.append(release.id)
    if removed:
        fsync_path(directory / RELEASES)
    return removed
