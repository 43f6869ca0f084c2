"""Fused numpy evaluators of the nets: one matrix-vector product per layer, state preallocated.

Why: at batch 1 a step is a few hundred multiply-adds, so its time is the number of calls made,
not the arithmetic. onnxruntime pays its session dispatch on every node of the graph; these
evaluators make the fewest numpy calls the arithmetic allows:

* the input normalisation ``(x - mean) / std`` is folded into the first weight matrix and bias;
* the bias is folded too: the input buffer ends in a constant 1 and the matrix has a bias column;
* the LSTM's four gates are one product ``W @ [x, h, 1]`` and one ``tanh`` for all of them
  (``sigmoid(z) = (1 + tanh(z / 2)) / 2``: the sigmoid gates' rows are pre-halved);
* every buffer is allocated once; a step writes into them with ``out=``.

The arithmetic is float32, as in the exported ONNX graph; the folding changes the rounding, so an
evaluator is accepted only after a parity check against the graph (see :mod:`edge.control.neural`
and ``models_export.onnx_step``). The same folded weights run many lanes at once
(:meth:`FusedNarmax.free_run_lanes`): the trainer scores its held-out free runs with them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

F32 = np.float32


def fold_affine(
    weight: NDArray[np.floating], bias: NDArray[np.floating], mean: NDArray[np.floating], std: NDArray[np.floating]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``W ((x - mean) / std) + b`` as ``W' x + b'`` (float64, rounded to float32 once, by the caller)."""
    w = np.asarray(weight, np.float64) / np.asarray(std, np.float64)[None, :]
    return w, np.asarray(bias, np.float64) - w @ np.asarray(mean, np.float64)


class FusedMLP:
    """A tanh MLP ``scale * (W_L tanh(... tanh(W_1 (x - mean) / std + b_1)) + b_L) + offset``.

    Args:
        layers: ``(weight (out, in), bias (out,))`` per layer; tanh between layers, none after.
        mean, std: input normalisation (folded into the first layer).
        scale, offset: output scaling (folded into the last layer).
    """

    def __init__(
        self,
        layers: Sequence[tuple[NDArray[np.floating], NDArray[np.floating]]],
        mean: NDArray[np.floating] | None = None,
        std: NDArray[np.floating] | None = None,
        scale: float = 1.0,
        offset: float = 0.0,
    ) -> None:
        n_in = np.asarray(layers[0][0]).shape[1]
        mean = np.zeros(n_in) if mean is None else np.asarray(mean, np.float64).reshape(-1)
        std = np.ones(n_in) if std is None else np.asarray(std, np.float64).reshape(-1)
        folded: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
        for i, (weight, bias) in enumerate(layers):
            w, b = np.asarray(weight, np.float64), np.asarray(bias, np.float64).reshape(-1)
            if i == 0:
                w, b = fold_affine(w, b, mean, std)
            if i == len(layers) - 1:
                w, b = w * scale, b * scale + offset
            folded.append((w, b))
        # layer i reads buffer i = [activations, 1] and writes the first rows of buffer i + 1
        self._buffers = [np.ones(w.shape[1] + 1, F32) for w, _ in folded] + [np.ones(folded[-1][0].shape[0], F32)]
        self._matrices = [np.ascontiguousarray(np.column_stack([w, b]), F32) for w, b in folded]
        views = [self._buffers[i + 1][: w.shape[0]] for i, (w, _) in enumerate(folded)]
        # (matrix, source buffer, target view, tanh after?) per layer, unrolled once here
        self._plan = [(m, self._buffers[i], views[i], i < len(folded) - 1) for i, m in enumerate(self._matrices)]
        self._output = views[-1]
        self._input = self._buffers[0]
        self._columns = range(n_in)
        self.n_inputs = n_in

    def step(self, x: Sequence[float] | NDArray[np.floating]) -> float:
        """The output for one input vector (float32 arithmetic)."""
        buffer = self._input
        for i in self._columns:  # element-wise: cheaper than converting a short list
            buffer[i] = x[i]
        for matrix, source, target, activate in self._plan:
            np.dot(matrix, source, out=target)
            if activate:
                np.tanh(target, out=target)
        return float(self._output[0])


class FusedNarmax:
    """The LSTM-NARMAX step (``host.train.lstm_narmax``): regressors ``[u, u_lag, n, n_lag, y_lag]``.

    ``y = n + y_std * (head_w . h + head_b)`` with ``h`` from one LSTM cell (PyTorch gate order
    input, forget, cell, output). Start (:meth:`reset`): zero LSTM state, lags at the first sample.
    """

    def __init__(
        self,
        w_ih: NDArray[np.floating],
        w_hh: NDArray[np.floating],
        bias: NDArray[np.floating],
        head_w: NDArray[np.floating],
        head_b: float,
        mean: NDArray[np.floating],
        std: NDArray[np.floating],
        y_std: float,
    ) -> None:
        hidden = np.asarray(w_hh).shape[1]
        n_x = np.asarray(w_ih).shape[1]
        w_x, b = fold_affine(w_ih, bias, mean, std)
        matrix = np.column_stack([w_x, np.asarray(w_hh, np.float64), b])
        sigmoid_rows = np.r_[0 : 2 * hidden, 3 * hidden : 4 * hidden]
        matrix[sigmoid_rows] *= 0.5
        self.hidden, self.n_x = hidden, n_x
        self.matrix = np.ascontiguousarray(matrix, F32)  # (4H, n_x + H + 1)
        self.head = np.asarray(head_w, np.float64) * float(y_std)
        self.head32 = self.head.astype(F32)
        self.head_b = F32(float(head_b) * float(y_std))
        self._v = np.ones(n_x + hidden + 1, F32)  # [x, h, 1]
        self._z = np.empty(4 * hidden, F32)
        self._c = np.zeros(hidden, F32)
        self._tc = np.empty(hidden, F32)
        self._ig = np.empty(hidden, F32)
        self._h = self._v[n_x : n_x + hidden]
        self._sig = self._z[: 2 * hidden]  # i, f (o handled with its own view)
        self._i, self._f = self._z[:hidden], self._z[hidden : 2 * hidden]
        self._g, self._o = self._z[2 * hidden : 3 * hidden], self._z[3 * hidden :]
        self._lags = (0.0, 0.0, 0.0)

    def reset(self, u0: float, n0: float) -> None:
        """Zero LSTM state; the lags at the first sample, ``y(-1) = n(0)`` (a steady start)."""
        self._h[:] = 0.0
        self._c[:] = 0.0
        self._lags = (u0, n0, n0)

    def step(self, u: float, n: float) -> float:
        """Output [output units] for input ``u`` and operator output ``n`` at this step."""
        v, z, h, c = self._v, self._z, self._h, self._c
        u_lag, n_lag, y_lag = self._lags
        v[0], v[1], v[2], v[3], v[4] = u, u_lag, n, n_lag, y_lag
        np.dot(self.matrix, v, out=z)
        np.tanh(z, out=z)
        np.multiply(self._sig, 0.5, out=self._sig)  # i, f: sigmoid = 0.5 + 0.5 tanh(z / 2)
        np.add(self._sig, 0.5, out=self._sig)
        np.multiply(self._i, self._g, out=self._ig)
        np.multiply(c, self._f, out=c)
        np.add(c, self._ig, out=c)
        np.tanh(c, out=self._tc)
        # o = 0.5 + 0.5 tanh(.) is applied inside h = o * tanh(c): h = 0.5 (tanh(c) + t_o tanh(c))
        np.multiply(self._o, self._tc, out=h)
        np.add(h, self._tc, out=h)
        np.multiply(h, 0.5, out=h)
        y = float(F32(n) + F32(np.dot(self.head32, h)) + self.head_b)
        self._lags = (u, n, y)
        return y

    def simulate(self, u: NDArray[np.floating], n: NDArray[np.floating]) -> NDArray[np.float64]:
        """Free run over a record from :meth:`reset` at its first sample."""
        self.reset(float(u[0]), float(n[0]))
        step = self.step
        return np.array([step(a, b) for a, b in zip(u.tolist(), n.tolist())])

    def free_run_lanes(
        self,
        x: NDArray[np.floating],
        n: NDArray[np.floating],
        y: NDArray[np.floating],
        free_from: NDArray[np.integer],
    ) -> NDArray[np.float64]:
        """Many runs at once (float64): lane ``b`` is teacher-forced before ``free_from[b]``, free after.

        ``x`` (L, B, n_x) are the teacher-forced regressors (the last column, ``y(k-1)``, is
        replaced by the lane's own prediction once it runs free), ``n`` and ``y`` (L, B) the
        operator output and the measured output. Returns the predictions (L, B).
        """
        length, lanes = n.shape
        hidden, n_x = self.hidden, self.n_x
        w = self.matrix.astype(np.float64)
        w_x, w_y, w_h, b = w[:, : n_x - 1], w[:, n_x - 1], w[:, n_x : n_x + hidden], w[:, -1]
        zx = np.asarray(x[..., : n_x - 1], np.float64) @ w_x.T + b  # (L, B, 4H), all steps at once
        h = np.zeros((lanes, hidden))
        c = np.zeros((lanes, hidden))
        y_lag = np.asarray(x[0, :, n_x - 1], np.float64).copy()
        out = np.empty((length, lanes))
        free = np.zeros(lanes, bool)
        for k in range(length):
            free |= free_from == k
            t = np.tanh(zx[k] + np.multiply.outer(y_lag, w_y) + h @ w_h.T)
            s = 0.5 + 0.5 * t
            c = s[:, hidden : 2 * hidden] * c + s[:, :hidden] * t[:, 2 * hidden : 3 * hidden]
            tc = np.tanh(c)
            h = s[:, 3 * hidden :] * tc
            out[k] = n[k] + h @ self.head + float(self.head_b)
            if k + 1 < length:
                y_lag = np.where(free, out[k], x[k + 1, :, n_x - 1])
        return out
