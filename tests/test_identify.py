"""Identification: known parameters come back from noiseless data; noise degrades gracefully."""

from __future__ import annotations

import numpy as np
import pytest

from edge.errors import DataError, ModelError
from edge.hysteresis.dpi import DPIModel
from edge.hysteresis.mpi import MPIModel
from edge.hysteresis.pi import PIModel, exponential_pi_parameters
from edge.hysteresis.preisach import PreisachModel, everett_from_masses
from edge.hysteresis.shaper import MonotonePiecewiseLinear
from host.identify import DPIEstimator, MPIEstimator, PIEstimator, PreisachEstimator
from host.identify.common import memory_start
from host.identify.pi import uniform_thresholds


def signal() -> np.ndarray:
    t = np.linspace(0.0, 1.0, 6000)
    up_down = 2.0 * (1 - np.cos(2 * np.pi * 6 * t)) * (0.35 + 0.65 * np.abs(np.sin(2 * np.pi * 1.7 * t)))
    return np.r_[0.0, up_down, 4.0 * np.linspace(0, 1, 200), 4.0 - 2 * np.linspace(0, 1, 100)]


def truth_output(model, u: np.ndarray) -> np.ndarray:
    start = memory_start(u)
    model.reset(float(u[start.index]), start.branch)
    return np.r_[np.full(start.index, np.nan), model.simulate(u[start.index :])]


def test_free_pi_weights_are_recovered_exactly():
    u = signal()
    thresholds = uniform_thresholds(u, 8)
    weights = np.array([0.6, 0.4, 0.0, 0.3, 0.2, 0.0, 0.1, 0.05])
    y = truth_output(PIModel(thresholds, weights, output_offset=1.5), u)
    est = PIEstimator(n_operators=8).fit(u, y)
    np.testing.assert_allclose(est.model_.weights, weights, atol=1e-8)
    assert est.model_.output_offset == pytest.approx(1.5, abs=1e-8)
    assert est.fit_seconds_ > 0 and est.start_index_ == 0


def test_exponential_pi_parameters_are_recovered():
    u = signal()
    thresholds, weights = exponential_pi_parameters(10, beta=0.17, delta=0.9, mu=0.6)
    y = truth_output(PIModel(thresholds, weights), u)
    est = PIEstimator(n_operators=10, parameterisation="exponential").fit(u, y)
    assert est.beta_ == pytest.approx(0.17, rel=1e-3)
    assert est.delta_ == pytest.approx(0.9, rel=1e-3)
    assert est.mu_ == pytest.approx(0.6, rel=1e-2)


def dpi_truth(u: np.ndarray, compensate: bool) -> DPIModel:
    n = 6
    dx = np.full(n, float(np.ptp(u)) / n)
    dye = np.array([0.4, 0.6, 0.9, 1.1, 1.4, 1.6])
    dyc = np.array([0.8, 1.0, 0.7, 1.2, 1.3, 1.0])
    dyc *= dye.sum() / dyc.sum()  # a closed major loop, as the estimator assumes
    return DPIModel(dx, dye, dx, dyc, x0=float(u.min()), y0=-0.3, compensate=compensate)


def test_dpi_pairs_are_recovered_from_the_branches():
    u = signal()
    truth = dpi_truth(u, compensate=False)
    est = DPIEstimator(n_operators=6).fit(u, truth_output(truth, u))
    np.testing.assert_allclose(est.model_.params["dye"], truth.params["dye"], rtol=1e-6)
    np.testing.assert_allclose(est.model_.params["dyc"], truth.params["dyc"], rtol=1e-6)
    assert est.model_.anchors == pytest.approx(truth.anchors)


def test_dpi_fit_of_a_compensated_system_stays_close():
    """The compensator rescales minor loops; the fit (which ignores it) is still within 3 % p-p."""
    u = signal()
    y = truth_output(dpi_truth(u, compensate=True), u)
    est = DPIEstimator(n_operators=6).fit(u, y)
    assert np.sqrt(np.mean((est.train_prediction_ - y) ** 2)) < 0.03 * np.ptp(y)


def forc_signal(levels: int = 12) -> np.ndarray:
    """First-order reversal curves: from the bottom up to a rising maximum and back down."""
    parts = [np.zeros(1)]
    for m in range(1, levels + 1):  # samples every 1/16 grid step, so every node is sampled
        peak = 4.0 * m / levels
        parts += [np.linspace(0, peak, 16 * m + 1), np.linspace(peak, 0, 16 * m + 1)]
    return np.concatenate(parts)


def test_preisach_everett_map_is_recovered_by_least_squares():
    rng = np.random.default_rng(9)
    u = np.r_[forc_signal(8), 4.0 * np.abs(np.sin(np.cumsum(rng.normal(0, 0.05, 4000))))]
    rng = np.random.default_rng(0)
    n = 8
    masses = np.tril(rng.uniform(0.0, 1.0, (n + 1, n + 1)), -1)
    truth = PreisachModel((float(u.min()), float(u.max())), everett_from_masses(masses), y_min=0.7)
    y = truth_output(truth, u)
    est = PreisachEstimator(n_levels=n, min_slope_ratio=1e-3).fit(u, y)
    np.testing.assert_allclose(est.model_.everett, truth.everett, atol=1e-6 * truth.everett.max())
    assert est.model_.y_min == pytest.approx(0.7, abs=1e-6)


def test_preisach_from_first_order_reversal_curves():
    u = forc_signal()
    rng = np.random.default_rng(1)
    n = 12
    masses = np.tril(rng.uniform(0.2, 1.0, (n + 1, n + 1)), -1)
    truth = PreisachModel((0.0, 4.0), everett_from_masses(masses), y_min=0.0)
    y = truth_output(truth, u)
    est = PreisachEstimator(n_levels=n, method="forc").fit(u, y)
    np.testing.assert_allclose(est.model_.everett, truth.everett, atol=1e-6 * truth.everett.max())
    assert np.sqrt(np.mean((est.train_prediction_ - y) ** 2)) < 1e-6 * np.ptp(y)


def test_mpi_fits_data_from_an_mpi_model_closely():
    u = signal()
    pi = PIModel(uniform_thresholds(u, 10), 0.9 * np.exp(-0.5 * uniform_thresholds(u, 10)))
    shaper = MonotonePiecewiseLinear.from_dead_zones([0.0, 1.5, 3.0], [1.0, 0.8, -0.6])
    truth = MPIModel(pi, shaper)
    y = truth_output(truth, u)
    est = MPIEstimator(n_operators=10, n_dead_zones=8).fit(u, y)
    start = est.start_index_
    assert np.sqrt(np.mean((est.train_prediction_ - y[start:]) ** 2)) < 0.01 * np.ptp(y)


@pytest.mark.parametrize("estimator", [PIEstimator(), MPIEstimator(), DPIEstimator(), PreisachEstimator()])
def test_noise_degrades_gracefully(estimator):
    """With white noise of std s on y, the model stays within a fraction of s of the truth."""
    u = signal()
    truth = PIModel(uniform_thresholds(u, 12), 0.8 * np.exp(-0.7 * uniform_thresholds(u, 12)))
    clean = truth_output(truth, u)
    rng = np.random.default_rng(2)
    sigma = 0.01 * np.ptp(clean)
    est = estimator.fit(u, clean + rng.normal(0.0, sigma, u.size))
    error = est.train_prediction_ - clean[est.start_index_ :]
    assert np.sqrt(np.mean(error**2)) < 0.5 * sigma


def test_training_data_must_move_and_match():
    with pytest.raises(DataError, match="constant"):
        PIEstimator().fit(np.ones(100), np.arange(100.0))
    with pytest.raises(DataError, match="equal lengths"):
        PIEstimator().fit(np.arange(100.0), np.arange(99.0))
    with pytest.raises(DataError, match="at least"):
        PIEstimator().fit(np.arange(5.0), np.arange(5.0))


def test_estimator_arguments_are_checked():
    with pytest.raises(ModelError):
        PIEstimator(parameterisation="quadratic")  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        DPIEstimator(n_operator=5)  # type: ignore[call-arg]
    with pytest.raises(ModelError, match="min_slope_ratio"):
        MPIEstimator(min_slope_ratio=0.0)


def test_memory_is_known_from_the_first_range_end():
    u = np.r_[2.0, 3.0, 1.0, 0.0, 4.0, 2.0]
    start = memory_start(u)
    assert (start.index, start.branch) == (3, "descending")


@pytest.mark.parametrize(
    "estimator, tolerance",
    [(PIEstimator(), 1e-6), (DPIEstimator(), 1e-6), (MPIEstimator(), 1e-2), (PreisachEstimator(), 1e-2)],
)
def test_a_record_starting_just_inside_its_range_end_fits_like_one_starting_at_it(estimator, tolerance):
    """memory_start accepts the first sample within 0.5 % of a range end; the model's start
    state and output level must then match the regression's (DPI's output level used to
    assume the exact end, and was off by the part of the last digit not yet filled)."""
    core = signal()[1:]
    top = int(core.argmax())
    u = np.r_[core.max() - 0.015, core[top:], core[:top]]  # starts 0.375 % of the range below the max
    thresholds = uniform_thresholds(u, 25)[::5]  # a subset of the estimators' grids: exact fits exist
    truth = PIModel(thresholds, 0.7 * np.exp(-0.5 * thresholds))
    y = truth_output(truth, u)
    est = estimator.fit(u, y)
    assert est.start_index_ == 0
    assert np.sqrt(np.mean((est.train_prediction_ - y) ** 2)) < tolerance * np.ptp(y)


def test_mpi_exponential_parameterisation_recovers_beta_and_mu():
    u = signal()
    thresholds, weights = exponential_pi_parameters(10, beta=0.17, delta=0.9, mu=0.6)
    shaper = MonotonePiecewiseLinear.from_dead_zones([0.0, 1.0, 2.0], [1.0, 0.6, -0.5])
    y = truth_output(MPIModel(PIModel(thresholds, weights), shaper), u)
    est = MPIEstimator(n_operators=10, n_dead_zones=12, parameterisation="exponential").fit(u, y)
    assert est.beta_ == pytest.approx(0.17, rel=0.02)
    assert est.mu_ == pytest.approx(0.6, rel=0.1)
    assert np.sqrt(np.mean((est.train_prediction_ - y) ** 2)) < 0.005 * np.ptp(y)


def test_a_constant_output_is_refused():
    u = signal()
    with pytest.raises(DataError, match="output y is constant"):
        PIEstimator().fit(u, np.full_like(u, 5.0))


@pytest.mark.parametrize("model, operators", [("pi", 0), ("mpi", 101), ("dpi", -1), ("preisach", 1), ("preisach", 61)])
def test_operator_counts_outside_the_stated_range_are_refused(model, operators):
    from host.workflow import make_estimator

    with pytest.raises(ModelError, match=rf"--operators {operators} is outside \d+-\d+ for {model} \(default \d+\)"):
        make_estimator(model, operators=operators)


def test_no_operator_count_means_the_model_default():
    from host.workflow import make_estimator

    assert make_estimator("pi").n_operators == 25 and make_estimator("preisach").n_levels == 20


def test_a_fit_records_its_cpu_time_and_blas_threads():
    u = signal()
    est = PIEstimator(n_operators=8).fit(u, np.tanh(u))
    assert est.fit_cpu_seconds_ > 0 and est.blas_threads_ == 1  # 6400 samples x 9 unknowns: one thread


def test_blas_threads_grow_with_the_problem_but_not_past_the_cores():
    from host.identify.threads import PARALLEL_WORK, threads_for

    assert threads_for(PARALLEL_WORK / 10, cpus=8) == 1
    assert 1 <= threads_for(PARALLEL_WORK * 100, cpus=4) <= 4
    assert threads_for(PARALLEL_WORK * 100, cpus=1) == 1
