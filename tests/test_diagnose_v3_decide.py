"""Diagnosis v3's ranking of measured columns (``Rules.column_first``) and its held-out statistics
(cluster-robust by runs or blocks, and on whitened errors), and the campaign scoring set of
``bench/diagnose_runs_injected.py`` (real muscle runs; skipped without ../shared/data)."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import norm

from host.data import Measurement
from host.diagnose.conditional import GroupTest
from host.diagnose.heldout import _hac_se, cluster_labels, held_out_statistics
from host.diagnose.rules import RULES
from host.diagnose.runs import run_set
from host.diagnose.v3 import decide

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def _group(name: str, unique_p: float, marginal_p: float, share: float) -> GroupTest:
    return GroupTest(name, 4, 30.0, unique_p, 40.0, marginal_p, share, 0.5, 0.01, 0.01, "test")


def test_a_measured_column_passing_its_unique_test_is_tried_before_a_larger_dynamic_cause():
    tests = {
        "rate_dependence": _group("rate_dependence", 0.002, 0.002, 0.20),
        "load_dependence": _group("load_dependence", 0.005, 0.005, 0.05),
        "slow_drift": _group("slow_drift", 0.5, 0.5, 0.01),
    }
    assert decide(tests, RULES)[0] == ["rate_dependence", "load_dependence"]
    first = dataclasses.replace(RULES, column_first=True)
    assert decide(tests, first)[0] == ["load_dependence", "rate_dependence"]


def test_a_column_that_passes_only_beyond_the_baseline_is_a_candidate_only_when_time_adds_nothing():
    rules = dataclasses.replace(RULES, column_first=True)
    tests = {
        "temperature_drift": _group("temperature_drift", 0.2, 0.005, 0.02),
        "slow_drift": _group("slow_drift", 0.3, 0.002, 0.02),
    }
    assert decide(tests, rules) == (["temperature_drift"], [])
    assert decide(tests, RULES) == ([], ["slow_drift", "temperature_drift"])  # cannot tell, without the rule
    # a drift significant beyond the column: the column must pass its own unique test
    tests["slow_drift"] = _group("slow_drift", 0.002, 0.002, 0.05)
    assert decide(tests, rules)[0] == ["slow_drift"]


def _runs(count: int, length: int) -> Measurement:
    t = np.arange(length) * 0.02
    return [Measurement(t, np.sin(t + k), np.cos(t + k), {}, f"run{k}") for k in range(count)]


def test_cluster_labels_are_runs_for_short_runs_and_twentieths_of_a_long_record():
    rules = dataclasses.replace(RULES, heldout_clusters=True)
    rs = run_set(_runs(8, 150), rules.max_rows, rules.min_samples)
    labels = cluster_labels(rs, rules)
    assert labels is not None and np.array_equal(labels, rs.run)
    long = run_set(_runs(1, 4000), rules.max_rows, rules.min_samples)
    blocks = cluster_labels(long, rules)
    assert blocks is not None and np.unique(blocks).size == 20 and np.all(np.diff(blocks) >= 0)
    assert cluster_labels(long, RULES) is None


def test_the_cluster_robust_clark_west_test_holds_its_level_when_errors_move_together_within_runs():
    """No extension predicts: every run's error has a common offset the extension's noise-fitted
    term shares by chance. Per-row standard errors reject far too often; run clusters do not."""
    rules = dataclasses.replace(RULES, heldout_clusters=True)
    rs = run_set(_runs(20, 100), rules.max_rows, rules.min_samples)
    labels = cluster_labels(rs, rules)
    scored = np.ones(rs.y.size, dtype=bool)
    rng = np.random.default_rng(4)
    rejected = {"rows": 0, "runs": 0}
    reps = 200
    for _ in range(reps):
        offset = rng.normal(0.0, 1.0, 20)[rs.run]
        y = offset + 0.3 * rng.normal(size=rs.y.size)
        fitted = 0.3 * rng.normal(0.0, 1.0, 20)[rs.run]  # a term fitted to other runs' noise
        rs.y = y
        base, ext = np.zeros_like(y), fitted
        for kind, clusters in (("rows", None), ("runs", labels)):
            t, _ = held_out_statistics(rs, base, ext, scored, rng, clusters)
            rejected[kind] += float(norm.sf(t)) <= 0.05
    assert rejected["runs"] / reps <= 0.12
    assert rejected["rows"] / reps >= 2 * rejected["runs"] / reps


def test_whitened_held_out_scores_equal_the_scores_of_the_filtered_errors():
    rs = run_set(_runs(1, 2000), RULES.max_rows, RULES.min_samples)
    rng = np.random.default_rng(1)
    base = rs.y + np.cumsum(rng.normal(0, 0.01, rs.y.size))  # slow excursions
    ext = base - 0.5 * (base - rs.y) + 0.01 * rng.normal(size=rs.y.size)
    scored = np.ones(rs.y.size, dtype=bool)
    raw = held_out_statistics(rs, base, ext, scored, np.random.default_rng(0))
    same = held_out_statistics(rs, base, ext, scored, np.random.default_rng(0), None, np.zeros(0))
    assert raw == same  # an empty AR model filters nothing
    ar = np.array([0.9])
    white = held_out_statistics(rs, base, ext, scored, np.random.default_rng(0), None, ar)
    rb, re = base - rs.y, ext - rs.y
    wb, we = rb[1:] - 0.9 * rb[:-1], re[1:] - 0.9 * re[:-1]
    cw = wb**2 - we**2 + (wb - we) ** 2
    assert white[0] == pytest.approx(cw.mean() / _hac_se(cw), rel=1e-9)  # the first row is the filter's start


@pytest.mark.skipif(not (DATA / "pam_muscle_sensory").is_dir(), reason="no real muscle data under ../shared/data")
def test_the_campaign_set_injects_each_effect_at_its_size_into_separate_runs():
    from bench.plants.injected_runs import injected_runs, runs_cases

    cases = [c for c in runs_cases(DATA) if c.campaign == "07-21+22"]
    assert {c.effect for c in cases} == {
        "none",
        "creep",
        "rate_dependence",
        "transport_delay",
        "load_dependence",
        "temperature_drift",
    }
    for case in cases:
        runs, truth = injected_runs(case, DATA)
        assert len(runs) == truth["runs"] >= 10 and all(m.t[0] == 0.0 for m in runs)
        if case.effect == "none":
            assert truth["effect_size"] == 0.0
        else:
            assert 0.02 <= truth["effect_size_over_span"] <= 0.12
        loads = [np.ptp(m.extras["load"]) for m in runs]
        assert max(loads) < 0.05  # one hanging mass per run (sensor noise only)


def test_the_series_lag_switch_reaches_the_live_baseline():
    from host.diagnose.v3 import score

    rs = run_set(_runs(6, 200), RULES.max_rows, RULES.min_samples)
    plain = score(rs, 8, RULES, 0)[0]
    series = score(rs, 8, dataclasses.replace(RULES, series_lag=True), 0)[0]
    assert series.nuisance.shape[1] == plain.nuisance.shape[1] + 1  # the second lag's tangent
