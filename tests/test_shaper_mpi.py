"""Dead-zone shaper (Ai2019 eqs 6, 7, 14) and the MPI model (eq 8, 12)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from edge.errors import ModelError
from edge.hysteresis.shaper import MonotonePiecewiseLinear, PiecewiseLinearKernel, dead_zone, dead_zone_form
from tests.conftest import random_walk
from tests.strategies import inverse_round_trip, random_mpi, seeds


def test_dead_zone_operator_matches_eq6():
    x = np.array([-2.0, -0.5, 0.0, 0.5, 2.0])
    np.testing.assert_allclose(dead_zone(x, 1.0), [0, 0, 0, 0, 1.0])
    np.testing.assert_allclose(dead_zone(x, -1.0), [-1.0, 0, 0, 0, 0])
    np.testing.assert_allclose(dead_zone(x, 0.0), x)


@given(seeds)
def test_knot_form_equals_the_dead_zone_sum(seed):
    rng = np.random.default_rng(seed)
    g = np.r_[0.0, np.sort(rng.uniform(-4, 4, 5))]
    v = np.r_[rng.uniform(0.5, 2.0), rng.uniform(-0.1, 0.5, 5)]
    shaper = MonotonePiecewiseLinear.from_dead_zones(g, v)
    x = np.linspace(-6, 6, 301)
    direct = sum(vj * dead_zone(x, gj) for gj, vj in zip(g, v))
    np.testing.assert_allclose(shaper(x), direct, atol=1e-12)
    kernel = PiecewiseLinearKernel(shaper.kernel_stage()[1])
    np.testing.assert_allclose([kernel.step(xi) for xi in x], direct, atol=1e-12)


def test_eq14_inverse_dead_zone_parameters_equal_the_swapped_map():
    """Ai2019 eq 14 with indices from 0: g'_j = sum_{k<=j} v_k (g_j - g_k),
    v'_0 = 1/v_0, v'_j = -v_j / (S_j S_{j-1}). The extracted text's '1 +' belongs to a PI
    part with an implicit unit linear weight; for the dead zones the sums start at v_0."""
    g = np.array([0.0, 1.0, 2.0, 3.5])
    v = np.array([1.2, 0.5, -0.3, 0.2])
    s = np.cumsum(v)
    g_inv_eq14 = np.array([sum(v[k] * (g[j] - g[k]) for k in range(j + 1)) for j in range(4)])
    v_inv_eq14 = np.r_[1 / v[0], -v[1:] / (s[1:] * s[:-1])]
    g_inv, v_inv = dead_zone_form(MonotonePiecewiseLinear.from_dead_zones(g, v).inverse())
    np.testing.assert_allclose(g_inv, g_inv_eq14)
    np.testing.assert_allclose(v_inv, v_inv_eq14)


def test_non_monotone_shaper_is_refused():
    with pytest.raises(ModelError, match="strictly increasing"):
        MonotonePiecewiseLinear.from_dead_zones([0.0, 1.0, 2.0], [1.0, -1.5, 2.0])


@settings(max_examples=50)
@given(seeds, st.sampled_from(["ascending", "descending"]))
def test_mpi_inverse_of_forward_is_identity(seed, branch):
    rng = np.random.default_rng(seed)
    forward = random_mpi(rng)
    u = random_walk(rng, 300, -2, 3, 0.4)
    _, recovered = inverse_round_trip(forward, u, branch)
    np.testing.assert_allclose(recovered, u, atol=1e-8)


@given(seeds)
def test_mpi_is_the_shaper_applied_to_its_pi_part(seed):
    rng = np.random.default_rng(seed)
    model = random_mpi(rng)
    u = random_walk(rng, 200, -2, 3, 0.4)
    model.reset(0.0, "ascending")
    state = model.get_state()
    y = model.simulate(u)
    model.pi.set_state(state)
    np.testing.assert_allclose(y, model.shaper(model.pi.simulate(u)), atol=1e-12)


def test_mpi_inverse_clamps_and_flags_unreachable_outputs():
    model = random_mpi(np.random.default_rng(5))
    inverse = model.inverse()
    inverse.reset(inverse.input_range[0], "descending")
    assert inverse.step(inverse.input_range[1] + 50.0) == pytest.approx(model.pi.actuator_range[1])
    assert inverse.saturated
