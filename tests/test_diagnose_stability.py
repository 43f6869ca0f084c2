"""``pmactl diagnose --stability``: is the verdict one the rest of the record agrees with?

The plant is an exact Preisach model (weighted play operators) whose output sags under a
payload. In one record the payload is swapped throughout; in the other it is hung on only for
the last 12 % of the record, so all the evidence for a load effect sits where the check leaves
the record out: that verdict must be reported as borderline, the first as holding.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray

from edge.hysteresis.pi import play_outputs
from host.cli import main
from host.data import Measurement
from host.diagnose.stability import diagnose_with_stability

DT = 0.02
SAG_MM_PER_KG = 0.6


def _record(load: NDArray[np.float64], seed: int = 3) -> Measurement:
    rng = np.random.default_rng(seed)
    t = np.arange(load.size, dtype=np.float64) * DT
    u = 3.0 + 2.8 * np.sin(2 * np.pi * t / 8.0 - np.pi / 2) * (0.7 + 0.3 * np.sin(2 * np.pi * t / 53.0))
    thresholds = np.array([0.1, 0.4, 0.8, 1.3])
    y = play_outputs(u, thresholds, u[0] - thresholds) @ np.array([3.0, 2.0, 1.5, 1.0])
    y = y - SAG_MM_PER_KG * load + rng.normal(0.0, 0.02, t.size)
    return Measurement(t, u, y, {"load": load}, source="payload record")


def _swapped_throughout(n: int) -> NDArray[np.float64]:
    return np.repeat([0.0, 2.0, 1.0, 3.0, 0.5, 2.5], -(-n // 6))[:n]


def _hung_on_at_the_end(n: int) -> NDArray[np.float64]:
    return np.where(np.arange(n) >= int(0.88 * n), 3.0, 0.0)


def test_a_load_effect_over_the_whole_record_holds() -> None:
    d = diagnose_with_stability(_record(_swapped_throughout(6000)), progress=False)
    assert d.cause == "load_dependence"
    assert d.confidence["stability"] == {
        "without_last_10%": "load_dependence",
        "without_last_20%": "load_dependence",
        "holds": True,
    }
    assert "holds without the last 10% and 20%" in d.reason


def test_evidence_only_at_the_end_of_the_record_is_reported_as_borderline() -> None:
    d = diagnose_with_stability(_record(_hung_on_at_the_end(6000)), progress=False)
    assert d.cause == "load_dependence"
    stability = d.confidence["stability"]
    assert isinstance(stability, dict)
    assert stability["holds"] is False
    assert stability["without_last_20%"] != d.cause  # the load is constant there: nothing to name
    assert "borderline" in d.reason


def test_the_cli_prints_and_writes_the_stability(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    m = _record(_swapped_throughout(6000))
    csv = tmp_path / "run.csv"
    np.savetxt(csv, np.column_stack([m.t, m.u, m.y, m.extras["load"]]), delimiter=",", header="t,u,y,load", comments="")
    out = tmp_path / "d.json"
    assert main(["diagnose", str(csv), "--stability", "--json", str(out)]) == 0
    assert "stability: holds" in capsys.readouterr().out
    assert json.loads(out.read_text())["confidence"]["stability"]["holds"] is True


def test_a_record_too_short_for_its_folds_once_cut_is_not_checked_rather_than_borderline() -> None:
    # the memory is known from sample 592: the 608 samples after it allow 4 folds of 3 blocks of
    # 50, the 488 left without the last 10 % do not
    d = diagnose_with_stability(_record(_swapped_throughout(1200)), progress=False)
    stability = d.confidence["stability"]
    assert isinstance(stability, dict)
    assert stability["holds"] is None and stability["without_last_20%"] == "not checked"
    assert "could not be checked" in d.reason and "folds" in d.reason and "borderline" not in d.reason


def test_stability_with_a_cross_run_is_refused_in_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    m = _record(_swapped_throughout(1000))
    csv = tmp_path / "run.csv"
    np.savetxt(csv, np.column_stack([m.t, m.u, m.y]), delimiter=",", header="t,u,y", comments="")
    assert main(["diagnose", "--train", str(csv), "--test", str(csv), "--stability"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--stability checks one recording" in err
