"""Cross-run diagnosis: a model identified on one recording, checked on another."""

from __future__ import annotations

import json

import numpy as np
import pytest

from hil.record import record
from host.cli import main
from host.data import Measurement
from host.diagnose.crossrun import cross_run


def hil(seed: int, effect: str = "none", duration_s: float = 100.0) -> Measurement:
    rec = record("mixed", seed, duration_s, effect)
    return Measurement(rec.t, rec.u, rec.y, source=f"hil {seed} {effect}")


@pytest.fixture(scope="module")
def train() -> Measurement:
    return hil(1)


def shifted(m: Measurement, gain: float, offset: float) -> Measurement:
    middle = float(np.mean(m.y))
    return Measurement(m.t, m.u, middle + gain * (m.y - middle) + offset, source=f"gain {gain} offset {offset}")


@pytest.mark.parametrize(
    "gain, offset, expected", [(1.0, 3.0, "session_drift"), (0.85, 0.0, "gain_change")], ids=["offset", "gain"]
)
def test_a_session_change_is_named(train, gain, offset, expected):
    test = shifted(hil(2), gain, offset)
    (result,) = cross_run(train, [test], progress=False)
    assert result.cause == expected, (result.reason, result.scores)


def test_a_dead_time_in_the_second_session_is_named(train):
    (result,) = cross_run(train, [hil(3, "transport_delay")], progress=False)
    assert result.cause == "transport_delay", (result.reason, result.scores)


def test_the_cli_takes_train_and_repeated_tests(tmp_path, train, capsys):
    def write(m: Measurement, name: str):
        path = tmp_path / name
        np.savetxt(path, np.c_[m.t, m.u, m.y], delimiter=",", header="t,u,y", comments="", fmt="%.6f")
        return path

    a, b = write(train, "a.csv"), write(shifted(hil(2), 1.0, 3.0), "b.csv")
    out = tmp_path / "x.json"
    assert main(["diagnose", "--train", str(a), "--test", str(b), "--test", str(b), "--json", str(out)]) == 0
    results = json.loads(out.read_text())
    assert [r["cause"] for r in results] == ["session_drift", "session_drift"]
    assert "a.csv -> b.csv: cause session_drift" in capsys.readouterr().out
    assert main(["diagnose", "--train", str(a)]) == 2
    assert "--test" in capsys.readouterr().err


def test_a_test_record_whose_input_reaches_its_range_ends_late_is_judged_from_an_assumed_state(train):
    # a ramp-up of the second session: its extremes come in the last samples (before: judged on
    # a tail of a few samples, or an IndexError when the tail was two samples)
    test = hil(2)
    middle = float(np.median(test.u))
    u = middle + (0.3 + 0.6 * test.t / test.t[-1]) * (test.u - middle)
    u[-2:] = float(test.u.min()), float(test.u.max())  # the range's ends: the last two samples
    late = Measurement(test.t, u, test.y, source="ramped session")
    (result,) = cross_run(train, [late], progress=False)
    assert any("rose from the record's minimum" in note for note in result.notes)
    assert np.isfinite(result.test_rmse)
