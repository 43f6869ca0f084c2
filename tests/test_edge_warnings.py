"""Warnings that catch a wrong model: a reference beyond the bundle's reach before arming, and
feedback that carries a steady part of the command while running (the bundle of another
muscle), as a warning line and event or, when the config asks, a fault."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from edge.runtime.mismatch import MismatchMonitor
from edge.runtime.telemetry_read import read_telemetry
from host.cli import main
from host.examples import example_path
from tests.edge_helpers import HIL_RIG, SEED_000_SINE


def bundle_for_pressure_factor(tmp_path: Path, factor: float, capsys: pytest.CaptureFixture[str]) -> Path:
    """A bundle fitted on the example recording with its pressure scaled by ``factor``: the model
    of a muscle that needs ``factor`` times the pressure of the emulated one."""
    data = np.genfromtxt(example_path("train"), delimiter=",", names=True)
    data["u"] *= factor
    csv = tmp_path / f"scaled-{factor:g}.csv"
    names = list(data.dtype.names or ())
    np.savetxt(csv, np.column_stack([data[n] for n in names]), delimiter=",", header=",".join(names), comments="")
    bundle = tmp_path / f"bundle-{factor:g}"
    assert main(["fit", "--model", "preisach", "--train", str(csv), "--units", "bar,mm", "--save", str(bundle)]) == 0
    capsys.readouterr()
    return bundle


def edge_run(bundle: Path, *extra: str, config: Path = HIL_RIG) -> list[str]:
    return ["edge", "run", "--config", str(config), "--bundle", str(bundle), *extra]


def test_a_reference_beyond_reach_is_one_warning_line_before_arming(tmp_path, capsys):
    bundle = bundle_for_pressure_factor(tmp_path, 1.0, capsys)
    assert main(edge_run(bundle, "--reference", "sine:amplitude=50,offset=70", "--duration", "2")) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "warning: the reference asks 20.0..120.0 mm but the bundle reaches only" in err[0]
    assert main(edge_run(bundle, "--reference", "sine:amplitude=20,offset=30", "--duration", "2", "--json")) == 0
    captured = capsys.readouterr()
    assert captured.err == "" and json.loads(captured.out)["warnings"] == []


@pytest.mark.parametrize("factor", [2.0, 0.5, 1.5])
def test_a_bundle_of_another_muscle_is_named_while_running(tmp_path, capsys, factor):
    bundle = bundle_for_pressure_factor(tmp_path, factor, capsys)
    telemetry = tmp_path / "run.pmt"
    args = edge_run(bundle, "--reference", "sine:amplitude=20,offset=30", "--duration", "15", "--json")
    assert main(args + ["--telemetry", str(telemetry)]) == 0
    captured = capsys.readouterr()
    lines = [line for line in captured.err.strip().splitlines() if "forward twin" not in line]  # it warns too
    assert len(lines) == 1 and "the bundle may not match this rig" in lines[0]
    assert ("too hard" if factor > 1 else "too little") in lines[0]
    events = [e for e in read_telemetry(telemetry).events if e["kind"] == "warning" and "twin" not in str(e["text"])]
    assert len(events) == 1 and "may not match" in str(events[0]["text"])
    assert json.loads(captured.out)["faults"] == []


def test_the_matching_bundle_is_not_warned_about(tmp_path, capsys):
    bundle = bundle_for_pressure_factor(tmp_path, 1.0, capsys)
    args = edge_run(bundle, "--reference", SEED_000_SINE, "--duration", "25", "--settle", "5", "--json")
    assert main(args) == 0
    assert "may not match" not in capsys.readouterr().err


def test_a_mismatch_can_be_a_fault(tmp_path, capsys):
    bundle = bundle_for_pressure_factor(tmp_path, 2.0, capsys)
    config = tmp_path / "rig.toml"
    config.write_text(HIL_RIG.read_text().replace("[safety]\n", "[safety]\nmismatch_fault = true\n"))
    args = edge_run(bundle, "--reference", "sine:amplitude=20,offset=30", "--duration", "15", config=config)
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "FAULT: the bundle may not match this rig" in err and "(valve vented)" in err


def test_the_monitor_averages_over_whole_windows():
    monitor = MismatchMonitor(limit=0.3, window_s=1.0)
    texts = [monitor.add(i * 0.01, 2.0, 1.0 if i % 2 else -0.2) for i in range(300)]  # 0.4 of 2.4: within
    assert not any(texts)
    texts = [monitor.add(3.0 + i * 0.01, 3.0, -1.2) for i in range(300)]  # -1.2 of 1.8
    assert sum(t is not None for t in texts) == 1 and "-67% of the command" in next(t for t in texts if t)
