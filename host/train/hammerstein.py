"""Hammerstein model (Ai2019): MPI operator -> BP net 2-5-10-1 on [u, y_MPI] -> ARX.

* The MPI operator is identified as ``pmactl fit --model mpi`` does (from the known memory start).
* The BP net (tanh, 2-5-10-1 as in Ai2019 Fig 7) maps the extended input ``[u, y_MPI]`` to
  what the operator gets wrong: ``v = y_MPI + net(u, y_MPI)``. Its last layer starts at zero,
  so training starts from the MPI model and early stopping can only keep an improvement (from
  random weights the net never got back to the operator's own held-out error on the HIL).
  It is trained with **L-BFGS** on the whole training part at once: 81 weights and a smooth
  full-batch loss are where a quasi-Newton method converges in tens of iterations,
  deterministically and without a learning rate to tune (Ai2019's BP gradient descent
  reaches the same minimum far more slowly). Early stopping: every epoch (5 L-BFGS
  iterations) scores the held-out tail.
* The ARX part (Ai2019 eqs 9-11) gives the dynamics:
  ``y(k) = sum_{i=1..na} a_i y(k-i) + sum_{j=0..nb-1} b_j v(k-j)`` with v the net output,
  unit static gain, no offset (the net carries the statics) and ``b >= 0`` (a lag; see
  ``fit_arx``). Orders ``na in 0..3``, ``nb in 1..3``
  are chosen by AIC (eq 17, ``N ln(sigma^2) + 2 p``) on the *simulation* error: the model is
  used in free run, and the equation error at 100 Hz and more rewards ``a_1 -> 1`` and says
  nothing about free run. Coefficients by least squares on the simulation error; unstable
  candidates are refused. The chosen ARX is kept only if it lowers the held-out tail's
  simulation error; otherwise the static net alone (``na = 0, nb = 1``) is the model.

The step (exported to ONNX) carries ``y_lags`` (3) and ``v_lags`` (2); unused orders have zero
coefficients, so the graph's shapes do not depend on the chosen orders.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.signal import lfilter

from host.train.common import Curve, EarlyStopping, Split, normaliser, progress
from host.train.operators import IdentifiedOperator, identify_mpi

MAX_NA, MAX_NB = 3, 3
SIZES = (2, 5, 10, 1)


@dataclass
class HammersteinWeights:
    """BP net layers (weights (out, in), biases), input normalisation, output scale, ARX."""

    layers: list[tuple[NDArray[np.float32], NDArray[np.float32]]]
    mean: NDArray[np.float32]
    std: NDArray[np.float32]
    y_mean: float
    y_std: float
    a: NDArray[np.float64]  # (3,) zero beyond na
    b: NDArray[np.float64]  # (3,) zero beyond nb
    c: float
    orders: tuple[int, int]

    def static(self, u: NDArray[np.float64], n: NDArray[np.float64]) -> NDArray[np.float64]:
        """Net output ``v = y_MPI + net(u, y_MPI)`` [output units] (float32 arithmetic, as exported)."""
        x = ((np.column_stack([u, n]).astype(np.float32) - self.mean) / self.std).astype(np.float32)
        for i, (w, bias) in enumerate(self.layers):
            x = x @ w.T + bias
            if i < len(self.layers) - 1:
                x = np.tanh(x)
        return (n.astype(np.float32) + x[:, 0] * np.float32(self.y_std)).astype(np.float64)


def arx_simulate(
    a: NDArray[np.float64], b: NDArray[np.float64], c: float, v: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Free-run ARX output, started at the steady state of ``v[0]``."""
    den = np.concatenate([[1.0], -a])
    gain = float(np.sum(b)) / float(np.sum(den))
    level = c / float(np.sum(den))
    # shift the input by its first value so the filter starts at rest in that steady state
    return np.asarray(lfilter(b, den, v - v[0])) + gain * v[0] + level


def _stable(a: NDArray[np.float64]) -> bool:
    return a.size == 0 or bool(np.all(np.abs(np.roots(np.concatenate([[1.0], -a]))) < 0.999))


def _unit_gain_b(a: NDArray[np.float64], raw: NDArray[np.float64]) -> NDArray[np.float64]:
    """Non-negative ``b`` scaled to unit static gain, ``sum b = 1 - sum a`` (the net carries the statics)."""
    total = float(np.sum(raw))
    return (1.0 - float(np.sum(a))) * (raw / total if total > 1e-12 else np.eye(raw.size)[0])


def fit_arx(
    v: NDArray[np.float64], y: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], float, tuple[int, int], dict[str, float]]:
    """ARX orders by AIC on the simulation error (see module docstring); coefficients padded to 3.

    Constraints: unit static gain and no offset (the BP net is trained to give the output
    itself; a free gain is ill-posed with poles near 1 at high sample rates), and ``b >= 0``
    (a lag, as an actuator's output has; an unconstrained fit on the piezo's smooth 20 Hz
    triangles found a differentiating ``b = [11.6, -22.1, 10.6]`` that turned every input step
    of the held-out runs into a spike of 5x the output range).
    """
    best: tuple[float, NDArray[np.float64], NDArray[np.float64], tuple[int, int]] | None = None
    table: dict[str, float] = {}
    for na, nb in itertools.product(range(MAX_NA + 1), range(1, MAX_NB + 1)):

        def residual(theta: NDArray[np.float64], na: int = na) -> NDArray[np.float64]:
            a = theta[:na]
            if not _stable(a):
                return np.full(y.size, 1e3 * float(np.ptp(y)))
            return arx_simulate(a, _unit_gain_b(a, theta[na:]), 0.0, v) - y

        lower = np.concatenate([np.full(na, -np.inf), np.zeros(nb)])
        start = np.concatenate([np.zeros(na), np.eye(nb)[0]])
        theta = least_squares(residual, start, bounds=(lower, np.inf), max_nfev=200).x if na + nb > 1 else start
        if not _stable(theta[:na]):
            continue
        mse = float(np.mean(residual(theta) ** 2))
        n_params = na + nb - 1  # the gain constraint removes one
        aic = y.size * float(np.log(max(mse, 1e-300))) + 2 * n_params
        table[f"na={na},nb={nb}"] = aic
        if best is None or aic < best[0]:
            best = (aic, theta[:na], _unit_gain_b(theta[:na], theta[na:]), (na, nb))
    assert best is not None  # na = 0, nb = 1 (the static net alone) is always there
    _, a, b, orders = best
    return np.pad(a, (0, MAX_NA - a.size)), np.pad(b, (0, MAX_NB - b.size)), 0.0, orders, table


@dataclass
class Hammerstein:
    """A trained Hammerstein model; ``simulate(u, branch)`` runs it in free run."""

    operator: IdentifiedOperator
    weights: HammersteinWeights
    aic: dict[str, float]
    curve: Curve = field(default_factory=Curve)
    kind: str = "hammerstein"

    def simulate(self, u: NDArray[np.float64], branch: str) -> NDArray[np.float64]:
        """Free-run output [output units] for ``u`` from a start in ``branch`` at ``u[0]``."""
        n = self.operator.operator.simulate(u, branch)
        w = self.weights
        return arx_simulate(w.a, w.b, w.c, w.static(u, n))


def train_hammerstein(
    u: NDArray[np.float64],
    y: NDArray[np.float64],
    split_fn: Callable[[int], Split],
    *,
    seed: int = 0,
    epochs: int = 60,
    quiet: bool = True,
    patience: int = 8,
) -> tuple[Hammerstein, Split]:
    """Identify MPI, train the BP net (L-BFGS), choose and fit the ARX part. ``split_fn(start) -> Split``."""
    import torch
    from torch import nn

    # MPI on the whole record, as ``pmactl fit --model mpi`` (the baseline it is compared with);
    # the tail is held out from the net's training and the ARX fit only
    operator = identify_mpi(u, y)
    split = split_fn(operator.start_index)
    n_all = operator.operator.simulate(u[split.start :], operator.start_branch)
    u_all, y_all = u[split.start :], y[split.start :]
    n_train = split.tail - split.start
    features = np.column_stack([u_all, n_all])
    mean = np.array([normaliser(features[:n_train, j])[0] for j in range(2)])
    std = np.array([normaliser(features[:n_train, j])[1] for j in range(2)])
    y_mean, y_std = normaliser(y_all[:n_train] - n_all[:n_train])

    layers: list[nn.Module] = []
    for i, (a, b) in enumerate(zip(SIZES, SIZES[1:])):
        layers.append(nn.Linear(a, b))
        if i < len(SIZES) - 2:
            layers.append(nn.Tanh())
    net = nn.Sequential(*layers)
    last = layers[-1]
    assert isinstance(last, nn.Linear)
    nn.init.zeros_(last.weight)  # start at the MPI model itself: early stopping can only improve on it
    nn.init.zeros_(last.bias)
    x = torch.as_tensor((features[:n_train] - mean) / std, dtype=torch.float32)
    target = torch.as_tensor((y_all[:n_train] - n_all[:n_train]) / y_std, dtype=torch.float32)
    optimiser = torch.optim.LBFGS(net.parameters(), lr=1.0, max_iter=5, history_size=20, line_search_fn="strong_wolfe")
    curve, stopper = Curve(), EarlyStopping(patience)

    def closure() -> torch.Tensor:
        optimiser.zero_grad()
        loss = torch.mean((net(x)[:, 0] - target) ** 2)
        loss.backward()
        return loss

    def weights(
        a: NDArray[np.float64], b: NDArray[np.float64], c: float, orders: tuple[int, int]
    ) -> HammersteinWeights:
        linears = [m for m in net if isinstance(m, nn.Linear)]
        return HammersteinWeights(
            [
                (m.weight.detach().numpy().astype(np.float32).copy(), m.bias.detach().numpy().astype(np.float32).copy())
                for m in linears
            ],
            mean.astype(np.float32),
            std.astype(np.float32),
            float(y_mean),
            float(y_std),
            a,
            b,
            c,
            orders,
        )

    no_a, unit_b = np.zeros(MAX_NA), np.array([1.0, 0.0, 0.0])  # the static net alone

    def tail_score() -> float:
        static = weights(no_a, unit_b, 0.0, (0, 1)).static(u_all[n_train:], n_all[n_train:])
        return float(np.sqrt(np.mean((static - y_all[n_train:]) ** 2)))

    stopper.update(tail_score(), {"net": net.state_dict()})  # the MPI alone: the net must beat it
    for epoch in progress(epochs, "hammerstein BP net (L-BFGS)", quiet):
        loss = float(optimiser.step(closure).detach())
        score = tail_score()
        curve.add("BP net (L-BFGS)", epoch, loss, score)
        if stopper.update(score, {"net": net.state_dict()}):
            break
    if stopper.best_state is not None:
        net.load_state_dict(stopper.best_state["net"])  # type: ignore[arg-type]
    static = weights(no_a, unit_b, 0.0, (0, 1)).static(u_all, n_all)
    arx_a, arx_b, arx_c, orders, aic = fit_arx(static[:n_train], y_all[:n_train])
    # the orders AIC chose are validated on the tail: dynamics that do not lower its simulation
    # error are not kept (on the real muscle they raised the held-out RMSE by 17 %)
    tail_static = float(np.sqrt(np.mean((static[n_train:] - y_all[n_train:]) ** 2)))
    dynamic = arx_simulate(arx_a, arx_b, arx_c, static)
    tail_dynamic = float(np.sqrt(np.mean((dynamic[n_train:] - y_all[n_train:]) ** 2)))
    aic["tail_rmse_static"], aic["tail_rmse_arx"] = tail_static, tail_dynamic
    if not tail_dynamic < tail_static:
        arx_a, arx_b, arx_c, orders = no_a, unit_b, 0.0, (0, 1)
    return Hammerstein(operator, weights(arx_a, arx_b, arx_c, orders), aic, curve), split
