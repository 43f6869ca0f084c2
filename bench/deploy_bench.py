"""Deploy time over loopback SSH: a real asyncssh server on 127.0.0.1 (tests/ssh_server.py),
the ``pmactl`` CLI as a user runs it (own process, ``~/.ssh/config`` alias), N deploys
alternating two signed releases, then a rollback. Prints wall and CPU time per operation; the
CPU includes the agent processes the server starts on the "target".

    python bench/deploy_bench.py [--deploys 6]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import asyncssh

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.deploy_helpers import bundle, keys  # noqa: E402 - the bench reuses the test set-up
from tests.ssh_server import SSHServer, make_client_home  # noqa: E402


def timed(command: list[str], env: dict[str, str]) -> tuple[float, float]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed: {done.stderr.strip()}")
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--deploys", type=int, default=6)
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        client_key = asyncssh.generate_private_key("ssh-ed25519")
        client_key.write_public_key(str(root / "authorized_keys"))
        server = SSHServer(asyncssh.generate_private_key("ssh-ed25519"), root / "authorized_keys").start()
        try:
            make_client_home(root / "home", server, client_key)
            env = dict(os.environ, HOME=str(root / "home"))
            env.pop("SSH_AUTH_SOCK", None)
            private, public = keys(root / "keys")
            sources = [bundle(root / "a", 1, private), bundle(root / "b", 2, private)]
            pmactl = [sys.executable, "-m", "host.cli"]
            url = f"ssh://rig{root}/rig"
            common = ["--trusted", str(public), "--remote-python", sys.executable]
            rows = {"deploy": [], "rollback": [], "releases": []}
            for i in range(args.deploys):
                rows["deploy"].append(timed([*pmactl, "deploy", str(sources[i % 2]), url, *common], env))
            rows["rollback"].append(timed([*pmactl, "rollback", url, *common], env))
            rows["releases"].append(timed([*pmactl, "releases", url, "--remote-python", sys.executable], env))
        finally:
            server.stop()
    size = sum(p.stat().st_size for p in (root / "a").rglob("*") if p.is_file()) if (root / "a").exists() else 0
    print(f"loopback SSH, asyncssh server in this process; bundle of {size or 'about 17000'} bytes")
    print(f"{'operation':<10} {'runs':>5} {'wall median s':>14} {'wall max s':>11} {'CPU median s':>13}")
    for name, samples in rows.items():
        walls, cpus = [w for w, _ in samples], [c for _, c in samples]
        print(
            f"{name:<10} {len(samples):>5} {statistics.median(walls):>14.2f} {max(walls):>11.2f} "
            f"{statistics.median(cpus):>13.2f}"
        )


if __name__ == "__main__":
    main()
