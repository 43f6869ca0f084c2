"""A neural state-space model: a linear model plus a small net, trained on simulation error.

The model, with ``u`` and ``y`` scaled by their training standard deviations (no offset, so the
rest state ``x = 0, u = 0`` stays an equilibrium and "from rest" means ``x = 0``)::

    x(k+1) = A x(k) + B u(k) + W2 (tanh(W1 [x(k), u(k)] + b1) - tanh(b1))
    y(k)   = C x(k)

The linear part starts from an ARX fit (equation error, least squares; the order up to
``state_order`` whose free run fits best) in real Schur form; the net's output layer starts at
zero, so training starts from the linear model and the net learns what it misses (hysteresis inside a resonance,
for the Bouc-Wen benchmark: ``bench/bouc_wen.py``). This is the model class of Forgione & Piga
(2021) and Beintema et al. (2021, SUBNET), minus everything a 1 kHz edge step cannot afford.

Training (tunables in :class:`StateSpaceSettings`): Adam on the *simulation* error of batches of
random subsequences of ``window`` samples (truncated simulation error). Each subsequence's
initial state comes from an *encoder*, a small net of the ``encoder_lags`` inputs and outputs
before it (the state of a linear-plus-net model is observable from a short past), trained with
the model; it is used only in training and scoring, never on the edge, where the model runs
free from rest. After every epoch the held-out tail is run free from the encoder's state in
several lanes at once (numpy, float64); the best weights are kept and training stops when the
smoothed score has not improved for ``patience`` epochs (:class:`host.train.common.EarlyStopping`).
Same seed, same model (torch on one thread, deterministic; numpy generator seeded).

:func:`export_onnx` writes the step graph with explicit state (``u``, ``x`` -> ``y``, ``x_next``)
for onnxruntime; :func:`simulate_numpy` is the same step in numpy.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from host.train.common import Curve, EarlyStopping, Split, progress, seed_everything

if TYPE_CHECKING:  # torch is imported where training runs (the train extra)
    import torch


@dataclass(frozen=True)
class StateSpaceSettings:
    """The trainer's tunables in one place (sizes in samples).

    Provenance: chosen on the Bouc-Wen benchmark's training realisations by their held-out tail
    score (bench/bouc_wen.py, seed 0; 120 epochs): 3 states stalled at 1.0e-4 m (the linear
    part's order: 2 mechanical states + 1 hysteretic), 4 states reached 3.6e-5 and 5 states
    2.7e-5; Adam at 5e-3 with a patience of 12 epochs stopped on the plateau before the drop that
    a rate decaying from 3e-3 reaches (the drop comes after 30-40 epochs), hence the patience.
    The net, encoder, window and batch sizes are those of the cited works scaled down to a
    2-core machine, not tuned.
    """

    state_order: int = 5
    hidden: int = 32
    encoder_lags: int = 16
    encoder_hidden: int = 32
    window: int = 128
    batch: int = 64
    steps_per_epoch: int = 40
    lr: float = 3e-3
    lr_final: float = 1e-4  # cosine decay over the epochs to this rate
    net_init_scale: float = (
        0.0  # largest initial entry of the output layer W2; 0: the start is exactly the linear model
    )
    score_horizon: int = 2048  # samples each held-out lane runs free
    max_score_lanes: int = 8
    patience: int = 30
    smoothing: float = 0.5


SETTINGS = StateSpaceSettings()


@dataclass
class StateSpaceWeights:
    """The trained step in numpy (scaled units inside; ``u_scale`` [input units], ``y_scale`` [output units])."""

    a: NDArray[np.float64]  # (nx, nx)
    b: NDArray[np.float64]  # (nx,)
    c: NDArray[np.float64]  # (nx,)
    w1: NDArray[np.float64]  # (hidden, nx + 1)
    b1: NDArray[np.float64]  # (hidden,)
    w2: NDArray[np.float64]  # (nx, hidden)
    u_scale: float
    y_scale: float

    @property
    def state_order(self) -> int:
        return int(self.a.shape[0])

    def as_dict(self) -> dict[str, object]:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in self.__dict__.items()}


@dataclass
class NeuralStateSpace:
    """A trained neural state-space model; ``simulate(u, branch)`` runs it free from rest."""

    weights: StateSpaceWeights
    curve: Curve = field(default_factory=Curve)
    kind: str = "state-space"

    def simulate(self, u: NDArray[np.float64], branch: str = "rest") -> NDArray[np.float64]:
        """Free-run output [output units] for ``u`` from rest (``branch`` is accepted for the shared
        ``simulate(u, branch)`` contract; a state-space model has no branch, it starts at ``x = 0``)."""
        return simulate_numpy(self.weights, np.asarray(u, dtype=np.float64))


def simulate_numpy(
    w: StateSpaceWeights, u: NDArray[np.float64], x0: NDArray[np.float64] | None = None
) -> NDArray[np.float64]:
    """Free run over ``u`` (T,) or lanes (T, L) from ``x0`` (nx,) / (L, nx) (rest by default)."""
    u = np.asarray(u, dtype=np.float64)
    lanes = u.ndim == 2
    us = (u if lanes else u[:, None]) / w.u_scale
    x = (
        np.zeros((us.shape[1], w.state_order))
        if x0 is None
        else np.array(x0, dtype=np.float64).reshape(-1, w.state_order)
    )
    w1x, w1u = w.w1[:, :-1].T.copy(), w.w1[:, -1].copy()
    offset = np.tanh(w.b1)
    a_t, w2_t = w.a.T.copy(), w.w2.T.copy()
    y = np.empty(us.shape)
    for k in range(us.shape[0]):
        uk = us[k][:, None]
        y[k] = x @ w.c
        x = x @ a_t + uk * w.b + (np.tanh(x @ w1x + uk * w1u + w.b1) - offset) @ w2_t
    y *= w.y_scale
    return y if lanes else y[:, 0]


def arx_init(
    u: NDArray[np.float64], y: NDArray[np.float64], order: int
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The linear start: ARX(n, n, delay 1) by least squares for n = 1..order, the one whose free
    run fits ``y`` best, as (A, B, C) of size ``order`` in real Schur form.

    ``y(k) = sum a_i y(k-i) + sum b_i u(k-i)`` is first written in observer canonical form
    (``x1 = y``, ``A = [a | I; 0]``, ``B = b``, zeros beyond n), then turned into Schur form.
    Poles at or outside radius 0.99 are pulled inside it: an unstable start would blow up every
    window. The equation error picks the coefficients, the simulation error
    the order: a high-order equation-error fit can simulate far worse than a low-order one.
    """
    from scipy.signal import lfilter

    best: tuple[float, NDArray[np.float64], NDArray[np.float64]] | None = None
    for n in range(1, order + 1):
        rows = np.column_stack(
            [y[n - i : y.size - i] for i in range(1, n + 1)] + [u[n - i : u.size - i] for i in range(1, n + 1)]
        )
        theta, *_ = np.linalg.lstsq(rows, y[n:], rcond=None)
        a_coef, b_coef = np.asarray(theta[:n], dtype=np.float64), np.asarray(theta[n:], dtype=np.float64)
        poles = np.roots(np.concatenate([[1.0], -a_coef]))
        if np.max(np.abs(poles), initial=0.0) >= 0.99:
            poles = np.where(np.abs(poles) >= 0.99, 0.99 * poles / np.abs(poles), poles)
            a_coef = -np.real(np.poly(poles))[1:]
        simulated = lfilter(np.concatenate([[0.0], b_coef]), np.concatenate([[1.0], -a_coef]), u)
        error = float(np.mean((simulated - y) ** 2))
        if np.isfinite(error) and (best is None or error < best[0]):
            best = (error, np.pad(a_coef, (0, order - n)), np.pad(b_coef, (0, order - n)))
    assert best is not None
    a = np.zeros((order, order))
    a[:, 0] = best[1]
    a[:-1, 1:] = np.eye(order - 1)
    c = np.zeros(order)
    c[0] = 1.0
    # the companion form's coefficients fix its poles badly (float32 rounding of a 5th-order
    # polynomial with poles near 1 can make it unstable); the real Schur form, an orthogonal change
    # of state, holds the poles on its (block) diagonal where rounding barely moves them
    from scipy.linalg import schur

    t, z = schur(a, output="real")
    return np.asarray(t, dtype=np.float64), z.T @ best[2], c @ z


def _lag_matrix(
    u: NDArray[np.float64], y: NDArray[np.float64], starts: NDArray[np.int64], lags: int
) -> NDArray[np.float64]:
    """Encoder inputs: the ``lags`` inputs and outputs before each start, (len(starts), 2 lags)."""
    index = starts[:, None] - lags + np.arange(lags)[None, :]
    return np.concatenate([u[index], y[index]], axis=1)


class _Torch:
    """The model and its encoder as torch modules (built lazily: torch is the train extra)."""

    def __init__(
        self, a: NDArray[np.float64], b: NDArray[np.float64], c: NDArray[np.float64], s: StateSpaceSettings
    ) -> None:
        import torch
        from torch import nn

        f = lambda v: nn.Parameter(torch.as_tensor(np.asarray(v), dtype=torch.float32))  # noqa: E731
        nx = a.shape[0]
        self.a, self.b, self.c = f(a), f(b), f(c)
        self.w1 = nn.Linear(nx + 1, s.hidden)
        self.w2 = nn.Linear(s.hidden, nx, bias=False)
        with torch.no_grad():
            self.w2.weight.mul_(s.net_init_scale / max(1e-12, float(self.w2.weight.abs().max())))
        self.encoder = nn.Sequential(
            nn.Linear(2 * s.encoder_lags, s.encoder_hidden), nn.Tanh(), nn.Linear(s.encoder_hidden, nx)
        )
        self.modules = nn.ModuleDict({"w1": self.w1, "w2": self.w2, "encoder": self.encoder})

    def parameters(self) -> list[torch.nn.Parameter]:
        return [self.a, self.b, self.c, *self.modules.parameters()]

    def simulate(self, x: torch.Tensor, u: torch.Tensor) -> torch.Tensor:
        """Outputs (B, T) of windows ``u`` (B, T) from states ``x`` (B, nx), scaled units."""
        import torch

        offset = torch.tanh(self.w1.bias)
        outputs = []
        for k in range(u.shape[1]):
            uk = u[:, k : k + 1]
            outputs.append(x @ self.c)
            x = x @ self.a.T + uk * self.b + self.w2(torch.tanh(self.w1(torch.cat([x, uk], 1))) - offset)
        return torch.stack(outputs, 1)

    def weights(self, u_scale: float, y_scale: float) -> StateSpaceWeights:
        g = lambda t: t.detach().numpy().astype(np.float64).copy()  # noqa: E731
        return StateSpaceWeights(
            g(self.a), g(self.b), g(self.c), g(self.w1.weight), g(self.w1.bias), g(self.w2.weight), u_scale, y_scale
        )

    def state(self) -> dict[str, object]:
        return {"abc": [t.detach().clone() for t in (self.a, self.b, self.c)], "nets": self.modules.state_dict()}

    def load(self, state: dict[str, object]) -> None:
        import torch

        with torch.no_grad():
            for p, v in zip((self.a, self.b, self.c), state["abc"]):  # type: ignore[call-overload]
                p.copy_(v)
        self.modules.load_state_dict(state["nets"])  # type: ignore[arg-type]


class _TailScore:
    """Held-out free-run RMSE [scaled output] over lanes of the tail, each started by the encoder."""

    def __init__(self, us: NDArray[np.float64], ys: NDArray[np.float64], tail: int, s: StateSpaceSettings) -> None:
        length = us.size - tail
        lanes = int(np.clip(length // s.score_horizon, 1, s.max_score_lanes))
        horizon = length // lanes
        self.starts = tail + horizon * np.arange(lanes)
        index = self.starts[None, :] + np.arange(horizon)[:, None]
        self.u, self.y = us[index], ys[index]
        self.past = _lag_matrix(us, ys, self.starts, s.encoder_lags)

    def __call__(self, model: _Torch) -> float:
        import torch

        with torch.no_grad():
            x0 = model.encoder(torch.as_tensor(self.past, dtype=torch.float32)).numpy().astype(np.float64)
        w = model.weights(1.0, 1.0)
        with np.errstate(all="ignore"):
            predicted = simulate_numpy(w, self.u, x0)
        score = float(np.sqrt(np.mean((predicted - self.y) ** 2)))
        return score if np.isfinite(score) else float("inf")


def train_state_space(
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    split_fn: Callable[[int], Split],
    *,
    seed: int = 0,
    epochs: int = 200,
    quiet: bool = True,
    settings: StateSpaceSettings = SETTINGS,
) -> tuple[NeuralStateSpace, Split]:
    """Train on ``u, y`` (see module docstring); ``split_fn(0)`` gives the training part and the tail.

    The record needs no hysteresis memory start (the encoder estimates the state), so the split
    starts at sample 0. Returns the model with the kept (best held-out) weights and the split.
    """
    import torch

    s = settings
    seed_everything(seed)  # the caller may have seeded already (train_model does); the model must not depend on it
    split = split_fn(0)
    u_scale = float(np.std(u[: split.tail])) or 1.0
    y_scale = float(np.std(y[: split.tail])) or 1.0
    us, ys = np.asarray(u, dtype=np.float64) / u_scale, np.asarray(y, dtype=np.float64) / y_scale
    a, b, c = arx_init(us[: split.tail], ys[: split.tail], s.state_order)
    model = _Torch(a, b, c, s)
    params = model.parameters()
    optimiser = torch.optim.Adam(params, lr=s.lr)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, max(1, epochs * s.steps_per_epoch), s.lr_final)
    u_t, y_t = torch.as_tensor(us, dtype=torch.float32), torch.as_tensor(ys, dtype=torch.float32)
    rng = np.random.default_rng(seed)
    first, last = s.encoder_lags, split.tail - s.window  # window starts inside the training part
    if last <= first:
        from edge.errors import DataError

        raise DataError(
            f"too short to train a state-space model: {split.tail} training samples, need more than "
            f"{s.encoder_lags + s.window} (encoder lags + window); record longer"
        )
    score = _TailScore(us, ys, split.tail, s)
    stopper = EarlyStopping(s.patience, smoothing=s.smoothing)
    curve = Curve()
    stopper.update(score(model), model.state())
    for epoch in progress(epochs, "state-space", quiet):
        losses = []
        for _ in range(s.steps_per_epoch):
            starts = rng.integers(first, last + 1, size=s.batch)
            index = torch.as_tensor(starts[:, None] + np.arange(s.window)[None, :])
            past = torch.as_tensor(_lag_matrix(us, ys, starts, s.encoder_lags), dtype=torch.float32)
            predicted = model.simulate(model.encoder(past), u_t[index])
            loss = torch.mean((predicted - y_t[index]) ** 2)
            optimiser.zero_grad()
            loss.backward()
            torch.nn.utils.clip_grad_norm_(params, 1.0)
            optimiser.step()
            schedule.step()
            losses.append(float(loss.detach()))
        tail_rmse = score(model)
        curve.add("simulation error", epoch, float(np.mean(losses)), tail_rmse * y_scale)
        if stopper.update(tail_rmse, model.state()):
            break
    if stopper.best_state is not None:
        model.load(stopper.best_state)
    return NeuralStateSpace(model.weights(u_scale, y_scale), curve), split


def export_onnx(w: StateSpaceWeights, path: str | Path) -> Path:
    """Write the step graph with explicit state: inputs ``u`` (1, 1), ``x`` (1, nx) [float32];
    outputs ``y`` (1, 1) = the output at this step, ``x_next`` (1, nx). Start at ``x = 0`` (rest)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    f32 = lambda name, v: numpy_helper.from_array(np.asarray(v, dtype=np.float32), name)  # noqa: E731
    nx = w.state_order
    inits = [
        f32("inv_u_scale", [[1.0 / w.u_scale]]),
        f32("a_t", w.a.T),
        f32("b_row", w.b[None, :]),
        f32("c_col", (w.c * w.y_scale)[:, None]),
        f32("w1x_t", w.w1[:, :-1].T),
        f32("w1u_row", w.w1[:, -1][None, :]),
        f32("b1", w.b1[None, :]),
        f32("tanh_b1", np.tanh(w.b1)[None, :]),
        f32("w2_t", w.w2.T),
    ]
    n = helper.make_node
    nodes = [
        n("Mul", ["u", "inv_u_scale"], ["us"]),
        n("MatMul", ["x", "c_col"], ["y"]),
        n("MatMul", ["x", "a_t"], ["ax"]),
        n("Mul", ["us", "b_row"], ["bu"]),
        n("MatMul", ["x", "w1x_t"], ["hx"]),
        n("Mul", ["us", "w1u_row"], ["hu"]),
        n("Add", ["hx", "hu"], ["h0"]),
        n("Add", ["h0", "b1"], ["h1"]),
        n("Tanh", ["h1"], ["h2"]),
        n("Sub", ["h2", "tanh_b1"], ["h3"]),
        n("MatMul", ["h3", "w2_t"], ["fx"]),
        n("Add", ["ax", "bu"], ["lin"]),
        n("Add", ["lin", "fx"], ["x_next"]),
    ]
    graph = helper.make_graph(
        nodes,
        "state_space_step",
        [
            helper.make_tensor_value_info("u", TensorProto.FLOAT, [1, 1]),
            helper.make_tensor_value_info("x", TensorProto.FLOAT, [1, nx]),
        ],
        [
            helper.make_tensor_value_info("y", TensorProto.FLOAT, [1, 1]),
            helper.make_tensor_value_info("x_next", TensorProto.FLOAT, [1, nx]),
        ],
        inits,
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)], producer_name="pmactl")
    model.ir_version = 8
    onnx.checker.check_model(model)
    path = Path(path)
    onnx.save(model, str(path))
    return path


def simulate_onnx(path: str | Path, u: NDArray[np.float64], nx: int) -> NDArray[np.float64]:
    """Free run of an exported step graph in onnxruntime from rest (one session, one thread)."""
    import onnxruntime as ort

    options = ort.SessionOptions()
    options.intra_op_num_threads = 1
    options.inter_op_num_threads = 1
    session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
    x = np.zeros((1, nx), dtype=np.float32)
    out = np.empty(len(u))
    for k, uk in enumerate(np.asarray(u, dtype=np.float32)):
        y, x = session.run(None, {"u": np.array([[uk]], dtype=np.float32), "x": x})
        out[k] = float(y[0, 0])
    return out


def save_state_space(model: NeuralStateSpace, directory: str | Path, record: dict[str, object]) -> Path:
    """Write ``step.onnx``, ``model.json`` (weights, step contract, training record and curve) and
    ``training_curve.png`` to ``directory`` (created; its parent must exist), as ``save_model`` does
    for the other nets."""
    import json

    directory = Path(directory)
    directory.mkdir(exist_ok=True)
    export_onnx(model.weights, directory / "step.onnx")
    curve_png = model.curve.save_png(directory / "training_curve.png", f"{model.kind} training")
    description = {
        "kind": model.kind,
        "step": {
            "file": "step.onnx",
            "inputs": {"u": [1, 1], "x": [1, model.weights.state_order]},
            "outputs": {"y": [1, 1], "x_next": [1, model.weights.state_order]},
            "initial_state": "zeros (rest)",
        },
        "weights": model.weights.as_dict(),
        "training": {**record, "curve": model.curve.as_dict(), "curve_png": curve_png.name},
    }
    (directory / "model.json").write_text(json.dumps(description, indent=2) + "\n")
    return directory
