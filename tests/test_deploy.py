"""pmactl deploy / rollback / releases to a local target: the steps, the refusals, the rollback."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from edge.runtime.bundle import load_bundle
from tests.deploy_helpers import bundle, cli, current, keys, release_id

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"


@pytest.fixture
def signed(tmp_path):
    private, public = keys(tmp_path / "keys")
    return private, public


def test_deploy_then_rollback_then_roll_forward(tmp_path, signed, capsys):
    private, public = signed
    target = tmp_path / "rig"
    first, second = bundle(tmp_path / "a", 1, private), bundle(tmp_path / "b", 2, private)
    status, out, _ = cli(capsys, "deploy", first, target, "--trusted", public, "--json")
    outcome = json.loads(out)
    assert status == 0 and outcome["ok"] and current(target) == release_id(first)
    assert [s["step"] for s in outcome["steps"]] == [
        "local verify",
        "connect",
        "prepare",
        "upload",
        "fsync",
        "verify",
        "publish",
        "health",
        "flip",
        "post-flip health",
        "post-flip",
        "prune",
    ]
    assert load_bundle(target, trusted_keys=[public]).release_id == release_id(first)  # as the edge loads it
    assert cli(capsys, "deploy", second, target, "--trusted", public)[0] == 0
    assert current(target) == release_id(second)
    status, out, _ = cli(capsys, "releases", target, "--json")
    listed = json.loads(out)
    assert [(r["id"], r["current"], r["previous"]) for r in listed["releases"]] == [
        (release_id(first), False, True),
        (release_id(second), True, False),
    ]
    assert all(r["signer"] for r in listed["releases"])
    assert cli(capsys, "rollback", target, "--trusted", public)[0] == 0
    assert current(target) == release_id(first)
    assert cli(capsys, "rollback", target)[0] == 0
    assert current(target) == release_id(second)


def test_a_failing_health_check_leaves_current_and_removes_the_new_release(tmp_path, capsys):
    target = tmp_path / "rig"
    assert cli(capsys, "deploy", bundle(tmp_path / "a", 1), target)[0] == 0
    running = current(target)
    status, out, err = cli(capsys, "deploy", bundle(tmp_path / "b", 2), target, "--tick-limit-us", "0.001")
    assert status == 2 and "step 'health'" in err and "over the 0.001 us limit" in err
    assert err.count("\n") == 1 and current(target) == running
    assert sorted(p.name for p in (target / "releases").iterdir()) == [running]


def test_a_failed_check_after_the_flip_rolls_back_by_itself(tmp_path, capsys):
    target = tmp_path / "rig"
    assert cli(capsys, "deploy", bundle(tmp_path / "a", 1), target)[0] == 0
    running = current(target)
    log = tmp_path / "restarts.log"
    command = f"echo started $(readlink {target}/current) >> {log}; test ! -e {tmp_path}/break"
    (tmp_path / "break").touch()  # the service "fails to start" with the new release
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "b", 2), target, "--post-flip", command)
    assert status == 2 and "step 'post-flip'" in err and "rolled back" in err
    assert current(target) == running
    started = log.read_text().split()
    assert started[-1] == f"releases/{running}"  # the old release was started again


def test_an_untrusted_bundle_never_leaves_the_host(tmp_path, signed, capsys):
    _, public = signed
    target = tmp_path / "rig"
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "a"), target, "--trusted", public)
    assert status == 2 and "step 'local verify'" in err and "unsigned" in err
    assert not target.exists()


def test_a_bundle_in_other_units_fails_the_health_check(tmp_path, capsys):
    import numpy as np

    from models_export.bundle import write_bundle
    from tests.strategies import random_dpi

    model = random_dpi(np.random.default_rng(1))
    model.reset(model.input_range[0], "descending")
    write_bundle(tmp_path / "u", model, model.inverse(), units=("u", "y"))
    status, _, err = cli(capsys, "deploy", tmp_path / "u", tmp_path / "rig")
    assert status == 2 and "step 'health'" in err and "--units bar,mm" in err
    assert current(tmp_path / "rig") is None


def test_rollback_without_a_previous_release_says_so(tmp_path, capsys):
    target = tmp_path / "rig"
    assert cli(capsys, "deploy", bundle(tmp_path / "a"), target)[0] == 0
    status, _, err = cli(capsys, "rollback", target)
    assert status == 2 and "no previous release" in err


@pytest.mark.parametrize(
    "target, message",
    [("ftp://rig/x", "scheme 'ftp' unknown"), ("ssh://rig", "needs a host and a directory"), ("ssh://rig:x/a", "port")],
)
def test_a_malformed_target_is_one_line(tmp_path, capsys, target, message):
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "a"), target)
    assert status == 2 and message in err and err.count("\n") == 1


def test_the_systemd_unit_runs_the_current_release(tmp_path):
    unit = (EXAMPLES / "pmactl-edge.service").read_text()
    exec_start = re.search(r"^ExecStart=(.*?)(?<!\\)$", unit, re.S | re.M).group(1)
    bundle_dir = re.search(r"--bundle (\S+)", exec_start).group(1)
    assert bundle_dir.endswith("/current")
    assert f"StateDirectory={Path(bundle_dir).parent.name}" in unit  # systemd makes the deploy target


EDGE_ONLY = """
import importlib.abc, runpy, sys
class HostExtrasMissing(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name.split(".")[0] in {"scipy", "torch", "matplotlib", "asyncssh", "onnx", "ray", "tqdm"}:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, HostExtrasMissing())
sys.argv = ["agent", *sys.argv[1:]]
runpy.run_module("host.deploy.agent", run_name="__main__")
"""


def test_the_target_agent_needs_only_the_edge_extra(tmp_path):
    import shutil
    import subprocess
    import sys

    from edge.runtime.bundle import resolve_release

    def agent(*args):
        done = subprocess.run([sys.executable, "-c", EDGE_ONLY, *map(str, args)], capture_output=True, text=True)
        assert done.stderr == "", done.stderr
        return json.loads(done.stdout)

    source = resolve_release(bundle(tmp_path / "a"))
    target = tmp_path / "rig"
    staging = Path(agent("prepare", "--root", target)["staging"])
    for path in source.iterdir():
        shutil.copyfile(path, staging / path.name)
    installed = agent("install", "--root", target, "--staging", staging, "--id", source.name)
    assert installed["ok"] and installed["current"] == source.name


# -- review findings: foreign targets, the staging path, the target's own keys, messages ------


@pytest.mark.parametrize("foreign", ["notes.txt", "releases/old/thesis.tex"])
def test_a_foreign_target_folder_is_refused_in_one_line(tmp_path, capsys, foreign):
    target = tmp_path / "rig"
    (target / foreign).parent.mkdir(parents=True, exist_ok=True)
    (target / foreign).write_text("mine")
    before = sorted(p.relative_to(target) for p in target.rglob("*"))
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "a"), target)
    assert status == 2 and "step 'prepare'" in err and "not a pmactl deploy target" in err
    assert err.count("\n") == 1 and sorted(p.relative_to(target) for p in target.rglob("*")) == before


def test_install_refuses_a_staging_path_outside_the_targets_releases(tmp_path, capsys):
    from host.deploy import agent

    target = tmp_path / "rig"
    assert cli(capsys, "deploy", bundle(tmp_path / "a"), target)[0] == 0
    victim = tmp_path / "thesis"
    victim.mkdir()
    (victim / "chapter1.tex").write_text("mine")
    status = agent.main(["install", "--root", str(target), "--staging", str(victim), "--id", "0" * 16])
    answer = json.loads(capsys.readouterr().out)
    assert status == 1 and "not an incoming upload" in answer["error"]
    assert (victim / "chapter1.tex").read_text() == "mine"


def test_the_first_deploy_with_trusted_pins_the_key_and_unsigned_ones_are_refused_after(tmp_path, signed, capsys):
    private, public = signed
    target = tmp_path / "rig"
    status, out, _ = cli(capsys, "deploy", bundle(tmp_path / "a", 1, private), target, "--trusted", public)
    assert status == 0 and "now trusts only key" in out
    assert [p.suffix for p in (target / "trusted_keys").iterdir()] == [".pub"]
    running = current(target)
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "b", 2), target)  # unsigned, no --trusted
    assert status == 2 and "step 'verify'" in err and "unsigned" in err and "trusted_keys" in err
    assert current(target) == running


def test_a_later_deploy_cannot_swap_the_targets_keys(tmp_path, signed, capsys):
    private, public = signed
    other_private, other_public = keys(tmp_path / "other")
    target = tmp_path / "rig"
    assert cli(capsys, "deploy", bundle(tmp_path / "a", 1, private), target, "--trusted", public)[0] == 0
    pinned = sorted(p.read_bytes() for p in (target / "trusted_keys").iterdir())
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "b", 2, other_private), target, "--trusted", other_public)
    assert status == 2 and "step 'verify'" in err and "not trusted" in err
    assert sorted(p.read_bytes() for p in (target / "trusted_keys").iterdir()) == pinned


def test_keys_placed_on_the_target_by_hand_are_required(tmp_path, signed, capsys):
    import shutil

    _, public = signed
    target = tmp_path / "rig"
    (target / "trusted_keys").mkdir(parents=True)
    shutil.copyfile(public, target / "trusted_keys" / "pmactl.pub")  # the documented one-time step
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "a"), target)
    assert status == 2 and "step 'verify'" in err and "unsigned" in err
    assert current(target) is None


def test_a_local_verify_failure_does_not_claim_the_targets_state(tmp_path, signed, capsys):
    _, public = signed
    status, _, err = cli(capsys, "deploy", bundle(tmp_path / "a"), tmp_path / "rig", "--trusted", public)
    assert status == 2 and "step 'local verify'" in err
    assert "current is" not in err and "not contacted" in err


def test_rollback_also_requires_the_targets_keys(tmp_path, signed, capsys):
    import shutil

    _, public = signed
    target = tmp_path / "rig"
    assert cli(capsys, "deploy", bundle(tmp_path / "a", 1), target)[0] == 0  # unsigned, before any keys
    assert cli(capsys, "deploy", bundle(tmp_path / "b", 2), target)[0] == 0
    running = current(target)
    (target / "trusted_keys").mkdir()
    shutil.copyfile(public, target / "trusted_keys" / "pmactl.pub")
    status, _, err = cli(capsys, "rollback", target)
    assert status == 2 and "step 'health'" in err and "unsigned" in err
    assert current(target) == running
