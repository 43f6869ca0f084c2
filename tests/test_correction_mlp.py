"""The correction MLP without torch: it learns, the ONNX graph the edge runs gives the same numbers."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from edge.control.neural import NeuralCorrection
from host.train.correction import FEATURES, train_correction


def synthetic(seed: int, n: int = 3000) -> tuple[np.ndarray, np.ndarray]:
    """Features over the ranges a muscle's reference covers and a smooth rate-dependent target [bar]."""
    rng = np.random.default_rng(seed)
    features = np.column_stack([rng.uniform(0, 70, n), rng.normal(0, 40, n), rng.uniform(0, 6, n)])
    target = 0.004 * features[:, 1] + 0.2 * np.sin(features[:, 0] / 12) - 0.03 * features[:, 2] ** 2
    return features, target


def test_the_trained_net_explains_most_of_a_held_out_tail():
    features, target = synthetic(1)
    net, curve, tail_rmse, n_train = train_correction(features, target, epochs=200)
    spread = float(np.std(target[n_train:]))
    assert tail_rmse < 0.1 * spread
    residual = net.predict(features[n_train:]) - target[n_train:]
    assert tail_rmse == pytest.approx(float(np.sqrt(np.mean(residual**2))))
    assert curve.rows and curve.rows[0][0] == "L-BFGS, full batch"


def test_the_same_seed_gives_the_same_net_and_another_seed_another():
    features, target = synthetic(2, 800)
    first = train_correction(features, target, epochs=20, seed=3)[0]
    again = train_correction(features, target, epochs=20, seed=3)[0]
    other = train_correction(features, target, epochs=20, seed=4)[0]
    assert all(np.array_equal(a, b) for a, b in zip(first.layers, again.layers))
    assert not np.array_equal(first.layers[0], other.layers[0])


def test_the_edge_runs_the_exported_graph_with_the_hosts_numbers(tmp_path):
    features, target = synthetic(3, 1500)
    net = train_correction(features, target, epochs=60)[0]
    path = net.to_onnx(tmp_path / "correction.onnx")
    edge = NeuralCorrection(path, {"features": list(FEATURES), "input": "features", "output": "correction_bar"})
    rows = features[:200]
    on_edge = np.array([edge.step((*row, 0.0, 0.0, 0.0)) for row in rows.tolist()])
    np.testing.assert_allclose(on_edge, net.predict(rows), atol=1e-5)


def test_training_and_export_import_no_torch(tmp_path):
    code = (
        "import sys\n"
        "class NoTorch:\n"  # as on an install without torch: importing it fails
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'torch': raise ModuleNotFoundError(name)\n"
        "sys.meta_path.insert(0, NoTorch())\n"
        "import numpy as np\n"
        "from host.train.correction import train_correction\n"
        "rng = np.random.default_rng(0); x = rng.normal(size=(600, 3)); y = np.tanh(x[:, 0])\n"
        f"train_correction(x, y, epochs=5)[0].to_onnx(r'{tmp_path / 'c.onnx'}')\n"
        "assert 'torch' not in sys.modules\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "c.onnx").stat().st_size > 0
