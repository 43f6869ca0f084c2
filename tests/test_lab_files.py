"""Measurement files as labs write them, through the CLI: delimiters, decimal commas, own column
names, units, a time column in milliseconds; and the warnings a user needs before trusting a score."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest

from host.cli import main
from host.cli.outputs import strict_json
from host.data import load_measurement
from host.data_format import ReadOptions, header_unit
from host.examples import example_path


def lab_copy(source, path, header, delimiter=";", decimal_comma=True, time_scale=1.0):
    """The example recording rewritten as a lab might export it."""
    m = load_measurement(source)
    with path.open("w") as handle:
        handle.write(delimiter.join(header) + "\n")
        for t, u, y in zip(m.t * time_scale, m.u, m.y):
            cells = [f"{t:.6g}", f"{u:.6g}", f"{y:.6g}"]
            handle.write(delimiter.join(c.replace(".", ",") if decimal_comma else c for c in cells) + "\n")
    return path


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    root = tmp_path_factory.mktemp("lab")
    header = ["time_s", "pressure_bar", "length_mm"]
    return {
        "train": lab_copy(example_path("train"), root / "train.csv", header),
        "test": lab_copy(example_path("test"), root / "test.csv", header),
        "ms": lab_copy(example_path("train"), root / "ms.csv", ["time", "pressure", "length"], time_scale=1e3),
        "root": root,
    }


COLUMNS = ["--columns", "t=time_s,u=pressure_bar,y=length_mm"]


def test_a_semicolon_file_with_decimal_commas_fits_with_one_columns_option(lab, capsys):
    assert main(["fit", "--model", "preisach", "--train", str(lab["train"]), "--test", str(lab["test"]), *COLUMNS]) == 0
    out = capsys.readouterr().out
    assert "RMSE [mm]" in out
    capsys.readouterr()
    plain = ["fit", "--model", "preisach", "--train", str(example_path("train")), "--test", str(example_path("test"))]
    assert main([*plain, "--json"]) == 0
    reference = json.loads(capsys.readouterr().out)["tests"][0]["rmse"]
    assert main(["fit", "--model", "preisach", "--train", str(lab["train"]), "--test", str(lab["test"]), *COLUMNS,
                 "--json"]) == 0  # fmt: skip
    report = json.loads(capsys.readouterr().out)
    assert report["units"] == {"u": "bar", "y": "mm"}
    assert report["tests"][0]["rmse"] == pytest.approx(reference, rel=1e-3)


def test_a_tab_separated_file_is_read_too(tmp_path):
    path = lab_copy(example_path("test"), tmp_path / "tab.tsv", ["t", "u [bar]", "y (mm)"], "\t", False)
    m = load_measurement(path, options=ReadOptions(columns={"u": "u [bar]", "y": "y (mm)"}))
    assert len(m) == len(load_measurement(example_path("test"))) and m.units == {"u": "bar", "y": "mm", "t": "s"}


def test_a_millisecond_time_column_is_refused_with_the_fix(lab, capsys):
    args = ["fit", "--model", "pi", "--train", str(lab["ms"]), "--columns", "t=time,u=pressure,y=length"]
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "looks like" in err and "--time-unit ms" in err and len(err.strip().splitlines()) == 1
    assert main([*args, "--time-unit", "ms"]) == 0


def test_a_time_header_in_ms_is_converted_to_seconds(tmp_path):
    path = lab_copy(example_path("test"), tmp_path / "ms.csv", ["time_ms", "u", "y"], ",", False, 1e3)
    m = load_measurement(path, options=ReadOptions(columns={"t": "time_ms"}))
    assert m.dt == pytest.approx(load_measurement(example_path("test")).dt)


def test_a_mapped_column_that_is_not_in_the_file_is_named(lab, capsys):
    assert (
        main(["fit", "--model", "pi", "--train", str(lab["train"]), "--columns", "t=time_s,u=p_bar,y=length_mm"]) == 2
    )
    assert "u=p_bar: no such column; found ['time_s', 'pressure_bar', 'length_mm']" in capsys.readouterr().err


@pytest.mark.parametrize("name, unit", [("time_s", "s"), ("length [mm]", "mm"), ("force (N)", "N"),
                                        ("load_cell", None), ("u", None), ("p_kPa", "kPa")])  # fmt: skip
def test_header_units(name, unit):
    assert header_unit(name) == unit


def test_fit_warns_when_the_test_input_leaves_the_training_range(tmp_path, capsys):
    m = load_measurement(example_path("train"))
    low = m.u <= 2.0
    narrow = tmp_path / "narrow.csv"
    rows = np.column_stack([m.t[: low.sum()], m.u[low], m.y[low]])
    np.savetxt(narrow, rows, delimiter=",", header="t,u_bar,y_mm", comments="")
    assert main(["fit", "--model", "pi", "--train", str(narrow), "--test", str(example_path("test"))]) == 0
    err = capsys.readouterr().err
    assert "of the test input" in err and "outside the training range 0..2 bar" in err


def test_fit_save_without_units_warns_and_with_units_does_not(tmp_path, capsys):
    assert main(["fit", "--model", "pi", "--train", str(example_path("train")), "--save", str(tmp_path / "a")]) == 0
    assert "--save without units" in capsys.readouterr().err
    assert main(["fit", "--model", "pi", "--train", str(example_path("train")), "--units", "bar,mm",
                 "--save", str(tmp_path / "b")]) == 0  # fmt: skip
    assert "units" not in capsys.readouterr().err


def test_fit_plot_draws_the_users_own_loops(lab, tmp_path, capsys):
    figure = tmp_path / "loops.png"
    assert main(["fit", "--model", "pi", "--train", str(lab["train"]), "--test", str(lab["test"]), *COLUMNS,
                 "--plot", str(figure)]) == 0  # fmt: skip
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["fit", "--model", "pi", "--train", str(lab["train"]), *COLUMNS, "--plot", str(figure)]) == 2


def test_strict_json_writes_null_for_non_finite_numbers():
    text = strict_json({"a": -math.inf, "b": [np.float64("nan"), 1.5], "c": np.int64(3)})
    assert json.loads(text) == {"a": None, "b": [None, 1.5], "c": 3}


def test_a_closed_pipe_is_quiet(tmp_path):
    bundle = tmp_path / "b"
    assert main(["fit", "--model", "pi", "--train", str(example_path("train")), "--units", "bar,mm",
                 "--save", str(bundle)]) == 0  # fmt: skip
    reader_closes = f"{sys.executable} -m host.cli bundle inspect {bundle} | head -c 1"
    done = subprocess.run(["bash", "-c", reader_closes], capture_output=True, text=True, timeout=120)
    assert done.stderr == ""


def test_train_warns_before_training_when_the_test_input_leaves_the_training_range(tmp_path, capsys, monkeypatch):
    from edge.errors import DataError

    def stop(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise DataError("training reached")

    monkeypatch.setattr("host.train.train_model", stop)
    m = load_measurement(example_path("train"))
    low = m.u <= 2.0
    narrow = tmp_path / "narrow.csv"
    np.savetxt(narrow, np.column_stack([m.t[: low.sum()], m.u[low], m.y[low]]), delimiter=",",
               header="t,u_bar,y_mm", comments="")  # fmt: skip
    argv = ["train", "--model", "hammerstein", "--train", str(narrow), "--test", str(example_path("test"))]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "outside the training range 0..2 bar" in err and "training reached" in err


def test_a_glob_of_runs_is_expanded_and_an_empty_one_named(lab, tmp_path, capsys):
    for k in range(2):
        (tmp_path / f"test{k}.csv").write_bytes(lab["test"].read_bytes())
    argv = ["fit", "--model", "pi", "--train", str(lab["train"]), *COLUMNS, "--json"]
    assert main([*argv, "--test", str(tmp_path / "test*.csv")]) == 0
    assert [t["file"] for t in json.loads(capsys.readouterr().out)["tests"]] == ["test0.csv", "test1.csv"]
    assert main([*argv, "--test", str(tmp_path / "nothing*.csv")]) == 2
    assert "no file matches the pattern" in capsys.readouterr().err
