"""A measured column's held-out gain against its surrogate copies' (host/diagnose/heldout_surrogates.py)
and how a column that passes it enters the verdict (host/diagnose/v3.with_columns)."""

from __future__ import annotations

import numpy as np
import pytest

from host.diagnose.conditional import column_copies
from host.diagnose.heldout import HeldOut, held_out
from host.diagnose.heldout_surrogates import held_out_surrogates
from host.diagnose.rules import RULES
from host.diagnose.runs import RunSet
from host.diagnose.v3 import Choice, with_columns

RUNS, PER_RUN = 16, 150


def _campaign(load_acts: bool, seed: int) -> tuple[RunSet, np.ndarray, np.ndarray]:
    """Runs of one inflate/deflate cycle, one hanging mass per run, a structural misfit (a cubic
    the nuisance lacks) in every run; the load scales the stroke when it acts."""
    rng = np.random.default_rng(seed)
    n = RUNS * PER_RUN
    phase = np.tile(np.linspace(0.0, 2 * np.pi, PER_RUN), RUNS)
    u = 0.5 - 0.5 * np.cos(phase)
    load = np.repeat(rng.permutation(np.linspace(0.0, 6.0, RUNS)), PER_RUN)
    y = u + 0.3 * u**3 + 0.01 * rng.normal(size=n)
    if load_acts:
        y += 0.02 * load * u
    run = np.repeat(np.arange(RUNS), PER_RUN)
    t = np.tile(np.arange(PER_RUN) * 0.02, RUNS)
    rs = RunSet(t, np.arange(n) * 0.02, u, y, run, 0.02, [f"run{i}" for i in range(RUNS)], {"load": load})
    nuisance = np.column_stack([np.ones(n), u])
    return rs, nuisance, load


def _masks(rs: RunSet, k: int = 5) -> list[np.ndarray]:
    return [np.isin(rs.run, np.arange(i, RUNS, k)) for i in range(k)]


def _test(rs: RunSet, nuisance: np.ndarray, load: np.ndarray) -> tuple[float, float]:
    copies, kind = column_copies(rs, load, 199, np.random.default_rng(0))
    assert kind == "its per-run values permuted across runs"
    r = held_out_surrogates(
        rs.y,
        nuisance,
        np.zeros((0, 0)),
        lambda c: np.column_stack([c, c * rs.u, c * rs.u**2]),
        load,
        copies,
        kind,
        _masks(rs),
        RULES.node_ridge,
    )
    return r.p, r.gain


def test_a_load_that_acts_beats_every_copy_held_out():
    rs, nuisance, load = _campaign(True, 1)
    p, gain = _test(rs, nuisance, load)
    assert p == pytest.approx(1 / 200)
    assert gain > 0.3


def test_a_decoy_load_ranks_among_its_copies_as_often_as_chance_says():
    """The copies meet the same cubic misfit: in-sample each load-times-output term fits part of
    it, held out none predicts it, so a decoy's p is uniform. Over 30 campaigns: 10 % of them at
    p <= 0.1 expected (measured 7.5 % over 200 others; 6 of these 30), 30 % allowed (3.6 binomial
    sd). An in-sample F-test of the same terms against the noise gives p <= 0.01 on all 30: the
    load-times-output terms fit part of the cubic."""
    ps = np.array([_test(*_campaign(False, seed))[0] for seed in range(30)])
    assert np.mean(ps <= 0.1) <= 0.3
    assert np.mean(ps <= 0.01) <= 0.1


def test_the_gram_block_fit_is_the_held_out_extension_of_heldout_py():
    """On a real v3 baseline (Preisach nodes with their smoothness penalty, whole-run folds) the
    column's and a copy's held-out gains equal held_out's, which fits on the training rows."""
    from host.diagnose.groups import branch_of, column_group
    from host.diagnose.heldout import holdout_folds
    from host.diagnose.runs import run_set
    from host.diagnose.v3 import score
    from tests.test_diagnose_v3 import runs_of

    rs = run_set(runs_of(5, 12, "load"), RULES.max_rows, RULES.min_samples)
    base, groups, _, _ = score(rs, RULES.preisach_levels, RULES, 0)
    masks, _ = holdout_folds(rs, RULES)
    branch = branch_of(rs)
    load = rs.columns["load"]
    copy = column_copies(rs, load, 1, np.random.default_rng(2))[0][0]
    gains = {}
    for name, values in (("real", load), ("copy", copy)):
        group = column_group(rs, base, values, RULES, branch)
        h = held_out(
            rs, base.nuisance, base.smoothness, group, masks, RULES.node_ridge, np.random.default_rng(0), values
        )
        gains[name] = h.gain
    r = held_out_surrogates(
        rs.y,
        base.nuisance,
        base.smoothness,
        lambda c: column_group(rs, base, c, RULES, branch),
        load,
        [copy],
        "one copy",
        masks,
        RULES.node_ridge,
    )
    assert r.gain == pytest.approx(gains["real"], abs=1e-9)
    assert r.median_copy_gain == pytest.approx(gains["copy"], abs=1e-9)
    assert base.smoothness.shape[0] > 0 and "load_dependence" in groups


def _trial(gain: float) -> HeldOut:
    return HeldOut(1.0, 1.0 - gain, gain, gain, (gain / 2, gain), 5.0, 1e-6, [], np.zeros(0), np.zeros(0))


def test_a_column_that_beats_its_copies_is_named_when_it_predicts_better_than_the_chosen_cause():
    trials = {"rate_dependence": _trial(0.2), "temperature_drift": _trial(0.6), "load_dependence": _trial(0.1)}
    chosen = Choice("rate_dependence", [], False, False, "rate_dependence")
    assert with_columns(chosen, ["temperature_drift"], trials.__getitem__).cause == "temperature_drift"
    assert with_columns(chosen, ["load_dependence"], trials.__getitem__).cause == "rate_dependence"
    assert with_columns(chosen, [], trials.__getitem__) is chosen
    nothing = Choice("none", ["creep"], True, False, None)
    named = with_columns(nothing, ["load_dependence"], trials.__getitem__)
    assert (named.cause, named.rejected, named.class_mismatch, named.heldout_of) == (
        "load_dependence",
        ["creep"],
        False,
        "load_dependence",
    )


def test_with_the_switch_a_load_per_run_is_named_with_its_held_out_surrogate_evidence():
    """End to end through diagnose_runs: the column's result is in the verdict, its reason and
    its JSON; without the switch none is computed."""
    from dataclasses import replace

    from host.diagnose.v3 import diagnose_runs
    from tests.test_diagnose_v3 import runs_of

    runs = runs_of(5, 12, "load")
    d = diagnose_runs(runs, rules=replace(RULES, column_heldout_surrogates=True))
    assert d.cause == "load_dependence", d.reason
    found = d.column_heldout["load_dependence"]
    assert found.p <= d.tests["load_dependence"].level and found.kind == "its per-run values permuted across runs"
    assert "surrogate copies" in d.reason
    assert d.as_json()["heldout_surrogates"]["load_dependence"]["copies"] == RULES.column_surrogates
    assert diagnose_runs(runs).column_heldout == {}
    few = diagnose_runs(runs, rules=replace(RULES, column_heldout_surrogates=True, column_surrogates=19))
    assert few.cause != "load_dependence" or "surrogate copies" not in few.reason  # p >= 1/20 cannot pass
    assert any("cannot pass: 19 copies give p >= 0.05" in note for note in few.notes)
