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
import shutil
import time
from dataclasses import dataclass
from pathlib import Path

from edge.errors import BundleError
from edge.runtime.bundle import CURRENT, MANIFEST, RELEASES, SIGNATURE

PREVIOUS = "previous"
STAGING_PREFIX = ".staging-"
INCOMING_PREFIX = ".incoming-"
STALE_SECONDS = 3600.0  # a staging directory older than this is a crashed write, safe to remove
DEFAULT_KEEP = 5


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


def is_store(directory: Path) -> bool:
    """True when ``directory`` has the releases/current layout."""
    return (directory / RELEASES).is_dir() and not (directory / RELEASES).is_symlink()


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


def _replace_link(directory: Path, name: str, release_id: str) -> None:
    temporary = directory / f".{name}.{os.getpid()}.{time.monotonic_ns()}"
    os.symlink(f"{RELEASES}/{release_id}", temporary)
    os.replace(temporary, directory / name)


def flip(directory: Path, release_id: str) -> str | None:
    """Make ``release_id`` current; ``previous`` gets the old current. Returns the old current."""
    if not (directory / RELEASES / release_id / MANIFEST).is_file():
        raise BundleError(f"{directory}: release {release_id} is not complete; nothing was changed")
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
        if entry.name.startswith(".") or not (entry / MANIFEST).is_file():
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
