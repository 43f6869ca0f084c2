"""Deploy, roll back and list releases on a target (the host side of ``pmactl deploy``).

Order of a deploy, each step named in the result and in any error:

1. ``local verify``: the release verifies here (signature against ``--trusted``, checksums,
   roles, golden vectors), so a bad bundle never leaves the host.
2. ``connect``, ``prepare``: reach the target, make ``releases/.incoming-*`` there.
3. ``upload``: the release's files into the incoming directory.
4. on the target (``host.deploy.agent install``): ``fsync``, ``verify``, ``publish``, ``health``,
   ``flip``, ``post-flip health``, ``post-flip``, ``prune``; a failure after the flip restores
   ``current`` by itself (``rolled_back``).

``current`` on the target changes only in ``flip`` (one rename), so every failure before it
leaves the running release exactly as it was.
"""

from __future__ import annotations

import base64
import json
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

from edge.errors import PmactlError
from edge.runtime.bundle import MANIFEST, SIGNATURE, load_bundle, read_public_key
from host.deploy import DeployError
from host.deploy.health import DEFAULT_TICK_LIMIT_US
from host.deploy.transport import TargetURL, Transport, open_transport, parse_target
from models_export.store import DEFAULT_KEEP


@dataclass
class Outcome:
    """What happened on the target: ``failed_step`` and ``error`` are set when ``ok`` is false."""

    ok: bool
    target: str
    release: str | None = None
    failed_step: str | None = None
    error: str | None = None
    current: str | None = None
    previous: str | None = None
    rolled_back: bool = False
    reached: bool = False  # the target was contacted, so ``current`` / ``previous`` are its state
    pinned_keys: list[str] = field(default_factory=list)
    seconds: float = 0.0
    bytes_sent: int = 0
    steps: list[dict[str, object]] = field(default_factory=list)
    releases: list[dict[str, object]] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        return asdict(self)

    def fail(self, step: str, error: str, since: float | None = None) -> Outcome:
        self.ok, self.failed_step, self.error = False, step, error
        self.steps.append({"step": step, "ok": False, "error": error, **_seconds(since)})
        return self

    def passed(self, step: str, detail: object, since: float) -> None:
        self.steps.append({"step": step, "ok": True, "detail": detail, **_seconds(since)})


def _seconds(since: float | None) -> dict[str, float]:
    return {} if since is None else {"seconds": time.perf_counter() - since}


def _trusted_args(trusted: Sequence[Path]) -> list[str]:
    args = []
    for path in trusted:
        _, raw = read_public_key(Path(path))
        args += ["--trusted-key", base64.b64encode(raw).decode()]
    return args


async def _agent(transport: Transport, args: Sequence[str], step: str) -> dict[str, object]:
    status, out, err = await transport.agent(args)
    try:
        result = json.loads(out.strip().splitlines()[-1])
        if not isinstance(result, dict):
            raise ValueError("not an object")
        return result
    except (ValueError, IndexError) as exc:
        last = (err.strip().splitlines() or ["no output"])[-1]
        raise DeployError(
            f"{step}: the agent on {transport.description} did not answer (exit {status}: {last}); install "
            "pmactl[edge] there or name its Python with --remote-python"
        ) from exc


async def deploy(
    source: str | Path,
    target: str,
    *,
    trusted: Sequence[Path] = (),
    keep: int = DEFAULT_KEEP,
    tick_limit_us: float = DEFAULT_TICK_LIMIT_US,
    post_flip: str | None = None,
    remote_python: str = "python3",
) -> Outcome:
    """Ship the release at ``source`` (a bundle directory or a release) to ``target``."""
    start = time.perf_counter()
    outcome = Outcome(False, target)
    try:
        url = parse_target(target)
    except PmactlError as exc:
        return outcome.fail("arguments", str(exc))
    outcome.target = str(url)
    await _deploy(outcome, url, source, start, trusted, keep, tick_limit_us, post_flip, remote_python)
    outcome.seconds = time.perf_counter() - start
    return outcome


async def _deploy(
    outcome: Outcome,
    url: TargetURL,
    source: str | Path,
    start: float,
    trusted: Sequence[Path],
    keep: int,
    tick_limit_us: float,
    post_flip: str | None,
    remote_python: str,
) -> Outcome:
    if keep < 2:
        return outcome.fail("arguments", f"--keep {keep}: keep at least 2 releases (current and previous)")
    try:
        bundle = load_bundle(source, trusted_keys=list(trusted) or None)
        trusted_args = _trusted_args(trusted)
    except PmactlError as exc:
        return outcome.fail("local verify", str(exc), start)
    outcome.release = bundle.release_id
    outcome.passed("local verify", bundle.identity, start)
    listed = bundle.manifest["files"]
    assert isinstance(listed, dict)  # load_bundle checked it
    files = [bundle.path / name for name in listed]
    files.append(bundle.path / MANIFEST)
    if (bundle.path / SIGNATURE).is_file():
        files.append(bundle.path / SIGNATURE)
    since = time.perf_counter()
    try:
        transport = await open_transport(url, remote_python)
    except PmactlError as exc:
        return outcome.fail("connect", str(exc), since)
    outcome.passed("connect", transport.description, since)
    outcome.reached = True
    async with transport:
        since = time.perf_counter()
        try:
            prepared = await _agent(transport, ["prepare", "--root", url.path], "prepare")
        except PmactlError as exc:
            return outcome.fail("prepare", str(exc), since)
        _state(outcome, prepared)
        if not prepared.get("ok"):
            return outcome.fail("prepare", str(prepared.get("error")), since)
        staging = str(prepared["staging"])
        outcome.passed("prepare", f"{prepared.get('free_bytes')} bytes free", since)
        since = time.perf_counter()
        try:
            outcome.bytes_sent = await transport.upload(files, staging)
            outcome.passed("upload", f"{len(files)} files, {outcome.bytes_sent} B", since)
        except PmactlError as exc:
            outcome.fail("upload", f"{exc}; the running release is untouched", since)
            try:
                await _agent(transport, ["abort", "--root", url.path, "--staging", staging], "abort")
            except PmactlError:
                outcome.error = f"{outcome.error}; the partial upload never runs and a later deploy removes it"
            return outcome
        args = ["install", "--root", url.path, "--staging", staging, "--id", bundle.release_id]
        args += ["--keep", str(keep), "--tick-limit-us", str(tick_limit_us), *trusted_args]
        if post_flip:
            args += ["--post-flip", post_flip]
        try:
            installed = await _agent(transport, args, "install")
        except PmactlError as exc:
            return outcome.fail("install", f"{exc}; run pmactl releases to see what is current")
    outcome.steps.extend(installed.get("steps", []))  # type: ignore[arg-type]
    _state(outcome, installed)
    outcome.ok = bool(installed.get("ok"))
    outcome.rolled_back = bool(installed.get("rolled_back"))
    outcome.pinned_keys = list(installed.get("pinned_keys", []))  # type: ignore[call-overload]
    if not outcome.ok:
        outcome.failed_step, outcome.error = str(installed.get("failed_step")), str(installed.get("error"))
    return outcome


def _state(outcome: Outcome, answer: dict[str, object]) -> None:
    outcome.current = answer.get("current")  # type: ignore[assignment]
    outcome.previous = answer.get("previous")  # type: ignore[assignment]


async def _simple(target: str, args: Sequence[str], step: str, remote_python: str) -> Outcome:
    outcome = Outcome(False, target)
    try:
        url = parse_target(target)
        outcome.target = str(url)
        async with await open_transport(url, remote_python) as transport:
            outcome.reached = True
            answer = await _agent(transport, [args[0], "--root", url.path, *args[1:]], step)
    except PmactlError as exc:
        return outcome.fail(step, str(exc))
    _state(outcome, answer)
    outcome.ok = bool(answer.get("ok"))
    outcome.rolled_back = bool(answer.get("rolled_back"))
    outcome.steps = list(answer.get("steps", []))  # type: ignore[call-overload]
    outcome.releases = list(answer.get("releases", []))  # type: ignore[call-overload]
    if not outcome.ok:
        outcome.failed_step, outcome.error = str(answer.get("failed_step", step)), str(answer.get("error"))
    return outcome


async def rollback(
    target: str,
    *,
    trusted: Sequence[Path] = (),
    tick_limit_us: float = DEFAULT_TICK_LIMIT_US,
    remote_python: str = "python3",
) -> Outcome:
    """Check the previous release on ``target`` and make it current again."""
    try:
        trusted_args = _trusted_args(trusted)
    except PmactlError as exc:
        return Outcome(False, target).fail("arguments", str(exc))
    args = ["rollback", "--tick-limit-us", str(tick_limit_us), *trusted_args]
    return await _simple(target, args, "rollback", remote_python)


async def list_releases(target: str, *, remote_python: str = "python3") -> Outcome:
    """The releases on ``target``, oldest first, with which is current and previous."""
    return await _simple(target, ["releases"], "releases", remote_python)


__all__ = ["Outcome", "TargetURL", "deploy", "list_releases", "rollback"]
