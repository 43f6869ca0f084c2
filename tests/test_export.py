"""ONNX step graphs: explicit state, static shapes, opset >= 18, parity with torch and numpy in free run."""

from __future__ import annotations

import numpy as np
import onnx
import pytest

from host.data import load_measurement
from host.train import train_model
from host.train.lstm_narmax import simulate_numpy
from models_export.onnx_step import export_step, simulate_onnx, simulate_torch
from tests.neural_data import hil_csv


@pytest.fixture(scope="module", params=["hammerstein", "lstm-narmax"])
def exported(request, tmp_path_factory):
    root = tmp_path_factory.mktemp("export")
    train = load_measurement(hil_csv(root, "sines", 3, 30.0, "rate_dependence"))
    held_out = load_measurement(hil_csv(root, "mixed", 4, 20.0, "rate_dependence"))
    model = train_model(request.param, [train], epochs=4).model
    path, spec = export_step(request.param, model.weights, root / "step.onnx")
    return request.param, model, path, spec, held_out


def test_the_graph_has_static_batch_1_shapes_and_explicit_state(exported):
    kind, _, path, spec, _ = exported
    graph = onnx.load(str(path))
    assert max(o.version for o in graph.opset_import if o.domain in ("", "ai.onnx")) >= 18
    shapes = {
        v.name: [d.dim_value for d in v.type.tensor_type.shape.dim] for v in [*graph.graph.input, *graph.graph.output]
    }
    assert all(all(d > 0 for d in shape) and shape[0] == 1 for shape in shapes.values())
    for state in spec.state:
        assert shapes[state.input] == shapes[state.output] == [1, state.size]
    if kind == "lstm-narmax":
        assert {"h", "c", "u_lag", "n_lag", "y_lag"} <= set(shapes)


def test_onnxruntime_matches_torch_in_free_run_on_a_held_out_record(exported):
    kind, model, path, _, record = exported
    n = model.operator.operator.simulate(record.u, "descending")
    reference = simulate_torch(kind, model.weights, record.u, n)
    onnx_run = simulate_onnx(path, kind, model.weights, record.u, n)
    assert np.max(np.abs(onnx_run - reference)) <= 1e-5 * np.ptp(reference)


def test_the_numpy_evaluator_matches_onnxruntime(exported):
    kind, model, path, _, record = exported
    u = record.u[:1500]
    n = model.operator.operator.simulate(u, "descending")
    onnx_run = simulate_onnx(path, kind, model.weights, u, n)
    assert np.max(np.abs(model.simulate(u, "descending") - onnx_run)) <= 1e-5 * np.ptp(onnx_run)
    if kind == "lstm-narmax":
        assert np.max(np.abs(simulate_numpy(model.weights, u, n) - onnx_run)) <= 1e-5 * np.ptp(onnx_run)
