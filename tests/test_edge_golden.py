"""Golden test: a 25 s lockstep run gives the same telemetry as the edge runtime before the v2
redesign (tests/data/edge_golden, captured from commit 4df3193 by capture.py there: every
100th row, column statistics and the summary, with the bundle that ran)."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from edge.runtime.config import config_from_dict
from edge.runtime.telemetry import read_telemetry
from tests.edge_helpers import HIL_RIG, runtime

GOLDEN = Path(__file__).parent / "data" / "edge_golden"
COLUMNS = ("t", "reference_mm", "contraction_mm", "pressure_bar", "u_ff_bar", "u_nn_bar", "u_fb_bar", "u_bar",
           "state", "fault", "lateness_us")  # fmt: skip
ADS1015_LSB_MM = 4.096 / 2048 * 48.484848  # one code of the 12-bit converter, in mm of contraction


@pytest.fixture(scope="module")
def golden():
    return json.loads((GOLDEN / "golden_25s.json").read_text())


def pre_v2_read_order():
    """The shipped HIL config as the old runtime read it: no pipelining, contraction converted
    first (the emulator's noise draws then come in the same order)."""
    raw = tomllib.loads(HIL_RIG.read_text())
    raw["devices"]["adc"]["pipeline"] = False
    channels = raw["channels"]
    raw["channels"] = {"contraction": channels.pop("contraction"), **channels}
    return config_from_dict(raw, str(HIL_RIG))


def run(tmp_path, name, config, feedforward):
    path = tmp_path / f"{name}.pmt"
    summary = runtime(GOLDEN / "bundle", config=config, feedforward=feedforward, telemetry_path=path, settle_s=5.0)
    return summary.run(25.0).as_dict(), read_telemetry(path)


@pytest.mark.parametrize("controller", ["feedforward", "pid"])
def test_the_same_rig_read_the_same_way_gives_the_same_telemetry_to_the_bit(tmp_path, golden, controller):
    summary, record = run(tmp_path, controller, pre_v2_read_order(), controller == "feedforward")
    expected = golden[controller]
    assert len(record.rows) == expected["summary"]["ticks"] == 25_000
    for key in ("rms_error", "mean_abs_error", "max_error", "scored_ticks", "faults"):
        assert summary[key] == expected["summary"][key], key
    for column in COLUMNS:
        values = record.column(column)
        assert np.array_equal(values[:: expected["decimation"]], np.array(expected["decimated"][column])), column
        stats = expected["stats"][column]
        assert values.mean() == pytest.approx(stats["mean"], rel=1e-12, abs=1e-12), column
        assert (values.min(), values.max()) == (stats["min"], stats["max"]), column


def test_the_shipped_pipelined_config_tracks_the_same_within_one_converter_step(tmp_path, golden):
    """Pipelining and reading pressure first change which noise sample lands where; the
    emulator samples a conversion when it is collected, so the loop is otherwise the same."""
    from tests.edge_helpers import rig_config

    summary, record = run(tmp_path, "shipped", rig_config(), True)
    expected = golden["feedforward"]
    assert summary["faults"] == [] and len(record.rows) == 25_000
    assert summary["rms_error"] == pytest.approx(expected["summary"]["rms_error"], rel=0.01)
    step = expected["decimation"]
    y = record.column("contraction_mm")[::step] - np.array(expected["decimated"]["contraction_mm"])
    u = record.column("u_bar")[::step] - np.array(expected["decimated"]["u_bar"])
    assert np.max(np.abs(y)) <= 2.5 * ADS1015_LSB_MM and np.sqrt(np.mean(y**2)) <= ADS1015_LSB_MM
    assert np.max(np.abs(u)) < 0.02  # bar
