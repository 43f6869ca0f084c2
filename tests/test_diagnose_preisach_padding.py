"""The baseline's Preisach grid reaches beyond the input's range (``Rules.preisach_pad_levels``).

A Preisach grid that ends at the input's minimum erases the memory whenever the input returns
there, so a loop that does not close at the ends of the range is outside the baseline's class: a
single play operator whose threshold is a sixth to a third of the excursion (a friction element,
the simplest rate-independent hysteresis of the generalised-PI models) was fitted to 1.2-2.9 % of
its span, and what the baseline missed went to the causes' tests. With the grid padded by one
interval each side it is fitted to 0.08-0.12 % (the noise is 0.03 %). The runs start at rest on
the play's rising branch; runs that start on its falling branch are fitted either way.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from edge.hysteresis.pi import play_outputs
from host.data import Measurement
from host.diagnose.nuisance import fit_baseline
from host.diagnose.rules import RULES, Rules
from host.diagnose.runs import preisach_basis, run_set
from tests.test_diagnose_v3 import RATE_HZ, cycle_run, rested_cycle


def play_runs(threshold: float, seed: int = 4, n_runs: int = 12) -> list[Measurement]:
    """Short inflate/deflate runs (peaks 4-6 bar) read through one play operator [mm per bar x 10],
    each run from rest (the play on its rising boundary: ``u[0] - threshold``)."""
    rng = np.random.default_rng(seed)
    runs = []
    for i in range(n_runs):
        t, u = rested_cycle(seed + i, rng, seconds=(2.0, 7.0))
        play = play_outputs(u, np.array([threshold]), np.array([u[0] - threshold]))[:, 0]
        y = 10.0 * play + rng.normal(0.0, 0.02, u.size)
        runs.append(Measurement(t, u, y, {}, f"run{i:02d}.csv"))
    return runs


def baseline_rms_over_span(runs: list[Measurement], rules: Rules) -> float:
    rs = run_set(runs, rules.max_rows, rules.min_samples)
    nodes, smoothness, _ = preisach_basis(rs, rules.preisach_levels, rules.preisach_pad_levels)
    base = fit_baseline(rs, nodes, smoothness, rules.output_lags_s, rules.node_ridge, rules.nuisance_lags_s)
    return float(np.sqrt(np.mean((rs.y - base.prediction) ** 2)) / np.ptp(rs.y))


@pytest.mark.parametrize("threshold", [0.33, 1.0, 2.0])
def test_a_play_operator_wider_than_the_excursions_end_is_in_the_padded_baselines_class(threshold):
    runs = play_runs(threshold)
    assert baseline_rms_over_span(runs, RULES) < 0.002  # the noise is 0.03 % of the span
    unpadded = dataclasses.replace(RULES, preisach_pad_levels=0)
    assert baseline_rms_over_span(runs, unpadded) > 0.01


def test_the_padded_grid_still_holds_a_loop_that_closes_at_the_ends():
    rng = np.random.default_rng(0)
    runs = []
    for i in range(8):
        _, u = cycle_run(i, rng.uniform(3.0, 6.0), 5.0)
        t = np.arange(u.size) / RATE_HZ
        y = 3.0 * u + 0.5 * u**2 + rng.normal(0.0, 0.02, u.size)  # no hysteresis at all
        runs.append(Measurement(t, u, y, {}, f"run{i}.csv"))
    assert baseline_rms_over_span(runs, RULES) < 0.002
