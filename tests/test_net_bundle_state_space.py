"""``train --model state-space --save``: the neural state-space forward and an inverse net as a bundle store.

One short ``edge record`` recording of the emulated rig to train on and one to hold out, a few
epochs (these tests check the wiring, not the fit).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from edge.runtime.bundle import load_bundle
from host.cli import main
from tests.net_recordings import record_train_and_held, train_store
from tests.test_net_bundle import SINE, rig_config


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    return record_train_and_held(tmp_path_factory.mktemp("ssbundle"))


@pytest.fixture(scope="module")
def store(trained):
    root, (recording, held) = trained
    return train_store(root, recording, held, "state-space", 2)


def test_the_bundle_holds_the_state_space_forward_and_an_inverse_net_and_verifies(trained, store, capsys):
    bundle = load_bundle(store, trusted_keys=[trained[0] / "keys" / "pmactl.pub"])
    assert bundle.signer is not None
    assert bundle.manifest["roles"] == {"feedforward": ["table", "net"], "forward": ["table", "net"]}
    nets = bundle.manifest["nets"]
    assert nets["forward"]["model"] == "state-space" and nets["inverse"]["model"] == "lstm-narmax"
    assert "operator" not in nets["forward"] and "operator.npz" not in bundle.manifest["files"]
    assert bundle.forward_net(0.01).kind == "state-space"
    capsys.readouterr()
    assert main(["bundle", "verify", str(store)]) == 0
    capsys.readouterr()
    assert main(["bundle", "inspect", str(store), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    with np.load(bundle.path / "golden.npz") as golden:
        nets_n = golden["forward_net_input"].size + golden["inverse_net_input"].size
    assert bundle.net_golden_samples == nets_n and record["golden_samples"] > nets_n


def test_the_edge_forward_reproduces_the_trained_model_on_a_held_out_record(trained):
    from host.data import load_measurement
    from host.train import train_model

    root, (recording, held) = trained
    model = train_model("state-space", [load_measurement(recording)], epochs=2).model
    target = root / "parity"
    assert main(["train", "--model", "state-space", "--train", str(recording), "--units", "bar,mm",
                 "--epochs", "2", "--save", str(target), "--json"]) == 0  # fmt: skip
    forward = load_bundle(target).forward_net(0.01)  # same seed, same model
    forward.reset()
    u = load_measurement(held).u
    edge = forward.simulate(u)
    host = model.simulate(u)
    assert np.max(np.abs(edge - host)) < 1e-3 * float(np.ptp(host))


def test_a_faster_loop_steps_the_net_at_its_period(store):
    forward = load_bundle(store).forward_net(0.005)
    assert forward.ticks_per_step == 2
    forward.reset()
    u = np.linspace(0.0, 5.0, 200)
    fast = forward.simulate(np.repeat(u, 2))[::2]
    forward.reset()
    slow = load_bundle(store).forward_net(0.01).simulate(u)
    assert np.allclose(fast, slow, atol=1e-9)


def test_deployed_and_run_with_the_net_feedforward(trained, store, capsys):
    root = trained[0]
    target = root / "target"
    assert main(["deploy", str(store), str(target), "--trusted", str(root / "keys" / "pmactl.pub")]) == 0
    capsys.readouterr()
    code = main(["edge", "run", "--config", str(rig_config(root, "net")), "--bundle", str(target / "current"),
                 "--reference", SINE, "--duration", "2", "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["faults"] == [] and summary["feedforward_role"] == "net"


def test_simulate_runs_the_state_space_net(trained, store, tmp_path, capsys):
    from host.data import load_measurement

    held = trained[1][1]
    capsys.readouterr()
    assert main(["simulate", str(store), str(held), "--out", str(tmp_path / "net.csv"), "--role", "net"]) == 0
    assert capsys.readouterr().out.strip().startswith("state-space net of the bundle")
    net = np.loadtxt(tmp_path / "net.csv", delimiter=",", skiprows=1)[:, 2]
    forward = load_bundle(store).forward_net(0.01)
    forward.reset()
    assert np.allclose(net, forward.simulate(load_measurement(held).u), rtol=1e-6, atol=1e-6)


def test_quantise_measures_the_inverse_and_leaves_the_state_space_forward_float32(trained, store, tmp_path, capsys):
    import shutil

    copy = tmp_path / "store"
    shutil.copytree(store, copy, symlinks=True)
    capsys.readouterr()
    assert main(["quantise", str(copy), "--calibration", str(trained[1][1]), "--json"]) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert set(report["nets"]) == {"inverse"}
    assert load_bundle(copy).forward_net(0.01).kind == "state-space"


def test_edge_run_with_the_state_space_net_as_the_twin(trained, store, capsys):
    root = trained[0]
    capsys.readouterr()
    code = main(["edge", "run", "--config", str(rig_config(root, "net", "net")), "--bundle", str(store),
                 "--reference", SINE, "--duration", "2", "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["faults"] == [] and summary["twin_model"] == "net"
