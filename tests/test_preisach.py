"""Preisach laws (Schreiber): Everett map, wiping-out, congruency, relays, exact inverse."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from edge.errors import ModelError
from edge.hysteresis.preisach import PreisachModel, everett_from_masses, masses_from_everett
from tests.conftest import random_walk
from tests.strategies import random_preisach, seeds


def relay_output(masses: np.ndarray, grid: np.ndarray, y_min: float, u: np.ndarray) -> np.ndarray:
    """Brute force: one 0/1 relay per cell (p, q): on at u >= grid[p], off at u <= grid[q]."""
    n = grid.size - 1
    cells = [(p, q) for p in range(1, n + 1) for q in range(p)]
    state = np.zeros(len(cells))
    out = np.empty(u.size)
    for i, v in enumerate(u):
        for c, (p, q) in enumerate(cells):
            if v >= grid[p] - 1e-12:
                state[c] = 1.0
            elif v <= grid[q] + 1e-12:
                state[c] = 0.0
        out[i] = y_min + sum(masses[p, q] * s for (p, q), s in zip(cells, state))
    return out


@given(seeds)
def test_everett_and_cell_masses_round_trip(seed):
    rng = np.random.default_rng(seed)
    masses = np.tril(rng.uniform(0, 1, (8, 8)), -1)
    np.testing.assert_allclose(masses_from_everett(everett_from_masses(masses)), masses, atol=1e-12)


@settings(max_examples=30)
@given(seeds)
def test_matches_a_brute_force_relay_model_on_grid_inputs(seed):
    rng = np.random.default_rng(seed)
    model = random_preisach(rng, 0.0, 1.0)
    n = model.n_levels - 1
    grid = np.linspace(0.0, 1.0, n + 1)
    levels = rng.integers(0, n + 1, 60)
    u = grid[levels]
    model.reset(0.0, "ascending")  # negative saturation = all relays off
    expected = relay_output(masses_from_everett(model.everett), grid, model.y_min, u)
    np.testing.assert_allclose(model.simulate(u), expected, atol=1e-9)


@given(seeds, st.floats(0.05, 0.95), st.floats(0.05, 0.95))
def test_wiping_out_forgets_a_loop_inside_the_new_extremum(seed, a_frac, b_frac):
    rng = np.random.default_rng(seed)
    model = random_preisach(rng, -1.0, 2.0)
    history = random_walk(rng, 50, -1, 2, 0.5)
    current, target = history[-1], 2.0 - 0.1 * rng.uniform()
    if target <= current:
        return
    a = current + a_frac * (target - current)  # excursion up to a, back down to b >= current
    b = current + b_frac * (a - current)
    model.reset(0.0, "centered")
    state = model.get_state()
    with_loop = model.simulate(np.r_[history, a, b, target])[-1]
    model.set_state(state)
    without_loop = model.simulate(np.r_[history, target])[-1]
    assert with_loop == pytest.approx(without_loop, abs=1e-10)


@given(seeds)
def test_minor_loops_between_the_same_extremes_are_congruent(seed):
    rng = np.random.default_rng(seed)
    model = random_preisach(rng, 0.0, 1.0)
    u1, u2 = 0.3, 0.6
    loop = np.r_[np.linspace(u1, u2, 15), np.linspace(u2, u1, 15)]
    shapes = []
    for history in ([1.0, 0.1, 0.9, u1], [0.8, 0.0, 0.7, 0.2, 0.95, u1]):
        model.reset(0.0, "ascending")
        model.simulate(np.array(history))
        y = model.simulate(loop)
        shapes.append(y - y[0])
    np.testing.assert_allclose(shapes[0], shapes[1], atol=1e-10)


@settings(max_examples=60)
@given(seeds)
def test_inverse_of_forward_is_identity(seed):
    rng = np.random.default_rng(seed)
    model = random_preisach(rng, -1.0, 2.0)
    u = random_walk(rng, 400, -1, 2, 0.3)
    model.reset(u[0], "centered")
    inverse = model.inverse()
    np.testing.assert_allclose(inverse.simulate(model.simulate(u)), u, atol=1e-9)


def test_stack_overflow_forgets_only_the_innermost_loop():
    model = PreisachModel((0.0, 1.0), everett_from_masses(np.tril(np.ones((6, 6)), -1)), 0.0, capacity=4)
    model.reset(0.0, "ascending")
    y = model.simulate(np.array([0.9, 0.1, 0.8, 0.2, 0.7, 0.3, 1.0]))  # deeper than 4 turning points
    assert y[-1] == pytest.approx(model.y_max)  # positive saturation is still exact
    assert np.all(np.isfinite(y))


def test_inverse_clamps_unreachable_outputs():
    model = random_preisach(np.random.default_rng(2))
    inverse = model.inverse()
    inverse.reset(model.y_min, "ascending")
    assert inverse.step(model.y_max + 5) == pytest.approx(model.u_range[1])
    assert inverse.saturated


def test_negative_density_is_refused():
    everett = everett_from_masses(np.tril(np.ones((4, 4)), -1))
    everett[3, 0] -= 2.5
    with pytest.raises(ModelError, match="not a valid Preisach density"):
        PreisachModel((0.0, 1.0), everett, 0.0)
