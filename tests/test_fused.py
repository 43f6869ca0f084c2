"""The fused numpy evaluators: compiled from the ONNX file, parity with torch and onnxruntime on a
held-out free run, the edge keeps onnxruntime when the fused form is missing or disagrees."""

from __future__ import annotations

import numpy as np
import onnx
import pytest
import torch
from onnx import numpy_helper
from torch import nn

from edge.control.fused_graph import choose, mlp_from_graph, narmax_from_graph
from edge.control.neural import NeuralCorrection
from edge.control.onnx_graph import GraphFormatError, read_graph
from host.data import load_measurement
from host.train import train_model
from models_export.onnx_step import export_module, export_step, simulate_onnx, simulate_torch
from tests.neural_data import hil_csv
from tests.onnx_models import mlp, rnn

SPEC3 = {
    "features": ["reference_mm", "reference_rate_mm_s", "feedforward_bar"],
    "input": "features",
    "output": "correction_bar",
}


class Correction(nn.Module):
    """The correction's shape (3-16-16-1) with normalisation and output scale inside the graph."""

    def __init__(self) -> None:
        super().__init__()
        torch.manual_seed(5)
        self.net = nn.Sequential(nn.Linear(3, 16), nn.Tanh(), nn.Linear(16, 16), nn.Tanh(), nn.Linear(16, 1))
        self.register_buffer("mean", torch.tensor([[40.0, 0.0, 3.0]]))
        self.register_buffer("inv_std", torch.tensor([[0.05, 0.02, 0.5]]))
        self.register_buffer("scale", torch.tensor(0.2))

    def forward(self, x):  # noqa: ANN001, ANN201
        return self.net((x - self.mean) * self.inv_std) * self.scale


@pytest.fixture(scope="module")
def narmax(tmp_path_factory):
    root = tmp_path_factory.mktemp("fused")
    train = load_measurement(hil_csv(root, "sines", 1, 40.0, "rate_dependence"))
    held_out = load_measurement(hil_csv(root, "sines", 2, 40.0, "rate_dependence"))
    model = train_model("lstm-narmax", [train], seed=0, epochs=6).model
    path, _ = export_step("lstm-narmax", model.weights, root / "step.onnx")
    return model, path, held_out


def test_the_reader_gives_the_initializers_onnx_gives(narmax):
    _, path, _ = narmax
    ours = read_graph(path).constants
    for tensor in onnx.load(str(path)).graph.initializer:
        assert np.array_equal(ours[tensor.name], numpy_helper.to_array(tensor))


def test_fused_narmax_matches_torch_and_onnxruntime_on_a_held_out_free_run(narmax):
    model, path, held_out = narmax
    u = held_out.u[:3000]
    n = model.operator.operator.simulate(u, "descending")
    reference = simulate_torch("lstm-narmax", model.weights, u, n)
    ort_run = simulate_onnx(path, "lstm-narmax", model.weights, u, n)
    fused_run = narmax_from_graph(read_graph(path)).simulate(u, n)
    span = float(np.ptp(reference))
    assert np.max(np.abs(ort_run - reference)) <= 1e-5 * span
    assert np.max(np.abs(fused_run - reference)) <= 1e-5 * span


def test_fused_mlp_compiled_from_a_torch_export_matches_torch(tmp_path):
    module = Correction().eval()
    path = export_module(module, (torch.zeros(1, 3),), tmp_path / "c.onnx", ["features"], ["correction_bar"])
    fused = mlp_from_graph(read_graph(path), "features", "correction_bar", 3)
    x = np.random.default_rng(1).normal(0, 20, (300, 3)).astype(np.float32)
    with torch.no_grad():
        expected = module(torch.from_numpy(x))[:, 0].numpy()
    got = np.array([fused.step(row) for row in x])
    assert np.max(np.abs(got - expected)) <= 1e-5 * np.ptp(expected)


def test_the_edge_correction_keeps_an_evaluator_that_reproduces_the_session(tmp_path):
    module = Correction().eval()
    path = export_module(module, (torch.zeros(1, 3),), tmp_path / "c.onnx", ["features"], ["correction_bar"])
    correction = NeuralCorrection(path, SPEC3)
    assert correction.choice.evaluator in ("numpy-fused", "onnxruntime")
    assert correction.choice.max_abs_diff <= 1e-5
    x = np.random.default_rng(2).normal(0, 20, (100, 3)).astype(np.float32)
    with torch.no_grad():
        expected = module(torch.from_numpy(x))[:, 0].numpy()
    got = [correction.step((a, b, c, 0.0, 0.0, 0.0)) for a, b, c in x]
    assert got == pytest.approx(expected.tolist(), abs=1e-5)


def test_a_recurrent_correction_runs_in_onnxruntime(tmp_path):
    path, _ = rnn(tmp_path / "rnn.onnx", hidden=4)
    spec = {
        **SPEC3,
        "features": ["reference_mm", "feedforward_bar"],
        "state": {"input": "h_in", "output": "h_out", "size": 4},
    }
    correction = NeuralCorrection(path, spec)
    assert correction.choice.evaluator == "onnxruntime"
    assert "no fused form" in correction.choice.reason


def test_a_fused_step_that_disagrees_is_not_used():
    probes = [[float(v)] for v in np.linspace(-1, 1, 50)]
    choice = choose(lambda x: float(np.tanh(x[0])), lambda x: float(np.tanh(x[0])) + 1e-2, probes)
    assert choice.evaluator == "onnxruntime" and "differs by" in choice.reason


def test_a_graph_with_an_unknown_operator_is_not_fused(tmp_path):
    path, _ = mlp(tmp_path / "bp.onnx")
    graph = read_graph(path)
    graph.nodes[2].op = "Relu"  # the first Tanh
    with pytest.raises(GraphFormatError, match="Relu is not fused"):
        mlp_from_graph(graph, "features", "correction_bar", 2)
