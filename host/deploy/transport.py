"""Reach a deploy target: a local directory, or ``ssh://[user@]host[:port]/path`` through asyncssh.

Why asyncssh: it reads the user's ``~/.ssh/config`` (Host aliases, HostName, Port, User,
IdentityFile, ProxyJump), uses the running ssh-agent and checks ``~/.ssh/known_hosts`` by
default, like ``ssh`` does; it gives SFTP and remote commands over one connection with exit
status and separate stdout/stderr, and typed errors (host key, authentication, connection lost)
that we turn into one line each. Shelling out to ``ssh``/``scp`` would give the same setup but
one connection per file (or ControlMaster tricks) and error text to parse; paramiko does not
read ``~/.ssh/config`` by itself.
"""

from __future__ import annotations

import asyncio
import shlex
import shutil
import subprocess
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING
from urllib.parse import unquote, urlsplit

from host.deploy import DeployError

if TYPE_CHECKING:
    import asyncssh

CHUNK = 1 << 15
CONNECT_TIMEOUT_S = 20.0
AGENT_MODULE = "host.deploy.agent"


@dataclass(frozen=True)
class TargetURL:
    """A parsed TARGET: ``host`` is ``None`` for a local path."""

    path: str
    host: str | None = None
    user: str | None = None
    port: int | None = None

    def __str__(self) -> str:
        if self.host is None:
            return self.path
        user = f"{self.user}@" if self.user else ""
        port = f":{self.port}" if self.port else ""
        return f"ssh://{user}{self.host}{port}{self.path}"


def parse_target(text: str) -> TargetURL:
    """``/local/dir``, ``file:///dir`` or ``ssh://[user@]host[:port]/absolute/path``."""
    if "://" not in text:
        return TargetURL(str(Path(text).expanduser().absolute()))
    parts = urlsplit(text)
    if parts.scheme == "file":
        return TargetURL(unquote(parts.path))
    if parts.scheme != "ssh":
        raise DeployError(
            f"target {text!r}: scheme {parts.scheme!r} unknown; use a path or ssh://[user@]host[:port]/path"
        )
    try:
        port = parts.port
    except ValueError as exc:
        raise DeployError(f"target {text!r}: port is not a number; use ssh://host:2222/path") from exc
    if not parts.hostname or not parts.path or parts.path == "/":
        raise DeployError(f"target {text!r}: needs a host and a directory, e.g. ssh://pi@rig.local/var/lib/pmactl")
    return TargetURL(unquote(parts.path), parts.hostname, unquote(parts.username) if parts.username else None, port)


class Transport:
    """Run the agent on the target and upload files there."""

    description = "target"

    async def __aenter__(self) -> Transport:
        return self

    async def __aexit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()

    async def close(self) -> None:
        return None

    async def agent(self, args: Sequence[str]) -> tuple[int, str, str]:
        """Exit status, stdout and stderr of ``python -m host.deploy.agent ARGS`` on the target."""
        raise NotImplementedError

    async def upload(self, files: Sequence[Path], remote_dir: str) -> int:
        """Copy ``files`` into ``remote_dir``; returns the bytes sent."""
        raise NotImplementedError


class LocalTransport(Transport):
    """A directory on this machine; the agent runs with this Python."""

    def __init__(self, url: TargetURL) -> None:
        self.url = url
        self.description = url.path

    async def agent(self, args: Sequence[str]) -> tuple[int, str, str]:
        # a worker thread, not asyncio's subprocess: that leaves a waitpid thread behind per child
        done = await asyncio.to_thread(
            subprocess.run, [sys.executable, "-m", AGENT_MODULE, *args], capture_output=True, text=True
        )
        return done.returncode, done.stdout, done.stderr

    async def upload(self, files: Sequence[Path], remote_dir: str) -> int:
        sent, total = 0, sum(p.stat().st_size for p in files)
        for path in files:
            try:
                await asyncio.to_thread(shutil.copyfile, path, Path(remote_dir) / path.name)
            except OSError as exc:
                raise DeployError(f"after {sent} of {total} bytes: {_reason(exc)}") from exc
            sent += path.stat().st_size
        return sent


class SSHTransport(Transport):
    """A directory on another machine, reached with the user's own SSH setup."""

    def __init__(self, url: TargetURL, remote_python: str) -> None:
        self.url = url
        self.remote_python = remote_python
        self.description = str(url)
        self.sent = 0
        self._conn: asyncssh.SSHClientConnection | None = None

    async def connect(self) -> SSHTransport:
        import asyncssh

        assert self.url.host is not None
        options: dict[str, object] = {"connect_timeout": CONNECT_TIMEOUT_S}
        if self.url.port:
            options["port"] = self.url.port
        if self.url.user:
            options["username"] = self.url.user
        try:
            self._conn = await asyncssh.connect(self.url.host, **options)
        except asyncssh.HostKeyNotVerifiable as exc:
            raise DeployError(
                f"{self.url.host}: host key not trusted ({exc.reason}); check it and add it to ~/.ssh/known_hosts "
                f"(e.g. connect once with ssh {self.url.host})"
            ) from exc
        except asyncssh.PermissionDenied as exc:
            raise DeployError(
                f"{self.url.host}: authentication failed ({exc.reason}); load your key into ssh-agent or set "
                "IdentityFile in ~/.ssh/config"
            ) from exc
        except (OSError, asyncssh.Error, TimeoutError) as exc:
            raise DeployError(f"{self.url}: cannot connect ({_reason(exc)}); check the host, port and network") from exc
        return self

    async def close(self) -> None:
        if self._conn is not None:
            self._conn.close()
            await self._conn.wait_closed()
            self._conn = None

    async def agent(self, args: Sequence[str]) -> tuple[int, str, str]:
        import asyncssh

        command = shlex.join([self.remote_python, "-m", AGENT_MODULE, *args])
        try:
            assert self._conn is not None
            done = await self._conn.run(command, check=False)
        except (OSError, asyncssh.Error) as exc:
            raise DeployError(f"{self.url}: connection lost while running the agent ({_reason(exc)})") from exc
        return int(done.exit_status if done.exit_status is not None else 255), str(done.stdout), str(done.stderr)

    async def upload(self, files: Sequence[Path], remote_dir: str) -> int:
        import asyncssh

        self.sent = 0
        total = sum(p.stat().st_size for p in files)
        try:
            assert self._conn is not None
            async with self._conn.start_sftp_client() as sftp:
                for path in files:
                    async with sftp.open(f"{remote_dir}/{path.name}", "wb") as remote:
                        with path.open("rb") as local:
                            for block in iter(lambda: local.read(CHUNK), b""):  # noqa: B023 - consumed here
                                await remote.write(block)
                                self.sent += len(block)
        except (OSError, asyncssh.Error) as exc:
            raise DeployError(f"after {self.sent} of {total} bytes: {_reason(exc)}") from exc
        return self.sent


def _reason(exc: BaseException) -> str:
    reason = getattr(exc, "reason", None) or str(exc) or type(exc).__name__
    return f"{type(exc).__name__}: {reason}"


async def open_transport(url: TargetURL, remote_python: str = "python3") -> Transport:
    """A connected transport for ``url``."""
    if url.host is None:
        return LocalTransport(url)
    return await SSHTransport(url, remote_python).connect()
