"""``pmactl simulate``: a saved model's forward model over an input, from a chosen or estimated start."""

from __future__ import annotations

import numpy as np
import pytest

from host.cli import main
from host.data import load_measurement
from host.examples import example_path
from host.train import save_model, train_model
from host.workflow import make_estimator
from tests.neural_data import hil_csv


def read(path):
    return np.genfromtxt(path, delimiter=",", names=True)


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    folder = tmp_path_factory.mktemp("sim") / "pi"
    assert main(["fit", "--model", "pi", "--train", str(example_path("train")), "--save", str(folder)]) == 0
    return folder


@pytest.fixture(scope="module")
def net(tmp_path_factory):
    root = tmp_path_factory.mktemp("simnet")
    record = load_measurement(hil_csv(root, "sines", 1, 40.0, "rate_dependence"))
    trained = train_model("lstm-narmax", [record], seed=0, epochs=4)
    save_model(trained, root / "net", {"model": "lstm-narmax"})
    held_out = hil_csv(root, "sines", 2, 40.0, "rate_dependence")
    return trained.model, root / "net", held_out


@pytest.mark.parametrize("branch", ["ascending", "descending"])
def test_a_bundle_reproduces_the_fitted_model_from_an_outer_branch(bundle, tmp_path, capsys, branch):
    test = example_path("test")
    assert main(["simulate", str(bundle), str(test), "--out", str(tmp_path / "p.csv"), "--initial", branch]) == 0
    out = read(tmp_path / "p.csv")
    record = load_measurement(test)
    model = make_estimator("pi").fit(*(lambda m: (m.u, m.y))(load_measurement(example_path("train")))).model_
    model.reset(float(record.u[0]), branch)
    expected = model.simulate(record.u)
    assert np.max(np.abs(out["y_model"] - expected)) <= 1e-6 * np.ptp(expected)
    assert np.array_equal(out["y"], record.y) and np.array_equal(out["u"], record.u)


def test_a_trained_net_runs_as_it_did_after_training(net, tmp_path, capsys):
    model, folder, held_out = net
    assert (
        main(["simulate", str(folder), str(held_out), "--out", str(tmp_path / "p.csv"), "--initial", "descending"]) == 0
    )
    record = load_measurement(held_out)
    expected = model.simulate(record.u, "descending")
    got = read(tmp_path / "p.csv")["y_model"]
    assert np.max(np.abs(got - expected)) <= 1e-4 * np.ptp(expected)
    assert "lstm-narmax net" in capsys.readouterr().out


def test_estimate_finds_the_start_the_record_was_made_from(bundle, tmp_path, capsys):
    t = np.arange(3000) / 100.0
    u = 3.0 + 2.5 * np.sin(2 * np.pi * 0.2 * t) * np.minimum(1.0, t / 10.0)
    model = make_estimator("pi").fit(*(lambda m: (m.u, m.y))(load_measurement(example_path("train")))).model_
    model.reset(float(u[0]), "ascending")
    model.step(float(u.max()))  # the input came down to u[0] from the record's maximum
    y = model.simulate(u)
    data = tmp_path / "made.csv"
    np.savetxt(data, np.column_stack([t, u, y]), delimiter=",", header="t,u,y", comments="")
    assert main(["simulate", str(bundle), str(data), "--out", str(tmp_path / "p.csv"), "--initial", "estimate"]) == 0
    assert "from descending (estimated" in capsys.readouterr().out


def test_a_designed_input_without_y_is_simulated(bundle, tmp_path, capsys):
    t = np.arange(500) / 100.0
    data = tmp_path / "design.csv"
    np.savetxt(data, np.column_stack([t, 3 + np.sin(t)]), delimiter=",", header="t,u", comments="")
    assert main(["simulate", str(bundle), str(data), "--out", str(tmp_path / "p.csv")]) == 0
    assert read(tmp_path / "p.csv").dtype.names == ("t", "u", "y_model")


@pytest.mark.parametrize(
    "case, message",
    [
        ("no_u", r"column\(s\) 'u' missing"),
        ("estimate_without_y", "--initial estimate needs a measured y column"),
        ("not_a_model", "neither a bundle .* nor a trained model"),
        ("out_exists", "already exists"),
    ],
)
def test_bad_input_is_one_line_and_exit_2_and_keeps_the_users_files(bundle, tmp_path, capsys, case, message):
    data = tmp_path / "in.csv"
    columns = "t,x" if case == "no_u" else "t,u"
    np.savetxt(data, np.column_stack([np.arange(20) / 10, np.ones(20)]), delimiter=",", header=columns, comments="")
    out = tmp_path / "p.csv"
    if case == "out_exists":
        out.write_text("precious\n")
    folder = tmp_path if case == "not_a_model" else bundle
    extra = ["--initial", "estimate"] if case == "estimate_without_y" else []
    assert main(["simulate", str(folder), str(data), "--out", str(out), *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert pytest.importorskip("re").search(message, err)
    assert (out.read_text() == "precious\n") if case == "out_exists" else not out.exists()


def test_a_trained_hammerstein_runs_in_onnxruntime_as_it_did_after_training(tmp_path, capsys):
    record = load_measurement(hil_csv(tmp_path, "sines", 1, 40.0, "rate_dependence"))
    trained = train_model("hammerstein", [record], seed=0, epochs=5)
    save_model(trained, tmp_path / "ham", {"model": "hammerstein"})
    held_out = hil_csv(tmp_path, "sines", 2, 40.0, "rate_dependence")
    out = tmp_path / "p.csv"
    assert main(["simulate", str(tmp_path / "ham"), str(held_out), "--out", str(out), "--initial", "ascending"]) == 0
    expected = trained.model.simulate(load_measurement(held_out).u, "ascending")
    assert np.max(np.abs(read(out)["y_model"] - expected)) <= 1e-4 * np.ptp(expected)
    assert "via onnxruntime" in capsys.readouterr().out
