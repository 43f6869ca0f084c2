"""Play operator and PI model laws (Ai2019 eqs 2-5, 14)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from edge.errors import ModelError
from edge.hysteresis.pi import PIModel, exponential_pi_parameters, inverse_pi_parameters
from tests.conftest import random_walk
from tests.strategies import inverse_round_trip, random_pi, seeds


@given(seeds)
def test_play_output_stays_within_threshold_of_input(seed):
    rng = np.random.default_rng(seed)
    model = PIModel([0.0, 0.3, 0.9], [1.0, 0.5, 0.2])
    u = random_walk(rng, 300, -2, 2, 0.3)
    model.simulate(u)
    for value in u:
        model.step(value)
        plays = model.get_state()["plays"]
        assert np.all(np.abs(plays - value) <= model.thresholds + 1e-12)


@given(seeds, st.integers(min_value=1, max_value=5))
def test_pi_is_rate_independent(seed, repeat):
    """Holding every sample longer (a slower input) gives the same output at the same inputs."""
    rng = np.random.default_rng(seed)
    model = random_pi(rng)
    u = random_walk(rng, 200, -2, 3, 0.4)
    model.reset(0.0, "centered")
    fast = model.simulate(u)
    model.reset(0.0, "centered")
    slow = model.simulate(np.repeat(u, repeat))
    np.testing.assert_allclose(slow[repeat - 1 :: repeat], fast, atol=1e-12)


@given(seeds)
def test_pi_output_bounded_by_saturation_outputs(seed):
    rng = np.random.default_rng(seed)
    model = random_pi(rng)
    model.reset(-2.0, "descending")
    y = model.simulate(random_walk(rng, 400, -2, 3, 0.5))
    lo, hi = model.saturation_outputs()
    slack = 1e-9 * (1 + abs(lo) + abs(hi))
    if np.all(model.weights >= 0):  # with negative weights the bound is the monotone envelope only
        assert y.min() >= lo - slack and y.max() <= hi + slack


@settings(max_examples=60)
@given(seeds, st.sampled_from(["ascending", "descending"]))
def test_inverse_of_forward_is_identity(seed, branch):
    rng = np.random.default_rng(seed)
    forward = random_pi(rng)
    u = random_walk(rng, 400, -2, 3, 0.4)
    inverse, recovered = inverse_round_trip(forward, u, branch)
    np.testing.assert_allclose(recovered, u, atol=1e-9 * (1 + np.abs(u).max()))
    assert not inverse.saturated


@settings(max_examples=30)
@given(seeds)
def test_inverse_driven_through_the_history_tracks_any_state(seed):
    """A demagnetised forward state is matched by driving the inverse with the forward's outputs."""
    rng = np.random.default_rng(seed)
    forward = random_pi(rng)
    inverse = forward.inverse()
    forward.reset(-2.0, "descending")
    inverse.reset(inverse.input_range[0], "descending")
    history = np.r_[np.linspace(3, -2, 7), random_walk(rng, 300, -2, 3, 0.4)]
    np.testing.assert_allclose(inverse.simulate(forward.simulate(history)), history, atol=1e-9 * 5)


def test_inverse_parameters_match_the_inverse_loading_curve():
    """r'_i = phi(r_i) and the inverse's slopes are 1/S_i (Ai2019 eq 14, indices from 0)."""
    r = np.array([0.0, 0.5, 1.2, 2.0])
    w = np.array([0.8, 0.4, -0.1, 0.3])
    r_inv, w_inv = inverse_pi_parameters(r, w)
    phi = [sum(wj * max(ri - rj, 0.0) for rj, wj in zip(r, w)) for ri in r]
    np.testing.assert_allclose(r_inv, phi)
    np.testing.assert_allclose(np.cumsum(w_inv), 1.0 / np.cumsum(w))


def test_non_invertible_weights_are_refused():
    with pytest.raises(ModelError, match="not invertible"):
        inverse_pi_parameters([0.0, 1.0], [0.5, -0.6])


def test_exponential_parameterisation_follows_eq5():
    r, w = exponential_pi_parameters(4, beta=0.5, delta=2.0, mu=0.3)
    np.testing.assert_allclose(r, [0, 0.5, 1.0, 1.5])
    np.testing.assert_allclose(w, 2.0 * np.exp(-0.3 * r))


def test_eq4_initial_state_matches_play_definition():
    """Ai2019 eq 4 with y0 = 0 is the demagnetised state at 0 followed by a step to u(0)."""
    model = PIModel([0.0, 0.4, 1.0], [1.0, 1.0, 1.0])
    model.set_state({"plays": np.zeros(3)})
    model.step(0.7)
    expected = [max(0.7 - r, min(0.7 + r, 0.0)) for r in (0.0, 0.4, 1.0)]
    np.testing.assert_allclose(model.get_state()["plays"], expected)


def test_simulate_equals_repeated_step_and_state_round_trips():
    rng = np.random.default_rng(3)
    model = random_pi(rng)
    u = random_walk(rng, 300, -2, 3, 0.3)
    model.reset(0.5, "ascending")
    saved = model.get_state()
    stepped = np.array([model.step(v) for v in u])
    model.set_state(saved)
    np.testing.assert_allclose(model.simulate(u), stepped, atol=1e-12)


def test_inverse_clamps_unreachable_outputs_and_flags_them():
    model = PIModel([0.0, 0.5], [1.0, 0.5], actuator_range=(0.0, 4.0))
    inverse = model.inverse()
    lo, hi = model.saturation_outputs()
    inverse.reset(lo, "descending")
    assert inverse.step(hi + 100.0) == pytest.approx(4.0)
    assert inverse.saturated
    assert np.isfinite(inverse.step(float("1e300")))
    inverse.step(hi - 0.1)
    assert not inverse.saturated


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"thresholds": [0.1, 0.5], "weights": [1, 1]}, "start at 0"),
        ({"thresholds": [0.0, 0.5, 0.4], "weights": [1, 1, 1]}, "increase strictly"),
        ({"thresholds": [0.0, 0.5], "weights": [1]}, "as many weights"),
    ],
)
def test_invalid_parameters_raise_model_error(kwargs, message):
    with pytest.raises(ModelError, match=message):
        PIModel(**kwargs)


def test_misspelled_keyword_raises():
    with pytest.raises(TypeError):
        PIModel([0.0], [1.0], output_ofset=1.0)  # type: ignore[call-arg]
