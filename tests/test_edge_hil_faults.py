"""HIL faults scheduled from the rig config or the sim:// URL (no Python): every kind is
reachable from ``pmactl edge run`` and ends in SAFE within 3 ticks (a stuck sensor: within its
detection window + 3 ticks), valve vented, the reason in the summary and the event log."""

from __future__ import annotations

import json

import pytest

from edge.runtime.safety import Fault
from edge.runtime.telemetry import read_telemetry
from hil.faults import FAULT_KINDS, TWIN_WATCHED_KINDS
from host.cli import main
from tests.edge_helpers import HIL_RIG, fit_bundle

AT_S = 1.0
PERIOD_S = 0.001
EXPECTED = {
    "estop": (Fault.ESTOP, "e-stop pressed"),
    "dac_nack": (Fault.BUS, "dac write failed"),
    "adc_nack": (Fault.BUS, "adc read failed"),
    "gpio_error": (Fault.BUS, "lines read failed"),
    "sensor_disconnected": (Fault.SENSOR_RANGE, "contraction"),
    "sensor_saturated": (Fault.SENSOR_RANGE, "contraction"),
    "sensor_stuck": (Fault.SENSOR_STUCK, "contraction sensor stuck"),
    "pressure_high": (Fault.OVERPRESSURE, "overpressure"),
}


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    return fit_bundle(tmp_path_factory.mktemp("bundle") / "preisach")


def test_every_fault_kind_is_covered():  # the twin-watched kinds: tests/test_twin.py
    assert set(EXPECTED) | set(TWIN_WATCHED_KINDS) == set(FAULT_KINDS)


def run(tmp_path, capsys, bundle, config_text):
    config, telemetry = tmp_path / "rig.toml", tmp_path / "t.pmt"
    config.write_text(config_text)
    args = ["edge", "run", "--config", str(config), "--bundle", str(bundle), "--duration", "2"]
    code = main([*args, "--telemetry", str(telemetry), "--json"])
    return code, json.loads(capsys.readouterr().out), read_telemetry(telemetry)


@pytest.mark.parametrize("kind", sorted(EXPECTED))
def test_a_fault_from_the_sim_url_ends_safe_in_three_ticks(tmp_path, capsys, bundle, kind):
    text = HIL_RIG.read_text().replace("sim://rig?clock=lockstep", f"sim://rig?clock=lockstep&faults={kind}@{AT_S}")
    code, summary, record = run(tmp_path, capsys, bundle, text)
    fault_kind, reason = EXPECTED[kind]
    t, fault = record.column("t"), record.column("fault")
    first = t[fault > 0][0]
    allowed = 3 * PERIOD_S + (0.3 if kind == "sensor_stuck" else 0.0)  # the stuck window
    assert AT_S - PERIOD_S <= first < AT_S + allowed, (kind, first)
    assert code == 1 and len(summary["faults"]) == 1 and reason in summary["faults"][0]
    assert set(fault[fault > 0]) == {fault_kind.value} and record.column("u_bar")[-1] == 0.0
    assert record.column("valve_enable")[-1] == 0.0 and record.column("state")[-1] == 3  # SAFE
    events = record.events
    assert [e["kind"] for e in events][-2:] == ["fault", "end"] and events[-2]["text"] == summary["faults"][0]
    assert events[-2]["code"] == fault_kind.value and events[-1]["summary"]["faults"] == summary["faults"]


def test_faults_from_the_config_table_and_a_bad_one_is_one_line(tmp_path, capsys, bundle):
    text = HIL_RIG.read_text().replace("hz = 1_000_000", 'hz = 1_000_000\nfaults = ["estop@0.5"]', 1)
    code, summary, record = run(tmp_path, capsys, bundle, text)
    assert code == 1 and summary["faults"] == ["e-stop pressed"] and summary["ticks"] < 510
    bad = HIL_RIG.read_text().replace("sim://rig?clock=lockstep", "sim://rig?clock=lockstep&faults=meteor@1")
    (tmp_path / "bad.toml").write_text(bad)
    assert (
        main(["edge", "run", "--config", str(tmp_path / "bad.toml"), "--bundle", str(bundle), "--duration", "1"]) == 2
    )
    err = capsys.readouterr().err.strip()
    assert "HIL fault 'meteor@1' unknown; write KIND@SECONDS" in err and err.count("\n") == 0
