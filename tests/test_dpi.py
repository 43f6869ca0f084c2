"""DPI laws (Zhou2022): digitized state, equivalence with PI, compensator, exact inverse."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from edge.errors import ModelError
from edge.hysteresis.dpi import DPIModel
from edge.hysteresis.lut import CompiledModel
from edge.hysteresis.pi import PIModel
from edge.hysteresis.table import LookupTable
from host.identify.dpi import DPIEstimator
from tests.conftest import random_walk
from tests.strategies import random_dpi, random_pi, seeds
from tests.test_identify import signal, truth_output


def dpi_from_pi(pi: PIModel, half_range: float) -> DPIModel:
    """Symmetric DPI of a PI model centred on 0: dX_i = 2(r_{i+1} - r_i), dY_i = dX_i S_i."""
    r = np.r_[pi.thresholds, half_range]
    dx = 2 * np.diff(r)
    dy = dx * np.cumsum(pi.weights)
    y0 = float(pi.weights @ (-half_range + pi.thresholds))
    return DPIModel(dx, dy, dx, dy, x0=-half_range, y0=y0)


@given(seeds)
def test_symmetric_dpi_is_the_classical_pi_model(seed):
    rng = np.random.default_rng(seed)
    pi = random_pi(rng, -2.5, 2.5)
    pi = PIModel(pi.thresholds, np.abs(pi.weights) + 0.01, actuator_range=(-2.5, 2.5))
    dpi = dpi_from_pi(pi, 2.5)
    u = random_walk(rng, 500, -2.5, 2.5, 0.5)
    for branch in ("ascending", "descending"):
        pi.reset(u[0], branch)
        dpi.reset(u[0], branch)
        np.testing.assert_allclose(dpi.simulate(u), pi.simulate(u), atol=1e-9)


def test_whole_digit_steps_give_a_binary_state():
    """Moving by whole digit widths from B0 leaves every digit at 0 or 1 (the paper's b_i)."""
    model = DPIModel([1.0, 1.0, 1.0], [1.0, 2.0, 3.0], [1.0, 1.0, 1.0], [1.5, 2.0, 2.5], x0=0.0, y0=0.0)
    model.reset(0.0, "ascending")
    for u in (2.0, 1.0, 3.0, 0.0, 1.0, 2.0, 1.0):
        model.step(u)
        assert set(model.get_state()["fills"].tolist()) <= {0.0, 1.0}


def test_expansion_fills_the_least_significant_digit_first():
    model = DPIModel([1.0, 1.0], [1.0, 3.0], [1.0, 1.0], [2.0, 2.0], x0=0.0, y0=0.0, compensate=False)
    model.reset(0.0, "ascending")
    assert model.step(1.0) == pytest.approx(1.0)  # digit 1: slope dYe_1/dXe_1 = 1
    assert model.step(2.0) == pytest.approx(4.0)  # digit 2: slope 3
    assert model.step(1.0) == pytest.approx(2.0)  # contraction empties digit 1 first: slope 2


@settings(max_examples=60)
@given(seeds)
def test_inverse_by_swapping_pairs_is_exact(seed):
    rng = np.random.default_rng(seed)
    model = random_dpi(rng)
    lo, hi = model.input_range
    u = random_walk(rng, 500, lo, hi, 0.2 * (hi - lo))
    model.reset(u[0], "ascending")
    inverse = model.inverse()
    np.testing.assert_allclose(inverse.simulate(model.simulate(u)), u, atol=1e-9 * (1 + abs(hi) + abs(lo)))


@st.composite
def spread_dpi(draw: st.DrawFn, asymmetry: float, width_asymmetry: float) -> DPIModel:
    """Digit slopes spread over 600x between digits (0.15..93, like identified models with floored
    digits), each digit's contraction height within ``asymmetry`` of its expansion height and its
    contraction width within ``width_asymmetry`` of its expansion width."""
    n = draw(st.integers(2, 25))
    log_slope = st.floats(np.log(0.15), np.log(93.0))
    dxe = np.array(draw(st.lists(st.floats(0.05, 0.5), min_size=n, max_size=n)))
    dye = dxe * np.exp(draw(st.lists(log_slope, min_size=n, max_size=n)))
    dxc = dxe * np.exp(draw(st.lists(log_ratio(width_asymmetry), min_size=n, max_size=n)))
    dyc = dye * np.exp(draw(st.lists(log_ratio(asymmetry), min_size=n, max_size=n)))
    x0, y0 = draw(st.floats(-10, 10)), draw(st.floats(-100, 100))
    return DPIModel(dxe, dye, dxc, dyc, x0=x0, y0=y0)


def log_ratio(asymmetry: float) -> st.SearchStrategy[float]:
    """A log ratio within ``asymmetry`` either way (exactly 0 when ``asymmetry`` is 1)."""
    return st.floats(-np.log(asymmetry), np.log(asymmetry))


def assert_round_trip(model: DPIModel, seed: int, step: float, bound: float) -> None:
    """The forward and the inverse run separately (as the edge's two tables do) over a 3000-sample
    random walk with thousands of reversals; the inverse recovers the input to ``bound`` x range."""
    lo, hi = model.input_range
    u = random_walk(np.random.default_rng(seed), 3000, lo, hi, step * (hi - lo))
    model.reset(u[0], "ascending")
    inverse = model.inverse()
    np.testing.assert_allclose(inverse.simulate(model.simulate(u)), u, rtol=0, atol=bound * (hi - lo))


@settings(max_examples=25, deadline=None)
@given(spread_dpi(3.0, 3.0), seeds, st.floats(0.01, 0.3))
def test_inverse_undoes_forward_over_long_histories_with_spread_slopes(model, seed, step):
    """Rounding level, however far apart the slopes of different digits are: the per-digit
    asymmetry, not the spread, sets the conditioning (module docstring; 300 draws: <= 2e-13)."""
    assert_round_trip(model, seed, step, 1e-11)


@settings(max_examples=25, deadline=None)
@given(spread_dpi(10.0, 1.0), seeds, st.floats(0.01, 0.3))
def test_inverse_undoes_forward_at_the_asymmetry_the_fit_allows(model, seed, step):
    """At the identification's default bound (``dYc_i / dYe_i`` within 10, equal digit widths as
    every identified model has) rounding can grow at reversals, but stays far below a DAC step
    (2.4e-4 of the range at 12 bits). 6200 uniform draws of this generator: median 2e-13,
    99.9th percentile 1.6e-8, max 5.7e-6 of the range (a bound of 1e-8 failed about one run in
    30); the bound is 1e-4, under half a DAC step. Unequal widths multiply the factor
    (:mod:`edge.hysteresis.dpi`); no fit makes them."""
    assert_round_trip(model, seed, step, 1e-4)


def test_drift_is_bounded_with_the_compensator_and_grows_without():
    rng = np.random.default_rng(7)
    dxe = np.full(6, 1.0)
    dye = rng.uniform(0.5, 1.5, 6)
    dyc = dye * rng.uniform(0.6, 0.9, 6)  # contraction systematically smaller: upward drift
    kwargs = dict(x0=0.0, y0=0.0, x1=6.0, y1=float(dye.sum()))
    compensated = DPIModel(dxe, dye, dxe, dyc, **kwargs)
    raw = DPIModel(dxe, dye, dxe, dyc, compensate=False, **kwargs)
    cycles = 10_000
    centres = rng.uniform(1.0, 5.0, cycles)
    amplitudes = rng.uniform(0.1, 1.0, cycles)
    u = np.empty(2 * cycles)
    u[0::2] = np.clip(centres + amplitudes, 0, 6)
    u[1::2] = np.clip(centres - amplitudes, 0, 6)
    for model in (compensated, raw):
        model.reset(3.0, "ascending")
    y_comp = compensated.simulate(u)
    y_raw = raw.simulate(u)
    assert y_comp.min() >= -1e-9 and y_comp.max() <= kwargs["y1"] + 1e-9
    first, last = y_raw[: cycles // 10], y_raw[-cycles // 10 :]
    assert last.mean() - first.mean() > 10 * kwargs["y1"]  # grows by far more than the range


def test_out_of_range_input_is_clamped_and_flagged():
    model = random_dpi(np.random.default_rng(1))
    inverse = model.inverse()
    inverse.reset(inverse.input_range[0], "ascending")
    assert inverse.step(inverse.input_range[1] + 10) == pytest.approx(model.input_range[1])
    assert inverse.saturated
    assert np.isfinite(inverse.step(-1e300)) and inverse.saturated


def test_flat_pairs_are_refused():
    with pytest.raises(ModelError, match="dye must be > 0"):
        DPIModel([1.0], [0.0], [1.0], [1.0], x0=0.0, y0=0.0)


def asymmetric_truth(u: np.ndarray, compensate: bool) -> DPIModel:
    """Equal widths as the fit uses; digit 2 contracts 36x steeper than it expands."""
    dx = np.full(4, float(np.ptp(u)) / 4)
    dye = np.array([1.0, 0.05, 1.5, 1.2])
    dyc = np.array([1.0, 2.5, 1.2, 0.5])
    dyc *= dye.sum() / dyc.sum()
    return DPIModel(dx, dye, dx, dyc, x0=float(u.min()), y0=0.0, compensate=compensate)


def rms_error(estimator: DPIEstimator, y: np.ndarray) -> float:
    scored = ~np.isnan(y)
    return float(np.sqrt(np.mean((estimator.train_prediction_[scored] - y[scored]) ** 2)))


def test_fit_bounds_every_digits_asymmetry():
    """The fit keeps dYc_i / dYe_i within [1/10, 10] by default (the inverse's conditioning);
    unbounded, it recovers the 36x digit exactly. On the compensated system (what the deployed
    model is) the bounded fit is as close as the unbounded one."""
    u = signal()
    truth = asymmetric_truth(u, compensate=False)
    free = DPIEstimator(n_operators=4, max_asymmetry=np.inf).fit(u, truth_output(truth, u)).model_.params
    np.testing.assert_allclose(free["dyc"] / free["dye"], truth.params["dyc"] / truth.params["dye"], rtol=1e-6)

    y = truth_output(asymmetric_truth(u, compensate=True), u)
    bounded = DPIEstimator(n_operators=4).fit(u, y)
    p = bounded.model_.params
    assert np.all(p["dyc"] <= 10 * p["dye"] * (1 + 1e-6)) and np.all(p["dye"] <= 10 * p["dyc"] * (1 + 1e-6))
    unbounded = DPIEstimator(n_operators=4, max_asymmetry=np.inf).fit(u, y)
    assert rms_error(bounded, y) <= 1.05 * rms_error(unbounded, y)


def test_asymmetry_bound_below_one_is_refused():
    with pytest.raises(ModelError, match="max_asymmetry must be >= 1"):
        DPIEstimator(max_asymmetry=0.5)


def test_a_table_written_before_the_turning_point_was_stored_runs_the_same_model():
    """Older DPI tables hold no ``turn_*`` arrays: they start a branch where they stand, which is
    the same branch in exact arithmetic."""
    rng = np.random.default_rng(5)
    model = random_dpi(rng)
    lo, hi = model.input_range
    model.reset(lo + 0.3 * (hi - lo), "centered")
    model.step(lo + 0.6 * (hi - lo))  # mid-branch: the turning point differs from the state
    table = model.compile()
    old = LookupTable(table.kind, table.stages, dict(table.arrays), table.input_range)
    for key in ("0.turn_fills", "0.turn_cursor"):
        del old.arrays[key]
    u = random_walk(rng, 500, lo, hi, 0.2 * (hi - lo))
    np.testing.assert_allclose(CompiledModel(old).simulate(u), CompiledModel(table).simulate(u), atol=1e-9)


def test_the_blockwise_branch_problem_is_the_full_least_squares_problem():
    from host.identify.common import MemoryStart
    from host.identify.dpi import CHUNK_ROWS, branch_regressors, compressed_branch_problem, digit_fills

    rng = np.random.default_rng(7)
    u = np.cumsum(rng.normal(0, 0.05, 2 * CHUNK_ROWS + 123))  # three blocks, the last one short
    y = np.tanh(u) + rng.normal(0, 0.01, u.size)
    n, start = 6, MemoryStart(40, "descending")
    dx = float(np.ptp(u)) / n
    gained, lost = branch_regressors(digit_fills(u, dx, n, start))
    design = np.column_stack([gained, -lost, np.ones(len(gained))])
    factor, projected = compressed_branch_problem(u, y, dx, n, start)
    target = y[start.index :]
    assert np.allclose(factor.T @ factor, design.T @ design, rtol=1e-9, atol=1e-6)
    assert np.allclose(factor.T @ projected, design.T @ target, rtol=1e-9, atol=1e-6)


@pytest.mark.slow
def test_dpi_converges_on_a_100k_sample_recording_where_slsqp_stalled(tmp_path):
    from hil.record import record

    recording = record("sines", 1, 1000.0, effect="rate_dependence")  # failed with "did not converge"
    estimator = DPIEstimator().fit(recording.u, recording.y)
    residual = estimator.train_prediction_ - recording.y[estimator.start_index_ :]
    assert np.sqrt(np.mean(residual**2)) < 0.1 * np.ptp(recording.y)
