"""A real SSH server on 127.0.0.1 for deploy tests: asyncssh in a thread of the test process.

Public-key authentication against an authorized_keys file, a host key the client must find in
its known_hosts, SFTP onto the real file system, and commands run as real processes through
the shell (``asyncio.create_subprocess_shell``), as sshd would run them. Faults are injected at
the server's file-system boundary (:class:`Faults`), never in the client's transport:

* ``drop_after_bytes``: the server aborts the TCP connection once that many bytes were written;
* ``corrupt_file``: one byte of that file is flipped as it is written (bit rot in transit /
  on a bad card, after SSH's own integrity check);
* ``quota_bytes``: writes beyond this many bytes fail with ENOSPC, as on a full disk.
"""

from __future__ import annotations

import asyncio
import errno
import subprocess
import threading
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import asyncssh


@dataclass
class Faults:
    drop_after_bytes: int | None = None
    corrupt_file: str | None = None
    quota_bytes: int | None = None
    written: int = 0

    def clear(self) -> None:
        self.drop_after_bytes = self.corrupt_file = self.quota_bytes = None
        self.written = 0


class FaultySFTPServer(asyncssh.SFTPServer):
    faults = Faults()

    def __init__(self, chan: asyncssh.SSHServerChannel) -> None:
        super().__init__(chan)
        self._names: dict[int, str] = {}

    def open(self, path: bytes, pflags: int, attrs: asyncssh.SFTPAttrs) -> object:
        handle = super().open(path, pflags, attrs)
        self._names[id(handle)] = Path(path.decode()).name
        return handle

    def write(self, file_obj: object, offset: int, data: bytes) -> int:
        faults = self.faults
        if faults.quota_bytes is not None and faults.written + len(data) > faults.quota_bytes:
            raise OSError(errno.ENOSPC, "No space left on device")
        if faults.drop_after_bytes is not None and faults.written + len(data) > faults.drop_after_bytes:
            self.connection.abort()
            raise OSError(errno.ECONNRESET, "connection dropped by the test server")
        if faults.corrupt_file is not None and self._names.get(id(file_obj)) == faults.corrupt_file:
            data = bytes([data[0] ^ 0x01]) + data[1:]
            faults.corrupt_file = None
        faults.written += len(data)
        return super().write(file_obj, offset, data)  # type: ignore[return-value]


# one worker started with the server: asyncio's own subprocess support would leave a waitpid
# thread per command behind, which the leak guard in conftest.py rightly flags
_COMMANDS = ThreadPoolExecutor(max_workers=1, thread_name_prefix="test-sshd-command")


def _shell(command: str) -> subprocess.CompletedProcess[bytes]:
    return subprocess.run(command, shell=True, stdin=subprocess.DEVNULL, capture_output=True)


async def _run_command(process: asyncssh.SSHServerProcess) -> None:
    done = await asyncio.get_running_loop().run_in_executor(_COMMANDS, _shell, process.command or "true")
    process.stdout.write(done.stdout)
    process.stderr.write(done.stderr)
    process.exit(done.returncode)


class SSHServer:
    """Runs the server on its own event loop in a daemon thread; ``port`` once started."""

    def __init__(self, host_key: asyncssh.SSHKey, authorized_keys: Path) -> None:
        self.host_key, self.authorized_keys = host_key, authorized_keys
        self.loop = asyncio.new_event_loop()
        self.faults = FaultySFTPServer.faults
        self.port = 0
        self._thread = threading.Thread(target=self.loop.run_forever, name="test-sshd", daemon=True)
        self._server: asyncssh.SSHAcceptor | None = None

    def start(self) -> SSHServer:
        _COMMANDS.submit(lambda: None).result()  # its worker exists before any test runs
        self._thread.start()
        self._server = asyncio.run_coroutine_threadsafe(self._listen(), self.loop).result(timeout=30)
        self.port = self._server.sockets[0].getsockname()[1]
        return self

    async def _listen(self) -> asyncssh.SSHAcceptor:
        return await asyncssh.listen(
            "127.0.0.1",
            0,
            server_host_keys=[self.host_key],
            authorized_client_keys=str(self.authorized_keys),
            process_factory=_run_command,
            sftp_factory=FaultySFTPServer,
            encoding=None,
        )

    def stop(self) -> None:
        async def close() -> None:
            assert self._server is not None
            self._server.close()
            await self._server.wait_closed()

        asyncio.run_coroutine_threadsafe(close(), self.loop).result(timeout=30)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(timeout=30)
        self.loop.close()


def make_client_home(home: Path, server: SSHServer, client_key: asyncssh.SSHKey, alias: str = "rig") -> None:
    """A user's ``~/.ssh``: id_ed25519, known_hosts with the server's key, config with ``Host alias``."""
    ssh = home / ".ssh"
    ssh.mkdir(parents=True, exist_ok=True)
    ssh.chmod(0o700)
    client_key.write_private_key(str(ssh / "id_ed25519"))
    (ssh / "id_ed25519").chmod(0o600)
    client_key.write_public_key(str(ssh / "id_ed25519.pub"))
    public = server.host_key.export_public_key().decode().strip()
    (ssh / "known_hosts").write_text(f"[127.0.0.1]:{server.port} {public}\n")
    (ssh / "config").write_text(
        f"Host {alias}\n    HostName 127.0.0.1\n    Port {server.port}\n    IdentityFile ~/.ssh/id_ed25519\n"
    )
