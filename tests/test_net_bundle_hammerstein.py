"""``train --model hammerstein --save``: the Hammerstein forward and an inverse net as a bundle store.

One short ``edge record`` recording of the emulated rig with rate dependence to train on and one
to hold out, a few epochs (these tests check the wiring; the numbers are in the report and in
docs/methods/neural.md).
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
    return record_train_and_held(tmp_path_factory.mktemp("hambundle"))


@pytest.fixture(scope="module")
def store(trained):
    root, (recording, held) = trained
    return train_store(root, recording, held, "hammerstein", 3)


def test_the_bundle_holds_the_hammerstein_forward_and_an_inverse_net_and_verifies(trained, store, capsys):
    bundle = load_bundle(store, trusted_keys=[trained[0] / "keys" / "pmactl.pub"])
    assert bundle.signer is not None
    assert bundle.manifest["roles"] == {"feedforward": ["table", "net"], "forward": ["table", "net"]}
    nets = bundle.manifest["nets"]
    assert nets["forward"]["model"] == "hammerstein" and nets["inverse"]["model"] == "lstm-narmax"
    assert nets["forward"]["training"]["method"].startswith("Hammerstein")
    assert bundle.forward_net(0.01).kind == "hammerstein"
    capsys.readouterr()
    assert main(["bundle", "inspect", str(store), "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    with np.load(bundle.path / "golden.npz") as golden:
        tables = golden["forward_input"].size + golden["inverse_input"].size
        nets_n = golden["forward_net_input"].size + golden["inverse_net_input"].size
    assert record["golden_samples"] == tables + nets_n and bundle.net_golden_samples == nets_n


def test_the_edge_forward_reproduces_the_trained_hammerstein(trained):
    from host.data import load_measurement
    from host.train import train_model

    record = load_measurement(trained[1][0])
    model = train_model("hammerstein", [record], epochs=2).model
    root = trained[0] / "parity"
    assert main(["train", "--model", "hammerstein", "--train", str(trained[1][0]), "--units", "bar,mm",
                 "--epochs", "2", "--save", str(root), "--json"]) == 0  # fmt: skip
    forward = load_bundle(root).forward_net(0.01)  # same seed, same model
    forward.reset()
    u = record.u[record.u.argmin() :]  # from the vented rest state the edge arms in
    edge = np.array([forward.step(p) for p in u.tolist()])
    host = model.simulate(u, "descending")
    assert np.max(np.abs(edge - host)) < 1e-3 * float(np.ptp(host))


def test_the_json_names_the_inverse_score_on_each_test_file(trained, tmp_path, capsys):
    root, (recording, held) = trained
    assert main(["train", "--model", "hammerstein", "--train", str(recording), "--test", str(held), "--units",
                 "bar,mm", "--epochs", "2", "--save", str(tmp_path / "s"), "--json"]) == 0  # fmt: skip
    out = json.loads(capsys.readouterr().out.strip().splitlines()[0])
    (score,) = out["bundle"]["inverse_tests"]
    assert score["file"] == "held.csv" and score["samples"] > 1000
    assert np.isfinite(score["rmse_bar"]) and score["table_rmse_bar"] > 0
    assert out["bundle"]["forward_model"] == "hammerstein"


def test_deployed_and_run_with_the_net_feedforward(trained, store, capsys):
    root = trained[0]
    target = root / "target"
    assert main(["deploy", str(store), str(target), "--trusted", str(root / "keys" / "pmactl.pub")]) == 0
    capsys.readouterr()
    code = main(["edge", "run", "--config", str(rig_config(root, "net")), "--bundle", str(target / "current"),
                 "--reference", SINE, "--duration", "2", "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["faults"] == [] and summary["feedforward_role"] == "net"


def test_simulate_runs_the_forward_net_and_the_table_on_request(trained, store, tmp_path, capsys):
    from host.data import load_measurement

    held = trained[1][1]
    assert main(["simulate", str(store), str(held), "--out", str(tmp_path / "net.csv")]) == 0
    assert main(["simulate", str(store), str(held), "--out", str(tmp_path / "table.csv"), "--role", "table"]) == 0
    net_line, table_line = capsys.readouterr().out.strip().splitlines()
    assert net_line.startswith("hammerstein net of the bundle") and "lookup table" in table_line
    net = np.loadtxt(tmp_path / "net.csv", delimiter=",", skiprows=1)[:, 2]
    forward = load_bundle(store).forward_net(0.01)
    forward.reset()
    expected = forward.simulate(load_measurement(held).u)
    assert np.allclose(net, expected, rtol=1e-6, atol=1e-6)
    table = np.loadtxt(tmp_path / "table.csv", delimiter=",", skiprows=1)[:, 2]
    assert np.max(np.abs(net - table)) > 0.01  # a different model, not the table twice


def test_simulate_refuses_a_net_role_without_a_net_and_an_input_at_another_rate(trained, store, tmp_path, capsys):
    recording = trained[1][0]
    table_only = tmp_path / "table"
    assert main(["fit", "--model", "mpi", "--train", str(recording), "--units", "bar,mm", "--save",
                 str(table_only)]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["simulate", str(table_only), str(recording), "--out", str(tmp_path / "a.csv"), "--role", "net"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "holds no forward net" in err[0]
    fast = tmp_path / "fast.csv"
    rows = np.loadtxt(recording, delimiter=",", skiprows=1)
    rows[:, 0] *= 0.5  # the same samples at 200 Hz
    header = recording.read_text().splitlines()[0]
    np.savetxt(fast, rows, delimiter=",", header=header, comments="", fmt="%.9g")
    assert main(["simulate", str(store), str(fast), "--out", str(tmp_path / "b.csv")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "steps every 10 ms" in err[0] and "--role table" in err[0]
    assert not (tmp_path / "a.csv").exists() and not (tmp_path / "b.csv").exists()
