"""pmactl deploy over SSH against a real server on 127.0.0.1 (tests/ssh_server.py), with the
user's ~/.ssh (config alias, key, known_hosts) and faults at the server's file system."""

from __future__ import annotations

import json
import sys

import asyncssh
import pytest

from tests.deploy_helpers import bundle, cli, current, keys, release_id
from tests.ssh_server import SSHServer, make_client_home


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    root = tmp_path_factory.mktemp("sshd")
    client_key = asyncssh.generate_private_key("ssh-ed25519")
    client_key.write_public_key(str(root / "authorized_keys"))
    sshd = SSHServer(asyncssh.generate_private_key("ssh-ed25519"), root / "authorized_keys").start()
    sshd.client_key = client_key
    yield sshd
    sshd.stop()


@pytest.fixture
def home(tmp_path, server, monkeypatch):
    """HOME with the user's SSH setup; no ssh-agent of the machine running the tests."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.delenv("SSH_AUTH_SOCK", raising=False)
    make_client_home(tmp_path / "home", server, server.client_key)
    server.faults.clear()
    yield tmp_path / "home"
    server.faults.clear()


@pytest.fixture
def rig(tmp_path, home, capsys):
    """A target over SSH that already runs release A; yields (url, path, A's id, B's dir)."""
    private, public = keys(tmp_path / "keys")
    first, second = bundle(tmp_path / "a", 1, private), bundle(tmp_path / "b", 2, private)
    path = tmp_path / "rig"
    url = f"ssh://rig{path}"
    status, _, err = cli(capsys, "deploy", first, url, "--remote-python", sys.executable, "--trusted", public)
    assert status == 0, err
    return url, path, release_id(first), second, public


def deploy(capsys, url, source, *extra):
    return cli(capsys, "deploy", source, url, "--remote-python", sys.executable, *extra)


def test_deploy_over_ssh_with_the_users_config_alias_then_list_and_roll_back(rig, capsys):
    url, path, running, second, public = rig
    status, out, _ = deploy(capsys, url, second, "--trusted", public, "--json")
    assert status == 0 and json.loads(out)["current"] == release_id(second) == current(path)
    status, out, _ = cli(capsys, "releases", url, "--remote-python", sys.executable)
    assert status == 0 and f"current  {release_id(second)}" in out and f"previous {running}" in out
    assert cli(capsys, "rollback", url, "--remote-python", sys.executable)[0] == 0
    assert current(path) == running


def test_an_unknown_host_key_is_refused_with_one_line(rig, home, capsys):
    url, path, running, second, _ = rig
    (home / ".ssh" / "known_hosts").write_text("")
    status, _, err = deploy(capsys, url, second)
    assert status == 2 and "host key not trusted" in err and err.count("\n") == 1
    assert current(path) == running


def test_a_connection_dropped_mid_upload_leaves_the_running_release(rig, server, capsys):
    url, path, running, second, _ = rig
    server.faults.drop_after_bytes = 5000  # into the first table, well before the manifest
    status, _, err = deploy(capsys, url, second)
    assert status == 2 and "step 'upload'" in err and "the running release is untouched" in err
    assert current(path) == running and sorted(p.name for p in (path / "releases").iterdir() if p.name[0] != ".") == [
        running
    ]
    server.faults.clear()
    assert deploy(capsys, url, second)[0] == 0 and current(path) == release_id(second)  # a retry goes through


def test_a_file_corrupted_in_transit_is_caught_on_the_target(rig, server, capsys):
    url, path, running, second, _ = rig
    server.faults.corrupt_file = "inverse.npz"
    status, _, err = deploy(capsys, url, second)
    assert status == 2 and "step 'verify'" in err and "checksum mismatch" in err
    assert current(path) == running
    assert sorted(p.name for p in (path / "releases").iterdir()) == [running]  # nothing half-installed


def test_a_full_disk_on_the_target_stops_the_upload(rig, server, capsys):
    url, path, running, second, _ = rig
    server.faults.quota_bytes = 8000
    status, _, err = deploy(capsys, url, second)
    assert status == 2 and "step 'upload'" in err and "space" in err.lower()
    assert current(path) == running
    assert sorted(p.name for p in (path / "releases").iterdir()) == [running]  # the partial upload was removed


def test_a_failing_health_check_over_ssh_keeps_the_running_release(rig, capsys):
    url, path, running, second, _ = rig
    status, _, err = deploy(capsys, url, second, "--tick-limit-us", "0.001")
    assert status == 2 and "step 'health'" in err and current(path) == running
    status, _, err = deploy(capsys, url, second, "--post-flip", "exit 3")
    assert status == 2 and "step 'post-flip'" in err and "rolled back" in err and current(path) == running


@pytest.fixture
def tiny_tmpfs(tmp_path):
    """A real 40 KiB tmpfs where mounting is permitted (root in CI); skipped elsewhere."""
    import shutil
    import subprocess

    mount_point = tmp_path / "small-disk"
    mount_point.mkdir()
    if shutil.which("mount") is None:
        pytest.skip("no mount command")
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=40k", "tmpfs", str(mount_point)], capture_output=True)
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here ({done.stderr.decode().strip()}); the ENOSPC quota test covers it")
    try:
        yield mount_point
    finally:
        subprocess.run(["umount", str(mount_point)], check=True)


def test_a_really_full_file_system_on_the_target(tiny_tmpfs, tmp_path, home, capsys):
    """The same fault without simulation: the target directory is a 40 KiB tmpfs that holds one
    release (about 30 KiB in pages) but not two."""
    first, second = bundle(tmp_path / "a", 1), bundle(tmp_path / "b", 2)
    url = f"ssh://rig{tiny_tmpfs}/rig"
    assert deploy(capsys, url, first)[0] == 0
    running = current(tiny_tmpfs / "rig")
    status, _, err = deploy(capsys, url, second)
    assert status == 2 and "space" in err.lower() and err.count("\n") == 1
    assert current(tiny_tmpfs / "rig") == running
    assert sorted(p.name for p in (tiny_tmpfs / "rig" / "releases").iterdir()) == [running]
