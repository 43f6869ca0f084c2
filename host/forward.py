"""The forward model of any saved model folder, run over an input: what ``pmactl simulate`` runs.

Two kinds of folder:

* a *bundle* (``pmactl fit --save``, ``pmactl train --save``): its verified forward net when it
  holds one (the edge's own evaluator, :class:`BundleNetForward`), else or with ``role="table"``
  its verified forward lookup table;
* an older *trained net* folder (``model.json``, ``step.onnx``, ``operator.npz``): the
  operator's lookup table, then the ONNX step graph in free run, run by the faster evaluator
  that reproduces the onnxruntime session (the fused numpy step for LSTM-NARMAX, see
  :mod:`edge.control.fused_graph`; onnxruntime otherwise).

Initial states (:data:`INITIAL_STATES`): ``rest`` is the state the table was compiled in;
``ascending`` / ``descending`` wipe the hysteresis memory at the lowest / highest input of the
record and move to its first sample (the input last came up from its minimum / down from its
maximum; a table does not record the actuator's memory range, the record's extremes are what the
user's input can reach; a trained net's ``model.json`` records its operator's memory range, and
its outer branches start there, as in training);
a net's own state starts at zero with its lags at the first sample (a steady start).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from edge.control.fused import FusedNarmax
from edge.control.fused_graph import Choice, choose, narmax_from_graph
from edge.control.onnx_graph import GraphFormatError, read_graph
from edge.errors import BundleError, ModelError
from edge.hysteresis.lut import CompiledModel, load_compiled

if TYPE_CHECKING:
    from edge.runtime.bundle import Bundle

INITIAL_STATES = ("rest", "ascending", "descending")
NET_KINDS = ("lstm-narmax", "hammerstein")


def _prime(table: CompiledModel, x0: float, initial: str, lo: float, hi: float) -> None:
    """Put ``table`` in ``initial`` at input ``x0`` (see module docstring)."""
    if initial not in INITIAL_STATES:
        raise ModelError(f"initial state {initial!r} unknown; use one of {', '.join(INITIAL_STATES)}")
    table.reset()
    if initial == "rest":
        return
    table.step(lo if initial == "ascending" else hi)
    table.step(x0)


def _wipe_range(table: CompiledModel, x: NDArray[np.float64]) -> tuple[float, float]:
    """Where the memory is wiped: the record's lowest and highest input, inside the table's range."""
    lo, hi = table.input_range
    return max(lo, float(x.min())), min(hi, float(x.max()))


class TableForward:
    """A bundle's forward lookup table."""

    def __init__(self, table: CompiledModel, description: str) -> None:
        self.table = table
        self.description = description
        self.evaluator = "lookup table"

    def run(self, u: NDArray[np.float64], initial: str) -> NDArray[np.float64]:
        """Output for ``u`` [output units] from ``initial`` (see module docstring)."""
        lo, hi = _wipe_range(self.table, u)
        _prime(self.table, float(u[0]), initial, lo, hi)
        return self.table.simulate(u)


class NetForward:
    """A trained net: operator table on the (warped) input, then the step graph in free run."""

    def __init__(self, folder: Path) -> None:
        try:
            spec = json.loads((folder / "model.json").read_text())
            self.kind = str(spec["kind"])
            step_file, operator = spec["step"]["file"], spec["operator"]
            self.centre = float(operator.get("warp_centre", 0.0))
            self.half_range = float(operator.get("warp_half_range", 0.0))
            memory = operator.get("memory_range")
            self.memory_range = (float(memory[0]), float(memory[1])) if memory else None
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise BundleError(
                f"{folder}/model.json: not a pmactl trained model ({exc}); save one with pmactl train --save"
            ) from exc
        if self.kind not in NET_KINDS:
            raise BundleError(
                f"{folder}/model.json: model kind {self.kind!r} unknown (known: {', '.join(NET_KINDS)}); "
                "upgrade pmactl or retrain"
            )
        from models_export.onnx_step import OnnxStepper, spec_of

        self.step_path = folder / str(step_file)
        self.operator = load_compiled(folder / str(operator["file"]))
        self.stepper = OnnxStepper(self.step_path, spec_of(self.kind))
        self.fused: FusedNarmax | None = None
        if self.kind == "lstm-narmax":
            try:
                self.fused = narmax_from_graph(read_graph(self.step_path))
            except GraphFormatError:
                self.fused = None
        self.choice: Choice | None = None
        self.evaluator = "onnxruntime"
        self.description = f"{self.kind} net ({folder.name})"

    def _warp(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.tanh((u - self.centre) / self.half_range) if self.half_range > 0 else u

    def _start_onnx(self, u0: float, n0: float) -> None:
        """Zero LSTM state and lags at the first sample; for Hammerstein the lags at its static output."""
        full = lambda value: np.full((1, 1), value, np.float32)  # noqa: E731
        if self.kind == "lstm-narmax":
            self.stepper.set_state({"u_lag": full(u0), "n_lag": full(n0), "y_lag": full(n0)})
            return
        self.stepper.set_state({})  # zero lags
        self.stepper.step(u0, n0)  # one step from zero lags: v_lags_out[0] is the static output v(u0, n0)
        v0 = float(self.stepper.state_in["v_lags"][0, 0])
        self.stepper.set_state({s.input: full(v0) for s in self.stepper.spec.state})

    def run(self, u: NDArray[np.float64], initial: str) -> NDArray[np.float64]:
        """Output for ``u`` [output units] from ``initial`` (see module docstring)."""
        x = self._warp(np.asarray(u, np.float64))
        lo, hi = self.memory_range or _wipe_range(self.operator, x)
        _prime(self.operator, float(x[0]), initial, lo, hi)
        n = self.operator.simulate(x)
        u0, n0 = float(u[0]), float(n[0])
        if self.fused is not None and self.choice is None:
            fused = self.fused
            probes = list(zip(u[:300].tolist(), n[:300].tolist()))

            def reset() -> None:
                fused.reset(u0, n0)
                self._start_onnx(u0, n0)

            self.choice = choose(lambda p: self.stepper.step(*p), lambda p: fused.step(*p), probes, reset)
            self.evaluator = self.choice.evaluator
        if self.evaluator == "numpy-fused" and self.fused is not None:
            return self.fused.simulate(u, n)
        self._start_onnx(u0, n0)
        step = self.stepper.step
        return np.array([step(a, b) for a, b in zip(u.tolist(), n.tolist())])


class BundleNetForward:
    """A bundle's forward net run by the edge's own evaluator (:meth:`edge.runtime.bundle.Bundle.forward_net`),
    one net step per input sample: the input must be sampled at the net's ``step_s``."""

    def __init__(self, bundle: Bundle) -> None:
        spec = bundle.net_spec("forward")
        self.step_s = float(spec["step_s"])  # type: ignore[arg-type]  # checked when the bundle loaded
        self.model = bundle.forward_net(self.step_s)
        self.kind = self.model.kind
        self.evaluator = self.model.net.choice.evaluator
        self.description = f"{self.kind} net of the bundle ({bundle.release_id})"

    def run(self, u: NDArray[np.float64], initial: str) -> NDArray[np.float64]:
        """Output for ``u`` [output units] from ``initial`` (see module docstring)."""
        from edge.control.net_state_space import StateSpaceForward

        model = self.model
        model.reset()
        if isinstance(model, StateSpaceForward):  # no operator: its state starts at rest (zeros) in any case
            return model.simulate(u)
        x = np.asarray(u, np.float64)
        if model.warp_half_range > 0:
            x = np.tanh((x - model.warp_centre) / model.warp_half_range)
        lo, hi = _wipe_range(model.table, x)
        _prime(model.table, float(x[0]), initial, lo, hi)  # the operator's memory; the net starts afresh
        return model.simulate(u)


def load_forward(folder: str | Path, role: str | None = None) -> TableForward | NetForward | BundleNetForward:
    """The forward model saved in ``folder`` (see module docstring); one clear error otherwise.

    ``role``: ``table`` or ``net``; ``None`` is the net when the folder holds one, else the table.
    """
    folder = Path(folder)
    if role not in (None, "table", "net"):
        raise ModelError(f"forward role {role!r} unknown; use table or net")
    if not folder.is_dir():
        raise BundleError(f"{folder}: not a folder; give the folder pmactl fit --save or pmactl train --save wrote")
    if (folder / "model.json").is_file():
        if role == "table":
            raise BundleError(f"{folder}: a trained net folder holds no forward table; drop --role table")
        return NetForward(folder)
    if not ((folder / "manifest.json").is_file() or (folder / "current").exists()):
        raise BundleError(
            f"{folder}: neither a bundle (no manifest.json) nor a trained model (no model.json); "
            "give the folder pmactl fit --save or pmactl train --save wrote"
        )
    from edge.runtime.bundle import load_bundle

    bundle = load_bundle(folder)
    if role == "net" and "forward" not in bundle.net_paths:
        raise BundleError(
            f"{folder}: holds no forward net (a table bundle); drop --role net, or train one with "
            "pmactl train --model lstm-narmax|hammerstein|state-space --save"
        )
    if role != "table" and "forward" in bundle.net_paths:
        return BundleNetForward(bundle)
    kind = bundle.identity.get("kind")
    return TableForward(bundle.forward, f"{kind} bundle ({bundle.release_id})")
