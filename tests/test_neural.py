"""The ONNX correction path: real onnxruntime sessions on models built here, checked against the
manifest, recurrent state carried and reset, broken output caught by the supervisor."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from edge.control.neural import NeuralCorrection
from edge.control.pid import PIDGains
from edge.control.tick import Controller, Readings, ScratchFrame
from edge.errors import BundleError
from edge.runtime.bundle import load_bundle
from edge.runtime.safety import Fault, Supervisor
from edge.runtime.telemetry import read_telemetry
from models_export.bundle import add_correction
from tests.edge_helpers import fit_bundle, rig_config, runtime
from tests.onnx_models import mlp, nan_model, rnn

FEATURES = ["reference_mm", "feedforward_bar"]
SPEC = {"features": FEATURES, "input": "features", "output": "correction_bar"}


def values(reference: float, feedforward: float) -> tuple[float, ...]:
    return (reference, 0.0, feedforward, 0.0, 0.0, 0.0)


def test_the_session_computes_what_the_network_does(tmp_path):
    path, forward = mlp(tmp_path / "bp.onnx")  # Ai2019's 2-5-10-1 BP net
    correction = NeuralCorrection(path, SPEC)
    rng = np.random.default_rng(3)
    for x in rng.normal(0, 2, (200, 2)):
        assert correction.step(values(*x)) == pytest.approx(forward(x), abs=1e-5)


def test_recurrent_state_is_carried_between_ticks_and_zeroed_on_arm(tmp_path):
    path, step = rnn(tmp_path / "rnn.onnx", hidden=4)
    spec = {**SPEC, "state": {"input": "h_in", "output": "h_out", "size": 4}}
    correction = NeuralCorrection(path, spec)
    xs = np.random.default_rng(4).normal(0, 1, (50, 2))
    h = np.zeros((1, 4), np.float32)
    first = []
    for x in xs:
        expected, h = step(x, h)
        first.append(correction.step(values(*x)))
        assert first[-1] == pytest.approx(expected, abs=1e-5)
    controller = Controller(lambda t: 0.0, PIDGains(kp=0.0), correction=correction)
    controller.arm(Readings(0.0))  # re-arm: the sequence starts again from a zero state
    again = [correction.step(values(*x)) for x in xs]
    assert again == pytest.approx(first, abs=1e-6)


@pytest.mark.parametrize(
    "change, message",
    [
        ({"input": "x"}, r"model inputs \['features'\] do not match the manifest's \['x'\]"),
        ({"output": "y"}, r"model has no output \['y'\]"),
        ({"features": ["reference_mm"]}, r"input 'features' is tensor\(float\) \['batch', 2\], the manifest needs"),
        ({"features": ["reference_mm", "speed"]}, r"correction features \['speed'\] not usable"),
        (
            {"state": {"input": "h_in", "output": "h_out", "size": 4}},
            r"do not match the manifest's \['features', 'h_in'\]",
        ),
    ],
)
def test_a_model_that_does_not_match_the_manifest_is_refused(tmp_path, change, message):
    path, _ = mlp(tmp_path / "bp.onnx")
    with pytest.raises(BundleError, match=message):
        NeuralCorrection(path, {**SPEC, **change})


def test_a_corrupt_model_file_is_refused(tmp_path):
    path = tmp_path / "broken.onnx"
    path.write_bytes(b"not a model")
    with pytest.raises(BundleError, match="onnxruntime cannot load the model"):
        NeuralCorrection(path, SPEC)


def test_a_non_finite_model_output_vents_in_the_first_tick(tmp_path):
    correction = NeuralCorrection(nan_model(tmp_path / "nan.onnx"), SPEC)
    supervisor = Supervisor(Controller(lambda t: 40.0, PIDGains(kp=0.05), correction=correction))
    supervisor.arm(Readings(40.0, 1.0))
    frame = ScratchFrame(0.0, 40.0, 1.0)
    supervisor.step(frame, 0.001)
    assert supervisor.fault_kind is Fault.MODEL_OUTPUT and frame.valve_enable == 0.0 and frame.u_bar == 0.0


@pytest.fixture(scope="module")
def bundle_with_correction(tmp_path_factory):
    root = tmp_path_factory.mktemp("nn")
    bundle = fit_bundle(root / "bundle")
    path, _ = mlp(root / "bp.onnx", scale=0.05)  # a small correction, as a trained one would be
    add_correction(bundle, path, SPEC)
    return bundle


def test_the_bundle_carries_the_correction_with_its_checksum(bundle_with_correction):
    bundle = load_bundle(bundle_with_correction)
    assert bundle.correction_path.name == "correction.onnx" and bundle.correction_spec["features"] == FEATURES
    manifest = json.loads((bundle.path / "manifest.json").read_text())
    assert manifest["files"]["correction.onnx"]["role"] == "correction"
    with (bundle.path / "correction.onnx").open("r+b") as handle:
        original = handle.read()
        handle.seek(len(original) // 2)
        handle.write(b"\x00\x01\x02")
    try:
        with pytest.raises(BundleError, match="checksum mismatch"):
            load_bundle(bundle_with_correction)
    finally:
        (bundle.path / "correction.onnx").write_bytes(original)


def test_the_runtime_adds_the_correction_every_tick(bundle_with_correction, tmp_path):
    edge = runtime(bundle_with_correction, telemetry_path=tmp_path / "t.pmt")
    summary = edge.run(3.0).as_dict()
    record = read_telemetry(tmp_path / "t.pmt")
    nn = record.column("u_nn_bar")
    assert summary["correction"] and summary["faults"] == []
    assert np.all(np.isfinite(nn)) and np.ptp(nn) > 0  # it follows the reference
    off = runtime(bundle_with_correction, use_correction=False).run(1.0).as_dict()
    assert not off["correction"]


def test_a_stalled_loop_is_vented_by_the_watchdog(tmp_path):
    """Real-time clock: a 100 ms stall inside a tick; the watchdog (50 ms) vents from its own
    thread while the loop is stuck, and the loop latches the fault when it comes back."""
    config = rig_config(rig={"io": "sim://rig?adc=ADS1015&clock=realtime"})
    edge = runtime(None, config=config)
    rig = edge.rig.device.rig
    seen = {}

    def stall(t: float) -> None:
        # the first tick at or after 0.5 s, once: on a busy machine no tick may land within a
        # fraction of a millisecond of 0.5 s itself
        if t >= 0.5 and "valve_enabled_after_stall" not in seen:
            time.sleep(0.1)
            seen["valve_enabled_after_stall"] = rig.gpio.get("valve_enable")

    edge.on_tick.append(stall)
    summary = edge.run(1.0).as_dict()
    assert seen["valve_enabled_after_stall"] is False
    assert summary["faults"] and summary["faults"][0].startswith("loop stalled for")
