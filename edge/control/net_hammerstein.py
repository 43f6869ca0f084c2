"""The bundle's Hammerstein forward net on the edge (Ai2019: MPI -> BP net on [u, y_MPI] -> ARX).

The step graph (``models_export.onnx_step``, ``pmactl train --model hammerstein --save``) maps
the pressure ``u`` [bar] and the MPI operator's output ``n`` [mm] (the bundle's operator table,
stepped by the edge) with the carried ARX state ``y_lags`` (3 past outputs) and ``v_lags`` (2
past static-net outputs) to the contraction ``y`` [mm] and the next state.

:class:`HammersteinNet` has the interface of :class:`edge.control.net_narmax.NarmaxNet`
(``step(u, n) -> y``, ``reset()``), so :class:`~edge.control.net_narmax.NetForward` and the
golden replay use it unchanged. It runs the onnxruntime session only: the graph is five small
Gemm/Tanh nodes and two 3-tap filters, about one session call per net step (every
``step_s``, 10 ms at ``edge record``'s 100 Hz), so a fused numpy copy would save microseconds
per net step and add a second evaluator to verify.

Start (after :meth:`reset`): the ARX starts in the steady state of the first input, as the
trainer's free runs start (``y_lags = v_lags = v(u0, n0)``); ``v(u0, n0)`` is read from the
graph's own ``v_lags_out`` after one probe step, not from a second copy of the net.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from edge.control.fused_graph import Choice
from edge.control.ort_session import tick_session
from edge.errors import BundleError

STATE_SIZES = {"y_lags": 3, "v_lags": 2}


def is_hammerstein(spec: Mapping[str, object]) -> bool:
    """Whether a manifest net entry describes a Hammerstein step graph (by its carried state)."""
    state = spec.get("state")
    return isinstance(state, list) and [s.get("input") for s in state if isinstance(s, dict)] == list(STATE_SIZES)


class HammersteinNet:
    """One Hammerstein step graph with its ARX state; ``step(u, n) -> y``, ``reset()``.

    Args:
        path: the ``.onnx`` step graph.
        spec: the manifest's entry for it (``inputs``, ``output``, ``state``).
    """

    kind = "hammerstein"

    def __init__(self, path: str | Path, spec: Mapping[str, object]) -> None:
        import onnxruntime as ort  # on the SBC only when a bundle holds a net

        self.path = Path(path)
        if not is_hammerstein(spec) or spec.get("inputs") != ["u", "n"] or spec.get("output") != "y":
            raise BundleError(f"{self.path}: not a Hammerstein step graph description in the manifest; re-export")
        self._session = tick_session(self.path)
        declared = {i.name for i in self._session.get_inputs()}
        if declared != {"u", "n", *STATE_SIZES}:
            raise BundleError(f"{self.path}: graph inputs {sorted(declared)} are not a Hammerstein step; re-export")
        self._u = np.zeros((1, 1), np.float32)
        self._n = np.zeros((1, 1), np.float32)
        self._y = np.zeros((1, 1), np.float32)
        self._state_in = {name: np.zeros((1, size), np.float32) for name, size in STATE_SIZES.items()}
        self._state_out = {name: np.zeros((1, size), np.float32) for name, size in STATE_SIZES.items()}
        binding = self._session.io_binding()
        value = ort.OrtValue.ortvalue_from_numpy
        binding.bind_ortvalue_input("u", value(self._u))
        binding.bind_ortvalue_input("n", value(self._n))
        binding.bind_ortvalue_output("y", value(self._y))
        for name in STATE_SIZES:
            binding.bind_ortvalue_input(name, value(self._state_in[name]))
            binding.bind_ortvalue_output(f"{name}_out", value(self._state_out[name]))
        self._binding = binding
        self._fresh = True
        self.choice = Choice("onnxruntime", "Hammerstein step graph: onnxruntime only (no fused evaluator)")

    def reset(self) -> None:
        """Forget the state: the next step starts the ARX in the steady state of its input (on arming)."""
        self._fresh = True

    def _run(self, u: float, n: float) -> None:
        self._u[0, 0], self._n[0, 0] = u, n
        self._session.run_with_iobinding(self._binding)

    def step(self, u: float, n: float) -> float:
        """``y`` for this step's ``u`` and ``n`` (NaN when the net's output is not finite)."""
        if self._fresh:
            for array in self._state_in.values():
                array.fill(0.0)
            self._run(u, n)  # v(u, n) comes out as v_lags_out[0]
            for array in self._state_in.values():
                array.fill(float(self._state_out["v_lags"][0, 0]))
            self._fresh = False
        self._run(u, n)
        for name, array in self._state_in.items():
            np.copyto(array, self._state_out[name])
        y = float(self._y[0, 0])
        return y if math.isfinite(y) else math.nan
