"""Diagnosis v3's decision replays from a dump: :func:`host.diagnose.v3.choose` is the one
decision loop the live diagnosis and ``bench/diagnose_replay.py --v3`` share, each gate can be
switched by a :class:`host.diagnose.rules.Rules` field, and the replay names the gate that lost
an effect. The second-order stage of the baseline finds a payload resonance it is shown."""

from __future__ import annotations

import dataclasses
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from host.data import Measurement
from host.diagnose.nuisance import fit_baseline, lowpass
from host.diagnose.rules import RULES
from host.diagnose.runs import node_differences, preisach_nodes, run_set

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench.diagnose_replay import main as replay_main  # noqa: E402
from bench.diagnose_v3_dump import overridden  # noqa: E402
from bench.diagnose_v3_replay import replay  # noqa: E402


def _test(p_u: float, p_m: float, stat: float = 50.0) -> dict[str, Any]:
    return {
        "df": 4,
        "unique_stat": stat,
        "unique_p": p_u,
        "marginal_stat": stat,
        "marginal_p": p_m,
        "unique_share": 0.1,
        "identifiable": 0.5,
        "mde": 0.01,
        "level": 0.05,
        "null": "dumped",
        "p_by_null": {"bootstrap": [p_u, p_m], "permutation": [min(1.0, 4 * p_u), min(1.0, 4 * p_m)]},
    }


def _row(effect: str, cw_p: float, lo: float, ladder_stat: float = 50.0) -> dict[str, Any]:
    """A dumped record: creep passes its unique test under the bootstrap (p 0.002) and the
    permutation (0.008); rate fails it."""
    return {
        "family": "x",
        "index": 0,
        "case": "c",
        "effect": effect,
        "verdict": "none",
        "v3": True,
        "tests": {"creep": _test(0.002, 0.002), "rate_dependence": _test(0.5, 0.4)},
        "richer": {
            "creep": {"unique_stat": ladder_stat, "unique_p": 0.5 if ladder_stat < 25 else 0.002, "level": 0.025},
            "rate_dependence": {"unique_stat": 5.0, "unique_p": 0.6, "level": 0.025},
        },
        "trials": {
            "creep": {"cw_p": cw_p, "lo": lo, "hi": 0.3, "gain": 0.1},
            "rate_dependence": {"cw_p": 0.5, "lo": -0.1, "hi": 0.1, "gain": 0.0},
        },
        "oracle_p": 0.001,
    }


def test_the_held_out_gates_lose_an_effect_and_switching_them_off_names_it():
    row = _row("creep", cw_p=0.2, lo=-0.05)
    assert replay(row, RULES).verdict == "none" and replay(row, RULES).lost_at == "held-out CW"
    assert replay(row, dataclasses.replace(RULES, heldout_gate=False)).verdict == "creep"
    interval_only = _row("creep", cw_p=0.01, lo=-0.05)
    assert replay(interval_only, RULES).lost_at == "held-out interval"
    assert replay(interval_only, dataclasses.replace(RULES, heldout_interval_gate=False)).verdict == "creep"


def test_the_ladder_loses_an_effect_whose_statistic_collapses_with_the_richer_rung():
    row = _row("creep", cw_p=0.001, lo=0.05, ladder_stat=10.0)
    assert replay(row, RULES).lost_at == "ladder"
    assert replay(row, dataclasses.replace(RULES, ladder_drop=1.0)).verdict == "creep"


def test_the_nulls_and_alpha_are_recombined_from_the_dumped_p_values():
    row = _row("creep", cw_p=0.001, lo=0.05)
    assert replay(row, RULES).verdict == "creep"  # max(bootstrap 0.002, permutation 0.008) <= 0.05
    assert replay(row, dataclasses.replace(RULES, alpha=0.005)).lost_at == "unique test"
    # without the permutation null the bootstrap's 0.002 alone counts, which passes at alpha 0.005
    assert replay(row, dataclasses.replace(RULES, alpha=0.005, within_state_null=False)).verdict == "creep"


def test_the_replay_cli_compares_rules_side_by_side_and_rejects_bad_overrides(tmp_path, capsys):
    dump = tmp_path / "d.jsonl"
    rows = [_row("creep", 0.2, -0.05), {**_row("none", 0.5, -0.1), "index": 1}]
    dump.write_text("\n".join(json.dumps(r) for r in rows) + "\n")
    assert replay_main(["--v3", str(dump), "--rules", "heldout_gate=false"]) == 0
    out = capsys.readouterr().out
    assert "current" in out and "heldout_gate=false" in out and "held-out CW" in out
    with pytest.raises(ValueError, match="unknown field 'alpah'"):
        overridden("alpah=0.1")
    with pytest.raises(SystemExit) as stop:
        replay_main(["--v3", str(dump), "--rules", "alpah=0.1"])
    assert stop.value.code == 2 and "unknown field" in capsys.readouterr().err


def test_the_baseline_finds_a_payload_resonance_it_is_shown():
    rate, f_hz, zeta = 200.0, 3.0, 0.3
    t = np.arange(int(40 * rate)) / rate
    levels = np.random.default_rng(1).uniform(0.0, 4.0, 20)  # steps every 2 s ring the payload
    u = lowpass(np.repeat(levels, int(2 * rate))[: t.size], 1 / rate, 0.01)
    x = u + 0.3 * u**2 / 4.0
    w = 2 * np.pi * f_hz
    from scipy.signal import cont2discrete, lfilter, lfilter_zi

    num, den, _ = cont2discrete(([w * w], [1.0, 2 * zeta * w, w * w]), 1 / rate, method="zoh")
    b, a = np.ravel(num), np.ravel(den)
    y = lfilter(b, a, lowpass(x, 1 / rate, 0.02), zi=lfilter_zi(b, a) * x[0])[0]
    y = y + np.random.default_rng(0).normal(0, 0.005, y.size)
    rs = run_set([Measurement(t, u, y, {}, "resonant.csv")], RULES.max_rows, RULES.min_samples)
    nodes, _ = preisach_nodes(rs, RULES.preisach_levels)
    d = node_differences(RULES.preisach_levels)
    args = (rs, nodes, d.T @ d, RULES.output_lags_s, RULES.node_ridge, RULES.nuisance_lags_s)
    plain = fit_baseline(*args)
    staged = fit_baseline(*args, RULES.resonance_hz, RULES.resonance_zetas)
    assert plain.resonance == (0.0, 0.0)
    assert 2.0 <= staged.resonance[0] <= 4.0 and staged.resonance[1] <= 0.5
    error = lambda base: float(np.sqrt(np.mean((rs.y - base.prediction) ** 2)))  # noqa: E731
    assert error(staged) < 0.6 * error(plain)
