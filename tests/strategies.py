"""Hypothesis strategies for valid random hysteresis models and inputs."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

from edge.hysteresis.dpi import DPIModel
from edge.hysteresis.mpi import MPIModel
from edge.hysteresis.pi import PIModel
from edge.hysteresis.preisach import PreisachModel, everett_from_masses
from edge.hysteresis.shaper import MonotonePiecewiseLinear

seeds = st.integers(min_value=0, max_value=2**32 - 1)


def random_pi(rng: np.random.Generator, lo: float = -2.0, hi: float = 3.0) -> PIModel:
    """Invertible PI: thresholds within half the range, positive partial weight sums."""
    n = int(rng.integers(1, 9))
    gaps = rng.uniform(0.05, 1.0, n - 1)
    thresholds = np.r_[0.0, np.cumsum(gaps) / max(gaps.sum(), 1e-9) * (hi - lo) * 0.45]
    weights = np.r_[rng.uniform(0.2, 2.0), rng.uniform(-0.1, 1.0, n - 1)]
    weights = np.where(np.cumsum(weights) <= 0.05, 0.1, weights)
    return PIModel(
        thresholds,
        weights,
        output_offset=float(rng.normal()),
        input_shift=float(rng.normal(0, 0.3)),
        actuator_range=(lo, hi),
    )


def random_mpi(rng: np.random.Generator, lo: float = -2.0, hi: float = 3.0) -> MPIModel:
    pi = random_pi(rng, lo, hi)
    knots = np.sort(rng.uniform(-5, 5, int(rng.integers(1, 6))))
    knots = np.unique(knots)
    values = np.cumsum(np.r_[0.0, np.diff(knots) * rng.uniform(0.2, 3.0, knots.size - 1)])
    shaper = MonotonePiecewiseLinear(knots, values + rng.normal(), rng.uniform(0.2, 3), rng.uniform(0.2, 3))
    return MPIModel(pi, shaper)


def random_dpi(rng: np.random.Generator, symmetric: bool = False, compensate: bool = True) -> DPIModel:
    n = int(rng.integers(1, 12))
    dxe = rng.uniform(0.1, 1.0, n)
    dye = rng.uniform(0.1, 2.0, n)
    dxc = dxe.copy() if symmetric else dxe * rng.uniform(0.5, 1.5, n)
    dyc = dye.copy() if symmetric else dye * rng.uniform(0.5, 1.5, n)
    return DPIModel(dxe, dye, dxc, dyc, x0=float(rng.normal()), y0=float(rng.normal()), compensate=compensate)


def random_preisach(rng: np.random.Generator, lo: float = -1.0, hi: float = 2.0) -> PreisachModel:
    n = int(rng.integers(2, 14))
    masses = np.tril(rng.uniform(0.0, 1.0, (n + 1, n + 1)) * (rng.uniform(size=(n + 1, n + 1)) < 0.6), -1)
    for p in range(1, n + 1):
        masses[p, p - 1] = rng.uniform(0.05, 1.0)
    return PreisachModel((lo, hi), everett_from_masses(masses), y_min=float(rng.normal()))


def inverse_round_trip(forward, u: np.ndarray, branch: str):
    """``forward`` from ``u[0]`` on ``branch``, its inverse from the matching output on the same
    branch; returns (inverse, the input the inverse recovers from forward's output)."""
    forward.reset(u[0], branch)
    inverse = forward.inverse()
    inverse.reset(forward.step(u[0]), branch)
    return inverse, inverse.simulate(forward.simulate(u))
