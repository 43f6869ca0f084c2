"""The plant-family scorecard (slow): effects named on plants the method was never tuned on.

``tests/plants`` holds three hysteresis plants besides the HIL; the held-out set (generalised
play, friction + spring) was fixed before any tuning. The targets are the issue's: at least 90 %
of the effects named, at most 1 false alarm in 10 effect-free records. ``python
bench/diagnose_scorecard.py`` prints the same table with every verdict.
"""

from __future__ import annotations

import warnings

import pytest

from host.diagnose.run import diagnose
from tests.plants.family import held_out_cases, measurement, tuning_cases

# the measured scorecard (bench/diagnose_scorecard.py --duration 100), held out and tuning
HELD_OUT_NAMED, HELD_OUT_ALARMS = 4, 2
TUNING_NAMED, TUNING_ALARMS = 4, 1


def _verdicts(case_list) -> list[tuple[str, str]]:
    out = []
    for case in case_list:
        m, _ = measurement(case)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out.append((case.effect, diagnose(m, progress=False).cause))
    return out


@pytest.fixture(scope="module")
def verdicts() -> list[tuple[str, str]]:
    return _verdicts(held_out_cases(100.0))


@pytest.fixture(scope="module")
def tuning_verdicts() -> list[tuple[str, str]]:
    return _verdicts(tuning_cases(100.0))


def named_and_alarms(verdicts: list[tuple[str, str]]) -> tuple[int, int]:
    named = sum(truth == verdict for truth, verdict in verdicts if truth != "none")
    alarms = sum(verdict != "none" for truth, verdict in verdicts if truth == "none")
    return named, alarms


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True, reason=f"below target: {HELD_OUT_NAMED}/20 held-out effects named (bench/diagnose_scorecard.py)"
)
def test_at_least_90_percent_of_held_out_effects_are_named(verdicts):
    effects = [(truth, verdict) for truth, verdict in verdicts if truth != "none"]
    named = sum(truth == verdict for truth, verdict in effects)
    assert named >= 0.9 * len(effects), effects


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=f"below target: {HELD_OUT_ALARMS}/10 false alarms on held-out plants (bench/diagnose_scorecard.py)",
)
def test_at_most_one_false_alarm_in_ten_effect_free_held_out_records(verdicts):
    alarms = [verdict for truth, verdict in verdicts if truth == "none" and verdict != "none"]
    assert len(alarms) <= 1, alarms


@pytest.mark.slow
def test_the_scorecards_do_not_fall_below_the_recorded_numbers(verdicts, tuning_verdicts):
    """What README and docs/benchmarks.md report (``--duration 100``); a change of the method that
    names fewer or alarms more must show up here, not only in a re-run of the bench."""
    assert named_and_alarms(verdicts)[0] >= HELD_OUT_NAMED, verdicts
    assert named_and_alarms(verdicts)[1] <= HELD_OUT_ALARMS, verdicts
    assert named_and_alarms(tuning_verdicts)[0] >= TUNING_NAMED, tuning_verdicts
    assert named_and_alarms(tuning_verdicts)[1] <= TUNING_ALARMS, tuning_verdicts


FOREIGN_CASES = [
    ("none", 1, {}),
    ("none", 2, {}),
    ("transport_delay", 1, {}),
    ("transport_delay", 2, {}),
    ("rate_dependence", 1, {"widening": 0.5}),
    ("rate_dependence", 1, {"widening": 1.5}),
    ("rate_dependence", 2, {"widening": 1.0, "power": 2.0}),
]


@pytest.mark.slow
@pytest.mark.parametrize("effect, seed, options", FOREIGN_CASES, ids=lambda v: str(v))
def test_the_rate_dependent_pi_plant_is_diagnosed(effect, seed, options):
    from tests.foreign_plant import rate_dependent_pi

    kind = {"none": "none", "transport_delay": "delay", "rate_dependence": "rate"}[effect]
    result = diagnose(rate_dependent_pi(kind, seed, **options), progress=False)
    assert result.cause == effect, (result.reason, result.scores)
