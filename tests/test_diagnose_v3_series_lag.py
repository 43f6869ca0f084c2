"""The v3 baseline's second lag in series (``Rules.series_lag``): a valve and the mechanics in
series (an S-shaped step response) are the baseline's class, found on a grid that does not hold
the true time constants; a pure dead time stays outside it, so transport delay keeps its part."""

from __future__ import annotations

import numpy as np

from host.data import Measurement
from host.diagnose.groups import delay_group
from host.diagnose.nuisance import Baseline, fit_baseline, lowpass
from host.diagnose.rules import RULES
from host.diagnose.runs import RunSet, node_differences, preisach_nodes, run_set

RATE = 200.0


def _record(valve_s: float, mechanics_s: float, delay_s: float) -> RunSet:
    t = np.arange(int(40 * RATE)) / RATE
    levels = np.random.default_rng(3).uniform(0.0, 4.0, 40)  # steps every second
    u = np.repeat(levels, int(RATE))[: t.size]
    x = u + 0.3 * u**2 / 4.0
    k = int(round(delay_s * RATE))
    x = np.r_[np.full(k, x[0]), x[: x.size - k]]
    y = lowpass(lowpass(x, 1 / RATE, valve_s), 1 / RATE, mechanics_s)
    y = y + np.random.default_rng(0).normal(0, 0.005, y.size)
    return run_set([Measurement(t, u, y, {}, "series.csv")], RULES.max_rows, RULES.min_samples)


def _baselines(rs: RunSet) -> tuple[Baseline, Baseline]:
    nodes, _ = preisach_nodes(rs, RULES.preisach_levels)
    d = node_differences(RULES.preisach_levels)
    args = (rs, nodes, d.T @ d, RULES.output_lags_s, RULES.node_ridge, RULES.nuisance_lags_s)
    return fit_baseline(*args), fit_baseline(*args, series_lags_s=RULES.series_lags_s)


def _rms(rs: RunSet, base: Baseline) -> float:
    return float(np.sqrt(np.mean((rs.y - base.prediction) ** 2)))


def _left_to(rs: RunSet, base: Baseline, group: np.ndarray) -> float:
    """Share of the baseline's residual sum of squares that ``group`` (partialled on the nuisance) removes."""
    both = np.hstack([base.nuisance, group])
    rss_base = float(np.sum((rs.y - base.nuisance @ np.linalg.lstsq(base.nuisance, rs.y, rcond=None)[0]) ** 2))
    rss_both = float(np.sum((rs.y - both @ np.linalg.lstsq(both, rs.y, rcond=None)[0]) ** 2))
    return 1.0 - rss_both / rss_base


def test_two_lags_in_series_are_found_off_the_grid():
    rs = _record(valve_s=0.07, mechanics_s=0.3, delay_s=0.0)
    plain, series = _baselines(rs)
    assert plain.second_lag_s == 0.0
    assert series.second_lag_s > 0.0
    assert _rms(rs, series) < 0.7 * _rms(rs, plain)


def test_a_dead_time_stays_outside_the_series_lags():
    rs = _record(valve_s=0.0, mechanics_s=0.2, delay_s=0.15)
    _, series = _baselines(rs)
    assert _left_to(rs, series, delay_group(rs, series, RULES)) > 0.5
