"""``pmactl train --model lstm-narmax|hammerstein|state-space --save DIR``: the trained nets as a bundle the edge runs.

The bundle (:mod:`models_export.bundle`) holds, from the same training recording(s):

* the rate-independent table model (``forward.npz`` / ``inverse.npz``), fitted as
  ``pmactl fit --model TABLE_MODEL`` would: the ``table`` feedforward role and the table forward;
* the forward net (``forward_net.onnx``, its operator as ``operator.npz``): pressure [bar] ->
  contraction [mm], the forward model a twin runs. The trained model: the LSTM-NARMAX (Wu2025,
  tanh-PI operator), the Hammerstein (Ai2019, MPI -> BP net on [u, y_MPI] -> ARX), or the neural
  state-space model (:mod:`host.train.state_space`: its step graph with the state ``x``
  carried, no operator table);
* the inverse LSTM-NARMAX (``inverse_net.onnx``) over the table inverse, trained by direct
  inverse learning (:mod:`host.train.net_inverse`): the ``net`` feedforward role. The same
  inverse for both forward models: why the Hammerstein's inverse is this net and not a per-tick
  solve of the inverse ARX and static net is in :mod:`host.train.net_inverse`.

Each net is one ONNX step graph with its state as explicit inputs and outputs, golden vectors
recorded by the edge's own evaluators (replayed on every load).
"""

from __future__ import annotations

import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from edge.errors import DataError
from edge.hysteresis.lut import CompiledModel
from host.data import Measurement
from host.train import Trained, join
from host.train.net_inverse import InverseNet, InverseScore, score_inverse, train_inverse_net

if TYPE_CHECKING:
    from models_export.bundle import NetPart

TABLE_MODEL = "mpi"  # Ai2019's feedforward model; identified in about a second on 10^4 samples
SAMPLE_PERIOD_RTOL = 1e-6
FORWARD_METHODS = {
    "lstm-narmax": "LSTM-NARMAX (Wu2025), host/train/lstm_narmax.py",
    "hammerstein": "Hammerstein (Ai2019: MPI -> BP net on [u, y_MPI] -> ARX), host/train/hammerstein.py",
    "state-space": "neural state-space (linear model + tanh net on simulation error), host/train/state_space.py",
}


@dataclass
class NetBundle:
    """What was written: the inverse net's held-out numbers and the table model's kind."""

    directory: Path
    inverse: InverseNet
    table_model: str
    step_s: float
    forward_model: str = "lstm-narmax"
    inverse_tests: list[InverseScore] = field(default_factory=list)  # on the --test recordings

    def as_dict(self) -> dict[str, object]:
        return {
            "bundle": str(self.directory),
            "table_model": self.table_model,
            "forward_model": self.forward_model,
            "inverse_tail_rmse_bar": self.inverse.tail_rmse_bar,
            "inverse_table_only_tail_rmse_bar": self.inverse.tail_rmse_table_bar,
            "inverse_preview_s": self.inverse.preview_steps * self.step_s,
            "inverse_tests": [score.as_dict() for score in self.inverse_tests],
        }


def sample_period(records: list[Measurement]) -> float:
    """The common sample period [s] of ``records`` (the nets step at it); refuses a mix."""
    periods = [r.dt for r in records]
    if any(abs(p - periods[0]) > SAMPLE_PERIOD_RTOL * periods[0] for p in periods):
        shown = ", ".join(f"{Path(r.source).name} {1 / r.dt:g} Hz" for r in records)
        raise DataError(f"--train recordings at different rates ({shown}); record them at one --sample-hz")
    return periods[0]


def save_net_bundle(
    trained: Trained,
    records: list[Measurement],
    directory: str | Path,
    units: tuple[str, str],
    record_info: dict[str, object],
    *,
    epochs: int,
    quiet: bool = True,
    table_model: str = TABLE_MODEL,
    tests: list[Measurement] | None = None,
) -> NetBundle:
    """Fit the table, train the inverse net, export both nets and write the bundle at ``directory``;
    the inverse is scored on ``tests`` (recordings not trained on, :func:`score_inverse`)."""
    from host.train.hammerstein import Hammerstein
    from host.train.lstm_narmax import LSTMNarmax
    from host.train.state_space import NeuralStateSpace
    from host.workflow import make_estimator, rest_state
    from models_export.bundle import NetPart, write_bundle
    from models_export.onnx_step import export_step

    model = trained.model
    if not isinstance(model, LSTMNarmax | Hammerstein | NeuralStateSpace):
        raise DataError(f"--save writes a bundle for --model lstm-narmax|hammerstein|state-space, not {model.kind}")
    step_s = sample_period(records)
    joined = join(records)
    estimator = make_estimator(table_model).fit(joined.u, joined.y)
    forward_table, inverse_table = rest_state(estimator.model_, float(joined.u.min()))
    inverse_net = train_inverse_net(
        joined, CompiledModel(inverse_table.compile()), seed=trained.seed, epochs=epochs, quiet=quiet
    )
    with tempfile.TemporaryDirectory() as scratch:
        forward_part = _forward_part(model, joined.u, Path(scratch) / "forward.onnx")
        inverse_path, inverse_step = export_step("lstm-narmax", inverse_net.weights, Path(scratch) / "inverse.onnx")
        forward_part.spec.update(
            {
                "model": model.kind,
                "step_s": step_s,
                "u_range": [float(joined.u.min()), float(joined.u.max())],
                "maps": f"{units[0]} -> {units[1]}",
                "training": {"method": FORWARD_METHODS[model.kind], **record_info},
            }
        )
        inverse_spec: dict[str, object] = {
            **inverse_step.as_dict(),
            "model": "lstm-narmax",
            "step_s": step_s,
            "u_range": list(inverse_net.target_range),
            "n_range": list(inverse_net.table_range),
            "maps": f"{units[1]} -> {units[0]}",
            "preview_s": inverse_net.preview_steps * step_s,
            "training": {
                "method": "direct inverse learning over the inverse table, host/train/net_inverse.py",
                "tail_rmse": inverse_net.tail_rmse_bar,
                "table_only_tail_rmse": inverse_net.tail_rmse_table_bar,
                "seed": trained.seed,
            },
        }
        parts = [
            forward_part,
            NetPart("inverse", inverse_path, inverse_spec),
        ]
        sources = [Path(r.source) for r in records]
        fit_record = {"model": table_model, "samples": len(joined), "nets": model.kind, **record_info}
        write_bundle(
            directory,
            forward_table,
            inverse_table,
            units=units,
            fit_record=fit_record,
            training_data=[p for p in sources if p.is_file()],
            nets=parts,
        )
    scores = [score_inverse(inverse_net, r, CompiledModel(inverse_table.compile())) for r in tests or []]
    return NetBundle(Path(directory), inverse_net, table_model, step_s, model.kind, scores)


def _forward_part(model: object, u: np.ndarray, path: Path) -> NetPart:
    """The forward net exported to ``path`` with its step description (and operator table, but for a
    state-space model, whose state holds the memory); the caller adds ranges and the training record."""
    from host.train.hammerstein import Hammerstein
    from host.train.lstm_narmax import LSTMNarmax
    from host.train.state_space import NeuralStateSpace, export_onnx
    from models_export.bundle import NetPart
    from models_export.onnx_step import export_step

    if isinstance(model, NeuralStateSpace):
        nx = model.weights.state_order
        export_onnx(model.weights, path)
        spec: dict[str, object] = {
            "inputs": ["u", "x"],
            "output": "y",
            "state": [{"input": "x", "output": "x_next", "size": nx}],
            "initial_state": "zeros (rest)",
        }
        return NetPart("forward", path, spec)
    assert isinstance(model, LSTMNarmax | Hammerstein)
    operator = model.operator.operator
    n_forward = operator.simulate(u, "descending")
    # the operator table is stored at the vented rest state the edge arms in
    operator.model.reset(float(operator.warp(np.array([u.min()]))[0]), "descending")
    forward_path, step = export_step(model.kind, model.weights, path)
    spec = {**step.as_dict(), "n_range": [float(n_forward.min()), float(n_forward.max())]}
    if isinstance(model, Hammerstein):  # the ARX AIC chose, for the reader (the graph holds it too)
        w = model.weights
        spec["arx"] = {"orders": list(w.orders), "a": w.a.tolist(), "b": w.b.tolist()}
    return NetPart("forward", forward_path, spec, operator.model, (operator.centre, operator.half_range))
