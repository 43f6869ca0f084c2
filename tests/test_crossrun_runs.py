"""Cross-run diagnosis over lists of runs: identify on every training run, judge every test run."""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

from hil.record import record
from host.cli import main
from host.data import Measurement, load_measurement
from host.diagnose.crossrun_runs import cross_runs

RUN_SAMPLES = 200  # 2 s at 100 Hz: one short run, as labs record them


def short_runs(seed: int, count: int = 10, effect: str = "none", dy: float = 0.0) -> list[Measurement]:
    """One HIL recording cut into ``count`` runs, each restarting ``t`` at 0; ``dy`` added to y."""
    rec = record("mixed", seed, count * RUN_SAMPLES / 100.0, effect)
    out = []
    for i in range(count):
        sl = slice(i * RUN_SAMPLES, (i + 1) * RUN_SAMPLES)
        out.append(Measurement(rec.t[sl] - rec.t[sl][0], rec.u[sl], rec.y[sl] + dy, {}, f"seed{seed}/run{i:02d}.csv"))
    return out


@pytest.fixture(scope="module")
def train() -> list[Measurement]:
    return short_runs(1)


def test_an_offset_between_sessions_is_named_with_a_line_per_test_run(train):
    test = short_runs(2, dy=3.0)
    result = cross_runs(train, test)
    assert result.cause == "session_drift", result.reason
    assert result.corrections["session_drift"].interval[0] > 0
    assert [line.name for line in result.per_run] == [f"run{i:02d}.csv" for i in range(10)]
    fixed = sum(line.corrected_rmse < 0.5 * line.model_rmse for line in result.per_run)
    assert fixed >= 8, result.per_run
    assert "whole runs" in result.holdout


def test_an_unchanged_session_names_nothing(train):
    result = cross_runs(train, short_runs(2))
    assert result.cause == "none", result.reason


def test_a_dead_time_in_the_second_session_is_named(train):
    result = cross_runs(train, short_runs(3, effect="transport_delay"))
    assert result.cause == "transport_delay", result.reason


def write_runs(runs: list[Measurement], folder: Path, header: str = "t,u,y") -> list[Path]:
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for m in runs:
        path = folder / Path(m.source).name
        np.savetxt(path, np.c_[m.t, m.u, m.y], delimiter=",", header=header, comments="", fmt="%.6f")
        paths.append(path)
    return paths


def test_the_cli_takes_globs_on_both_sides_and_writes_a_report_a_person_reads(tmp_path, train, capsys):
    write_runs(train, tmp_path / "day1")
    write_runs(short_runs(2, dy=3.0), tmp_path / "day2")
    out, report = tmp_path / "x.json", tmp_path / "report"
    args = ["diagnose", "--train", str(tmp_path / "day1" / "*.csv"), "--test", str(tmp_path / "day2" / "run0*.csv")]
    assert main([*args, "--units", "u=bar,y=mm", "--json", str(out), "--report", str(report)]) == 0
    printed = capsys.readouterr().out
    assert "10 runs (run00.csv ...) -> 10 runs (run00.csv ...): cause session_drift" in printed
    assert len(re.findall(r"run0\d\.csv +200 samples", printed)) == 10
    payload = json.loads(out.read_text())
    assert payload["cause"] == "session_drift" and payload["interval_90"][0] > 0
    assert len(payload["per_run"]) == 10
    text = (report / "report.md").read_text()
    assert "**Verdict: `session_drift`.**" in text
    assert "| run07.csv | 200 |" in text  # the per-run table
    assert "gain [mm]" in text and "RMS error [mm]" in text  # the units the user gave
    assert not re.search(r"\d\.\d{7,}", text), "a long float in the report"
    assert "{" not in text, "a raw dict or JSON in the report"
    assert (report / "runs.png").stat().st_size > 10_000
    assert (report / "failure_by_run.png").stat().st_size > 10_000


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_bad_lists_are_refused_in_one_line(tmp_path, train, capsys):
    day1 = write_runs(train[:4], tmp_path / "day1")
    day2 = write_runs(short_runs(2, count=4), tmp_path / "day2")
    cases = {
        "no file matches": ["--train", str(tmp_path / "nope*.csv"), "--test", str(day2[0])],
        "is a folder": ["--train", str(tmp_path / "day*"), "--test", str(day2[0])],
        "both --train and --test": ["--train", str(tmp_path / "day1" / "*.csv"), "--test", str(day1[0])],
        "--method v2 identifies on one": ["--train", str(day1[0]), "--train", str(day1[1]), "--test", str(day2[0])]
        + ["--method", "v2"],
        "writes no report; add --method v3": ["--train", str(day1[0]), "--test", str(day2[0]), "--report", "r"]
        + ["--method", "v2"],
    }
    for expected, args in cases.items():
        assert main(["diagnose", *args]) == 2, expected
        assert expected in _one_error_line(capsys)


def test_mixed_units_are_refused(tmp_path, train, capsys):
    write_runs(train[:3], tmp_path / "mm", header="t,u [bar],y [mm]")
    write_runs(short_runs(2, count=3), tmp_path / "m", header="t,u [bar],y [m]")
    code = main(["diagnose", "--train", str(tmp_path / "mm" / "*.csv"), "--test", str(tmp_path / "m" / "*.csv")])
    assert code == 2
    line = _one_error_line(capsys)
    assert "mixed units of y" in line and "mm" in line and "--units" in line


def test_a_test_run_shorter_than_the_models_memory_is_refused(tmp_path, train, capsys):
    write_runs(train, tmp_path / "day1")
    stub = short_runs(2, count=1)[0]
    short = Measurement(stub.t[:40], stub.u[:40], stub.y[:40], {}, "day2/stub.csv")
    write_runs([*short_runs(2, count=3), short], tmp_path / "day2")
    assert main(["diagnose", "--train", str(tmp_path / "day1" / "*.csv"), "--test", str(tmp_path / "day2" / "*")]) == 2
    line = _one_error_line(capsys)
    assert "stub.csv: test run of 40 samples is shorter than the model's memory" in line


def _campaign(root: Path, name: str) -> list[Measurement]:
    paths = sorted((root / "pam_muscle_sensory").glob(f"{name}*/*.csv"))
    if not paths:
        pytest.skip(f"no {name} campaign under {root}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # irregular sampling is resampled, with a warning per file
        return [load_measurement(p) for p in paths]


def test_the_second_muscle_campaign_differs_from_the_first(shared_data):
    # the data README: the 31-03 campaign's pressure plateaus are 1.6-3 psi higher for the same
    # setting while peak contraction matches, so the pressure-to-contraction relation moved
    result = cross_runs(_campaign(shared_data, "18-03"), _campaign(shared_data, "31-03"))
    assert result.cause in ("session_drift", "input_drift", "gain_change"), result.reason
    assert result.corrections[result.cause].interval[0] > 0
    assert len(result.per_run) == 38


def test_one_short_training_run_is_judged_by_the_runs_method_instead_of_refused(tmp_path, train, capsys):
    (a,) = write_runs(train[:1], tmp_path / "day1")  # 200 samples: too short for v2's cross-run
    tests = write_runs(short_runs(2, count=3, dy=3.0), tmp_path / "day2")
    assert main(["diagnose", "--train", str(a), "--test", str(tmp_path / "day2" / "*.csv")]) == 0
    printed = capsys.readouterr().out
    assert "run00.csv -> 3 runs (run00.csv ...): cause" in printed
    assert all(f"{p.name} " in printed for p in tests)
