"""LSTM-NARMAX (seed 001): an LSTM over NARMAX regressors with a tanh-input PI operator.

Regressors at step k (seed 001: hv = 2, hn = 2, hy = 1)::

    [v(k), v(k-1), n(k), n(k-1), y(k-1)]

with v the input, n the tanh-input PI operator's output (:mod:`host.train.operators`) and y the
output. An LSTM (hidden 7) and a linear head give ``y(k) = n(k) + head(h(k))``: the net learns
what the rate-independent operator misses (its output is already in output units), which keeps
the head small and the start of training sane. Seed 001 feeds n as a regressor too; the skip is
our choice.

Training, in two phases, Adam (the LSTM's loss surface is non-convex and minibatched):

1. *teacher forcing*: ``y(k-1)`` is the measured output; fast (one ``nn.LSTM`` call per batch
   of windows), but it teaches a one-step predictor that leans on the measured lag;
2. *free run* (what it is scored on): ``y(k-1)`` is the model's own prediction, over windows of
   ``free_run_window`` samples whose first ``washout`` samples are teacher-forced and not
   scored (the state gets to where it should be), back-propagated through the whole window.

After every epoch the held-out tail is simulated in free run from the known memory start; the
best weights on it are kept (early stopping with ``patience``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from host.train.common import Curve, EarlyStopping, Split, normaliser, progress
from host.train.operators import IdentifiedOperator, identify_tanh_pi

HIDDEN = 7
N_REGRESSORS = 5


@dataclass
class NarmaxWeights:
    """The trained weights in numpy (float32), PyTorch's gate order (input, forget, cell, output)."""

    w_ih: NDArray[np.float32]  # (4 hidden, 5)
    w_hh: NDArray[np.float32]  # (4 hidden, hidden)
    bias: NDArray[np.float32]  # (4 hidden,)  b_ih + b_hh
    head_w: NDArray[np.float32]  # (hidden,)
    head_b: float
    mean: NDArray[np.float32]  # regressor normalisation (5,)
    std: NDArray[np.float32]
    y_std: float


@dataclass
class LSTMNarmax:
    """A trained LSTM-NARMAX: operator + weights; ``simulate(u, branch)`` runs it in free run."""

    operator: IdentifiedOperator
    weights: NarmaxWeights
    curve: Curve = field(default_factory=Curve)
    kind: str = "lstm-narmax"

    def simulate(self, u: NDArray[np.float64], branch: str) -> NDArray[np.float64]:
        """Free-run output [output units] for ``u`` from a start in ``branch`` at ``u[0]``."""
        n = self.operator.operator.simulate(u, branch)
        return simulate_numpy(self.weights, u, n)


def _sigmoid(x: NDArray[np.float32]) -> NDArray[np.float32]:
    return np.asarray(1.0 / (1.0 + np.exp(-x)), dtype=np.float32)


def simulate_numpy(w: NarmaxWeights, u: NDArray[np.float64], n: NDArray[np.float64]) -> NDArray[np.float64]:
    """The numpy evaluator of the step graph (float32, same arithmetic as the ONNX export).

    Start: zero LSTM state, lags at the first sample (``y(-1) = n(0)``).
    """
    hidden = w.w_hh.shape[1]
    h = np.zeros(hidden, np.float32)
    c = np.zeros(hidden, np.float32)
    u32, n32 = u.astype(np.float32), n.astype(np.float32)
    x = np.empty(N_REGRESSORS, np.float32)
    out = np.empty(u.size)
    u_lag, n_lag, y_lag = u32[0], n32[0], n32[0]
    inv_std = (1.0 / w.std).astype(np.float32)
    for k in range(u.size):
        x[0], x[1], x[2], x[3], x[4] = u32[k], u_lag, n32[k], n_lag, y_lag
        z = w.w_ih @ ((x - w.mean) * inv_std) + w.w_hh @ h + w.bias
        i, f, g, o = (
            _sigmoid(z[:hidden]),
            _sigmoid(z[hidden : 2 * hidden]),
            np.tanh(z[2 * hidden : 3 * hidden]),
            _sigmoid(z[3 * hidden :]),
        )
        c = f * c + i * g
        h = o * np.tanh(c)
        y = np.float32(n32[k] + (w.head_w @ h + np.float32(w.head_b)) * np.float32(w.y_std))
        out[k] = y
        u_lag, n_lag, y_lag = u32[k], n32[k], y
    return out


def _regressors(u: NDArray[np.float64], n: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    """Teacher-forced regressors [v(k), v(k-1), n(k), n(k-1), y(k-1)] (lags at k=0 repeat sample 0)."""
    lag = lambda s: np.concatenate([s[:1], s[:-1]])  # noqa: E731
    return np.column_stack([u, lag(u), n, lag(n), lag(y)])


def _window_starts(length: int, window: int, rng: np.random.Generator) -> NDArray[np.int64]:
    """Window starts covering ``[0, length)`` with a random phase (every sample seen each epoch)."""
    phase = int(rng.integers(0, max(1, window // 2)))
    starts = np.arange(phase, max(phase + 1, length - window + 1), window // 2)
    return starts[starts + window <= length]


def train_lstm_narmax(
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    split_fn: Callable[[int], Split],
    *,
    seed: int = 0,
    epochs: int = 60,
    quiet: bool = True,
    teacher_window: int = 256,
    free_run_window: int = 400,
    washout: int = 50,
    patience: int = 8,
) -> tuple[LSTMNarmax, Split]:
    """Identify the operator, train the LSTM (see module docstring). ``split_fn(start) -> Split``."""
    import torch
    from torch import nn

    # the operator is identified on the whole record, as ``pmactl fit`` would (the baselines it is
    # compared with see the same data); the tail is held out from the net's training only
    operator = identify_tanh_pi(u, y)
    split = split_fn(operator.start_index)
    n_all = operator.operator.simulate(u[split.start :], operator.start_branch)
    u_all, y_all = u[split.start :], y[split.start :]
    n_train = split.tail - split.start
    regressors = _regressors(u_all, n_all, y_all)
    mean = np.array([normaliser(regressors[:n_train, j])[0] for j in range(N_REGRESSORS)])
    std = np.array([normaliser(regressors[:n_train, j])[1] for j in range(N_REGRESSORS)])
    y_std = normaliser(y_all[:n_train] - n_all[:n_train])[1]

    lstm = nn.LSTM(N_REGRESSORS, HIDDEN, batch_first=True)
    head = nn.Linear(HIDDEN, 1)
    nn.init.zeros_(head.weight)
    nn.init.zeros_(head.bias)
    params = list(lstm.parameters()) + list(head.parameters())
    t = lambda a: torch.as_tensor(np.asarray(a), dtype=torch.float32)  # noqa: E731
    x_norm = t((regressors - mean) / std)
    n_t, y_t = t(n_all), t(y_all)
    rng = np.random.default_rng(seed)
    curve = Curve()
    stopper = EarlyStopping(patience)

    def weights() -> NarmaxWeights:
        p = {name: value.detach().numpy().astype(np.float32) for name, value in lstm.named_parameters()}
        return NarmaxWeights(
            p["weight_ih_l0"].copy(),
            p["weight_hh_l0"].copy(),
            p["bias_ih_l0"] + p["bias_hh_l0"],
            head.weight.detach().numpy()[0].astype(np.float32).copy(),
            float(head.bias.detach()[0]),
            mean.astype(np.float32),
            std.astype(np.float32),
            float(y_std),
        )

    def tail_rmse(w: NarmaxWeights) -> float:
        predicted = simulate_numpy(w, u_all, n_all)
        return float(np.sqrt(np.mean((predicted[n_train:] - y_all[n_train:]) ** 2)))

    def snapshot() -> dict[str, object]:
        return {"lstm": lstm.state_dict(), "head": head.state_dict()}

    stopper.update(tail_rmse(weights()), snapshot())  # head at zero: the operator alone, to beat
    teacher_epochs = max(1, (2 * epochs) // 3)
    optimiser = torch.optim.Adam(params, lr=1e-2)
    for epoch in progress(teacher_epochs, "lstm-narmax teacher forcing", quiet):
        losses = []
        starts = _window_starts(n_train, teacher_window, rng)
        for batch in np.array_split(rng.permutation(starts), max(1, len(starts) // 4)):
            index = torch.as_tensor(batch[:, None] + np.arange(teacher_window)[None, :])
            hidden, _ = lstm(x_norm[index])
            predicted = n_t[index] + head(hidden)[..., 0] * y_std
            loss = torch.mean(((predicted - y_t[index]) / y_std) ** 2)
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            losses.append(float(loss.detach()))
        score = tail_rmse(weights())
        curve.add("teacher forcing", epoch, float(np.mean(losses)), score)
        stopper.update(score, snapshot())

    if stopper.best_state is not None:
        lstm.load_state_dict(stopper.best_state["lstm"])  # type: ignore[arg-type]
        head.load_state_dict(stopper.best_state["head"])  # type: ignore[arg-type]
    stopper.stale = 0
    optimiser = torch.optim.Adam(params, lr=1e-3)
    mean_t, std_t = t(mean), t(std)
    for epoch in progress(epochs - teacher_epochs, "lstm-narmax free run", quiet):
        losses = []
        starts = _window_starts(n_train, free_run_window, rng)
        for batch in np.array_split(rng.permutation(starts), max(1, len(starts) // 16)):
            index = torch.as_tensor(batch[:, None] + np.arange(free_run_window)[None, :])
            _, (h, c) = lstm(x_norm[index[:, :washout]])
            y_lag = y_t[index[:, washout - 1]]
            outputs = []
            for k in range(washout, free_run_window):
                regress = x_norm[index[:, k]].clone()
                regress[:, 4] = (y_lag - mean_t[4]) / std_t[4]
                step, (h, c) = lstm(regress[:, None, :], (h, c))
                y_lag = n_t[index[:, k]] + head(step[:, 0])[:, 0] * y_std
                outputs.append(y_lag)
            predicted = torch.stack(outputs, 1)
            loss = torch.mean(((predicted - y_t[index[:, washout:]]) / y_std) ** 2)
            optimiser.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(params, 1.0)
            optimiser.step()
            losses.append(float(loss.detach()))
        score = tail_rmse(weights())
        curve.add("free run", epoch, float(np.mean(losses)), score)
        if stopper.update(score, snapshot()):
            break
    if stopper.best_state is not None:
        lstm.load_state_dict(stopper.best_state["lstm"])  # type: ignore[arg-type]
        head.load_state_dict(stopper.best_state["head"])  # type: ignore[arg-type]
    return LSTMNarmax(operator, weights(), curve), split
