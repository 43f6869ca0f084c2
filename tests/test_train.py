"""Training the neural models: reproducible, early-stopped, clear errors, the CLI's JSON contract."""

from __future__ import annotations

import json

import numpy as np
import pytest

from edge.errors import DataError
from host.cli import main
from host.data import load_measurement
from host.train import score_model, train_model
from tests.neural_data import hil_csv


@pytest.fixture(scope="module")
def rate_records(tmp_path_factory):
    root = tmp_path_factory.mktemp("rate")
    return hil_csv(root, "sines", 1, 40.0, "rate_dependence"), hil_csv(root, "sines", 2, 40.0, "rate_dependence")


@pytest.mark.parametrize("kind", ["hammerstein", "lstm-narmax"])
def test_the_same_seed_gives_the_same_model(rate_records, kind):
    record = load_measurement(rate_records[0])
    first = train_model(kind, [record], seed=3, epochs=3).model
    again = train_model(kind, [record], seed=3, epochs=3).model
    u = record.u[:500]
    assert np.array_equal(first.simulate(u, "descending"), again.simulate(u, "descending"))


def test_a_different_seed_gives_a_different_lstm(rate_records):
    record = load_measurement(rate_records[0])
    u = record.u[:500]
    a = train_model("lstm-narmax", [record], seed=1, epochs=3).model.simulate(u, "descending")
    b = train_model("lstm-narmax", [record], seed=2, epochs=3).model.simulate(u, "descending")
    assert not np.array_equal(a, b)


def test_early_stopping_keeps_the_best_epoch_on_the_held_out_tail(rate_records):
    trained = train_model("lstm-narmax", [load_measurement(rate_records[0])], seed=0, epochs=6)
    rows = trained.model.curve.rows
    assert len(rows) >= 2 and trained.tail_start > trained.memory_start
    assert all(np.isfinite(r[3]) for r in rows)


def test_data_too_short_to_train_on_is_one_clear_error(rate_records):
    short = load_measurement(rate_records[0]).slice(0, 300)
    with pytest.raises(DataError, match="too short to train on: .* need at least 400"):
        train_model("hammerstein", [short])


def test_the_cli_prints_fits_json_plus_mae_and_time_per_run(rate_records, tmp_path, capsys):
    train, test = rate_records
    code = main(
        [
            "train",
            "--model",
            "hammerstein",
            "--train",
            str(train),
            "--test",
            str(test),
            "--epochs",
            "3",
            "--json",
            "--save",
            str(tmp_path / "ham"),
        ]
    )
    assert code == 0
    record = json.loads(capsys.readouterr().out)
    assert set(record) == {"model", "fit_seconds", "tests", "bundle"} and record["model"] == "hammerstein"
    [result] = record["tests"]
    assert set(result) == {"file", "rmse", "rmse_pct_pp", "max_error", "mae", "ms_per_run"}
    assert 0 < result["mae"] <= result["rmse"] <= result["max_error"] and result["ms_per_run"] > 0
    saved = json.loads((tmp_path / "ham" / "current" / "manifest.json").read_text())
    assert saved["nets"]["forward"]["opset"] >= 18 and saved["nets"]["forward"]["model"] == "hammerstein"


def test_the_cli_refuses_short_data_with_exit_2(tmp_path, capsys):
    path = tmp_path / "short.csv"
    path.write_text("t,u,y\n" + "".join(f"{k * 0.01},{np.sin(k / 10)},{np.sin(k / 10)}\n" for k in range(200)))
    assert main(["train", "--model", "lstm-narmax", "--train", str(path)]) == 2
    assert "too short to train on" in capsys.readouterr().err


def test_the_correction_needs_a_bundle(rate_records, capsys):
    assert main(["train", "--model", "correction", "--train", str(rate_records[0])]) == 2
    assert "needs --bundle DIR" in capsys.readouterr().err


@pytest.mark.slow
def test_lstm_narmax_learns_what_its_operator_misses(tmp_path):
    """Rate dependence (120 s, train and test plants of different seeds): the trained net beats
    its own rate-independent operator held out by a clear margin."""
    from host.evaluate import predict_with_candidates

    train, test = (load_measurement(hil_csv(tmp_path, "sines", seed, 120.0, "rate_dependence")) for seed in (1, 2))
    trained = train_model("lstm-narmax", [train])
    [result] = score_model(trained.model, [test])
    alone = predict_with_candidates(trained.model.operator.operator.simulate, test.u, test.y)
    assert result.prediction.score.rmse < 0.8 * alone.score.rmse


def test_zero_epochs_is_refused(rate_records, capsys):
    assert main(["train", "--model", "lstm-narmax", "--train", str(rate_records[0]), "--epochs", "0"]) == 2
    assert "--epochs 0 must be at least 1" in capsys.readouterr().err


@pytest.fixture
def no_training(monkeypatch):
    """Training fails the test if it starts: these checks must come before any of it."""

    def refuse(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("training started before --save was checked")

    monkeypatch.setattr("host.train.train_model", refuse)
    monkeypatch.setattr("host.train.correction.train_correction_into", refuse)


def test_save_under_a_missing_folder_is_refused_before_training_and_creates_nothing(
    rate_records, tmp_path, capsys, no_training
):
    target = tmp_path / "typo" / "models" / "ham"
    assert main(["train", "--model", "hammerstein", "--train", str(rate_records[0]), "--save", str(target)]) == 2
    err = capsys.readouterr().err
    assert "does not exist" in err and "mkdir -p" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "typo").exists()


def test_save_into_a_folder_holding_a_model_is_refused_before_training_and_keeps_it(
    rate_records, tmp_path, capsys, no_training
):
    old = tmp_path / "ham"
    old.mkdir()
    (old / "model.json").write_text('{"kind": "earlier"}\n')
    (old / "step.onnx").write_bytes(b"earlier")
    # an earlier pmactl's model folder: --save writes a bundle store now (tests/test_net_bundle*.py)
    assert main(["train", "--model", "hammerstein", "--train", str(rate_records[0]), "--save", str(old)]) == 2
    err = capsys.readouterr().err
    assert "not a pmactl bundle" in err and "choose a new or empty directory" in err
    assert (old / "model.json").read_text() == '{"kind": "earlier"}\n'
    assert (old / "step.onnx").read_bytes() == b"earlier"


def test_correction_save_is_checked_before_the_bundle_is_changed(rate_records, tmp_path, capsys, no_training):
    target = tmp_path / "missing" / "curve"
    code = main(
        ["train", "--model", "correction", "--train", str(rate_records[0]), "--bundle", str(tmp_path / "b"),
         "--save", str(target)]
    )  # fmt: skip
    assert code == 2 and "does not exist" in capsys.readouterr().err
