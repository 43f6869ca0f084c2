"""``pmactl quantise`` on a net bundle: every net's int8 variants measured under the correction's rule.

A short ``edge record`` recording of the emulated rig and a net trained for a few epochs; the
measured numbers are in models_export/quantise_nets.py and the report, not asserted here (no
timed assertions).
"""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from edge.runtime.bundle import load_bundle
from host.cli import main
from tests.test_net_bundle import rig_config


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("quantnets")
    recording = root / "rec.csv"
    assert main(["edge", "record", "--config", str(rig_config(root, None)), "--protocol",
                 "sines:frequencies=0.2/0.5/1,amplitudes=1/0.5,cycles=2", "--range", "0:6", "--out",
                 str(recording), "--json"]) == 0  # fmt: skip
    store = root / "store"
    assert main(["train", "--model", "lstm-narmax", "--train", str(recording), "--units", "bar,mm",
                 "--epochs", "3", "--save", str(store), "--json"]) == 0  # fmt: skip
    return root, recording, store


def copy_store(store, tmp_path):
    copy = tmp_path / "store"
    shutil.copytree(store, copy, symlinks=True)
    return copy


def test_every_net_is_measured_and_float32_kept_leaves_the_bundle_unchanged(trained, tmp_path, capsys):
    _, recording, store = trained
    copy = copy_store(store, tmp_path)
    before = sorted(p.name for p in (copy / "releases").iterdir())
    capsys.readouterr()
    assert main(["quantise", str(copy), "--calibration", str(recording), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report["nets"]) == {"forward", "inverse"}
    for which in ("forward", "inverse"):
        net = report["nets"][which]
        assert set(net["variants"]) == {"float32", "dynamic_int8", "dynamic_int8_reduce_range", "static_qdq"}
        assert net["variants"]["float32"]["rmse_ratio"] == 1.0 and net["variants"]["float32"]["rmse"] > 0
        assert net["float32_edge_us_per_step_cpu"] <= net["variants"]["float32"]["us_per_step_cpu"]
    if not report["changed"]:  # the measured outcome on this machine: nothing earned its place
        assert sorted(p.name for p in (copy / "releases").iterdir()) == before


def test_a_kept_variant_replaces_the_net_in_a_new_release_that_verifies(trained, tmp_path, capsys, monkeypatch):
    _, recording, store = trained
    copy = copy_store(store, tmp_path)
    before = load_bundle(copy)
    monkeypatch.setattr("models_export.quantise_nets.choose", lambda measured: ("dynamic_int8", []))
    assert main(["quantise", str(copy), "--calibration", str(recording), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["changed"] == ["forward", "inverse"]
    after = load_bundle(copy)  # checksums and the nets' golden vectors, recorded again, replayed
    assert after.release_id != before.release_id
    assert after.net_spec("inverse")["quantisation"]["kept"] == "dynamic_int8"
    assert after.net_paths["inverse"].read_bytes() != before.net_paths["inverse"].read_bytes()
    inverse = after.feedforward("net", 0.01)
    assert inverse.net.choice.evaluator == "onnxruntime"  # a quantised graph is not fused
    target = 35.0 + 15.0 * np.sin(np.linspace(0.0, 6.0, 300))
    inverse.reset()
    assert np.all(np.isfinite(inverse.simulate(target)))
    capsys.readouterr()
    assert main(["quantise", str(copy), "--calibration", str(recording)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "already quantised" in err[0]


def test_a_calibration_recording_at_another_rate_is_one_line(trained, tmp_path, capsys):
    _, recording, store = trained
    fast = tmp_path / "fast.csv"
    rows = np.loadtxt(recording, delimiter=",", skiprows=1)
    rows[:, 0] *= 0.5
    np.savetxt(fast, rows, delimiter=",", header=recording.read_text().splitlines()[0], comments="", fmt="%.9g")
    copy = copy_store(store, tmp_path)
    capsys.readouterr()
    assert main(["quantise", str(copy), "--calibration", str(fast)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "nets step every 10 ms" in err[0]
