"""Further causes: after the named cause, the other significant causes are confirmed held out one
after another, each beyond the baseline and the causes named before it (fixed-sequence testing)."""

from __future__ import annotations

import dataclasses

import numpy as np

from host.data import Measurement
from host.diagnose.heldout import HeldOut
from host.diagnose.report_v3 import PLAIN, write_report_v3
from host.diagnose.rules import RULES
from host.diagnose.v3 import diagnose_runs, further_causes
from tests.test_diagnose_v3 import runs_of


def _trial(gain: float, p: float) -> HeldOut:
    empty = np.zeros(0)
    return HeldOut(1.0, 1.0 - gain, gain, gain, (gain - 0.05, gain + 0.05), 3.0, p, [], empty, empty)


def test_the_sequence_stops_at_the_first_cause_held_out_data_do_not_confirm():
    asked: list[tuple[str, list[str]]] = []
    results = {"creep": _trial(0.2, 1e-4), "transport_delay": _trial(0.01, 0.4), "slow_drift": _trial(0.3, 1e-6)}

    def trial_beyond(cause: str, before: list[str]) -> HeldOut:
        asked.append((cause, list(before)))
        return results[cause]

    found = further_causes("rate_dependence", ["creep", "transport_delay", "slow_drift"], trial_beyond, RULES)
    assert [g for g, _ in found] == ["creep"]
    # each is tested beyond the named cause and those confirmed before it; nothing after the first failure
    assert asked == [("creep", ["rate_dependence"]), ("transport_delay", ["rate_dependence", "creep"])]


def test_nothing_further_without_a_named_cause_and_at_most_the_rules_allow():
    def confirmed_trial(cause: str, before: list[str]) -> HeldOut:
        return _trial(0.2, 1e-6)

    causes = ["creep", "transport_delay", "slow_drift"]
    assert further_causes("none", causes, confirmed_trial, RULES) == []
    assert len(further_causes("rate_dependence", causes, confirmed_trial, RULES)) == RULES.max_further_causes
    one = dataclasses.replace(RULES, max_further_causes=1)
    assert [g for g, _ in further_causes("rate_dependence", causes, confirmed_trial, one)] == ["creep"]
    off = dataclasses.replace(RULES, max_further_causes=0)
    assert further_causes("rate_dependence", causes, confirmed_trial, off) == []


def load_and_temperature(seed: int, share: float = 0.03) -> list[Measurement]:
    """Twelve runs with one hanging mass each (the stroke scales with it) and a temperature per run,
    drawn independently of the mass, that offsets the stroke by ``share`` of its span per 5 K."""
    runs = runs_of(seed, 12, "load")
    rng = np.random.default_rng(seed + 100)
    temperatures = rng.permutation(np.linspace(20.0, 30.0, len(runs)))
    span = float(np.ptp(np.concatenate([m.y for m in runs])))
    out = []
    for m, temperature in zip(runs, temperatures):
        extras = dict(m.extras, temperature=np.full(m.t.size, temperature))
        out.append(Measurement(m.t, m.u, m.y + share * span * (temperature - 25.0) / 5.0, extras, m.source))
    return out


def test_a_further_cause_is_compared_with_the_model_that_already_holds_the_named_one(tmp_path):
    found = [diagnose_runs(load_and_temperature(seed)) for seed in range(3, 9)]
    with_further = [d for d in found if d.further]
    assert with_further, [(d.cause, d.also) for d in found]
    for d in with_further:
        first, h = d.further[0]
        assert first != d.cause and h.clark_west_p <= RULES.alpha and h.interval[0] > 0
        # the further comparison's baseline is the named cause's extension, fitted the same way on the same folds
        np.testing.assert_allclose(h.base_prediction, d.trials[d.cause].ext_prediction, rtol=1e-9, atol=1e-12)
        listed = d.as_json()["also_confirmed"]
        assert isinstance(listed, list) and listed[0]["cause"] == first and listed[0]["beyond"] == [d.cause]
        assert f"{first} also predicts held-out data better" in d.reason
    d = with_further[0]
    text = write_report_v3(d, tmp_path, "12 runs", "mm").read_text()
    first = d.further[0][0]
    assert f"Beyond {d.cause.replace('_', ' ')}, {PLAIN[first]}: adding it too lowers the held-out error" in text
    assert "also confirmed held out" in text  # its role in the evidence table
    # what is named is an injected cause, and the other one is confirmed beyond it on some plants
    # (not on all: on one of these six, a 3.9 % rate term is confirmed beyond the load instead, with
    # an actuator lag of 0.1 s where none acts; the further step inherits the held-out test's
    # calibration, docs/methods/diagnosis.md)
    assert all(d.cause in ("none", "load_dependence", "temperature_drift") for d in found)
    confirmed_both = [d for d in with_further if {d.cause, d.further[0][0]} == {"load_dependence", "temperature_drift"}]
    assert len(confirmed_both) >= 2
