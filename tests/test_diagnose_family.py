"""The plant-family scorecards (slow): effects named on the tuning plants and on plants never tuned on.

``tests/plants/family.py`` holds the tuning plants (Bouc-Wen, generalised play, friction +
spring, the HIL); ``tests/plants/fresh_family.py`` the first held-out set (four other cores, other
effect forms, protocols and rates), built separately; its verdicts were read while the method
was changed after v4, so it is no longer blind. ``tests/plants/blind_family.py`` is the third set
(four more cores, new forms, protocols and rates), built blind and scored three times, never to
choose between variants; ``tests/plants/blind2_family.py`` the fourth, built blind for v6 and
scored once, at its end, then used with the other three to calibrate v7's gain floor;
``tests/plants/blind3_family.py`` the fifth, built blind for v7 and scored once, at its end;
``tests/plants/blind4_family.py`` the sixth, built blind for v8 and scored once, at its end.
The targets are the
issue's, on the held-out set: at least 90 % of the effects named, at most 1 false alarm in 10
effect-free records. ``python bench/diagnose_scorecard.py`` prints the same tables with every verdict.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable

import pytest

from host.data import Measurement
from host.diagnose.run import diagnose
from tests.plants.blind2_family import blind2_cases, blind2_measurement
from tests.plants.blind3_family import blind3_cases, blind3_measurement
from tests.plants.blind4_family import blind4_cases, blind4_measurement
from tests.plants.blind_family import blind_cases, blind_measurement
from tests.plants.family import Case, measurement, tuning_cases
from tests.plants.fresh_family import fresh_cases, fresh_measurement

# the measured scorecards (bench/diagnose_scorecard.py --duration 100): named effects, false alarms
FRESH_NAMED, FRESH_EFFECTS, FRESH_ALARMS, FRESH_NONE = 11, 40, 1, 20
TUNING_NAMED, TUNING_ALARMS = 16, 1
BLIND_NAMED, BLIND_EFFECTS, BLIND_ALARMS, BLIND_NONE = 10, 40, 0, 20
BLIND2_NAMED, BLIND2_EFFECTS, BLIND2_ALARMS, BLIND2_NONE = 15, 40, 1, 20
BLIND3_NAMED, BLIND3_EFFECTS, BLIND3_ALARMS, BLIND3_NONE = 6, 40, 0, 20
BLIND4_NAMED, BLIND4_EFFECTS, BLIND4_ALARMS, BLIND4_NONE = 8, 40, 0, 20


def _verdicts(
    case_list: list[Case], record: Callable[[Case], tuple[Measurement, dict[str, object]]]
) -> list[tuple[str, str]]:
    out = []
    for case in case_list:
        m, _ = record(case)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out.append((case.effect, diagnose(m, progress=False).cause))
    return out


@pytest.fixture(scope="module")
def verdicts() -> list[tuple[str, str]]:
    return _verdicts(fresh_cases(100.0), fresh_measurement)


@pytest.fixture(scope="module")
def tuning_verdicts() -> list[tuple[str, str]]:
    return _verdicts(tuning_cases(100.0), measurement)


@pytest.fixture(scope="module")
def blind_verdicts() -> list[tuple[str, str]]:
    return _verdicts(blind_cases(100.0), blind_measurement)


@pytest.fixture(scope="module")
def blind2_verdicts() -> list[tuple[str, str]]:
    return _verdicts(blind2_cases(100.0), blind2_measurement)


@pytest.fixture(scope="module")
def blind3_verdicts() -> list[tuple[str, str]]:
    return _verdicts(blind3_cases(100.0), blind3_measurement)


@pytest.fixture(scope="module")
def blind4_verdicts() -> list[tuple[str, str]]:
    return _verdicts(blind4_cases(100.0), blind4_measurement)


def named_and_alarms(verdicts: list[tuple[str, str]]) -> tuple[int, int]:
    named = sum(truth == verdict for truth, verdict in verdicts if truth != "none")
    alarms = sum(verdict != "none" for truth, verdict in verdicts if truth == "none")
    return named, alarms


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=f"below target: {FRESH_NAMED}/{FRESH_EFFECTS} held-out effects named (bench/diagnose_scorecard.py)",
)
def test_at_least_90_percent_of_held_out_effects_are_named(verdicts):
    effects = [(truth, verdict) for truth, verdict in verdicts if truth != "none"]
    named = sum(truth == verdict for truth, verdict in effects)
    assert named >= 0.9 * len(effects), effects


@pytest.mark.slow
def test_at_most_one_false_alarm_in_ten_effect_free_held_out_records(verdicts):
    """Met on the fresh set since the changes after v4 (2/20), but those changes were judged on
    it: the blind set's false alarms are in :func:`test_the_targets_hold_on_the_blind_plants`."""
    alarms = [verdict for truth, verdict in verdicts if truth == "none" and verdict != "none"]
    assert len(alarms) <= len([1 for truth, _ in verdicts if truth == "none"]) / 10, alarms


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=f"below target: {BLIND_NAMED}/{BLIND_EFFECTS} named, {BLIND_ALARMS}/{BLIND_NONE} false alarms (blind set)",
)
def test_the_targets_hold_on_the_blind_plants(blind_verdicts):
    named, alarms = named_and_alarms(blind_verdicts)
    assert named >= 0.9 * BLIND_EFFECTS and alarms <= BLIND_NONE / 10, blind_verdicts


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=f"below target: {BLIND2_NAMED}/{BLIND2_EFFECTS} named, {BLIND2_ALARMS}/{BLIND2_NONE} false alarms "
    "(second blind set)",
)
def test_the_targets_hold_on_the_second_blind_plants(blind2_verdicts):
    named, alarms = named_and_alarms(blind2_verdicts)
    assert named >= 0.9 * BLIND2_EFFECTS and alarms <= BLIND2_NONE / 10, blind2_verdicts


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=f"below target: {BLIND3_NAMED}/{BLIND3_EFFECTS} named, {BLIND3_ALARMS}/{BLIND3_NONE} false alarms "
    "(third blind set)",
)
def test_the_targets_hold_on_the_third_blind_plants(blind3_verdicts):
    named, alarms = named_and_alarms(blind3_verdicts)
    assert named >= 0.9 * BLIND3_EFFECTS and alarms <= BLIND3_NONE / 10, blind3_verdicts


@pytest.mark.slow
@pytest.mark.xfail(
    strict=True,
    reason=f"below target: {BLIND4_NAMED}/{BLIND4_EFFECTS} named, {BLIND4_ALARMS}/{BLIND4_NONE} false alarms "
    "(fourth blind set)",
)
def test_the_targets_hold_on_the_fourth_blind_plants(blind4_verdicts):
    named, alarms = named_and_alarms(blind4_verdicts)
    assert named >= 0.9 * BLIND4_EFFECTS and alarms <= BLIND4_NONE / 10, blind4_verdicts


@pytest.mark.slow
def test_the_scorecards_do_not_fall_below_the_recorded_numbers(
    verdicts, tuning_verdicts, blind_verdicts, blind2_verdicts, blind3_verdicts, blind4_verdicts
):
    """What README and docs/benchmarks.md report (``--duration 100``); a change of the method that
    names fewer or alarms more must show up here, not only in a re-run of the bench."""
    assert named_and_alarms(verdicts)[0] >= FRESH_NAMED, verdicts
    assert named_and_alarms(verdicts)[1] <= FRESH_ALARMS, verdicts
    assert named_and_alarms(tuning_verdicts)[0] >= TUNING_NAMED, tuning_verdicts
    assert named_and_alarms(tuning_verdicts)[1] <= TUNING_ALARMS, tuning_verdicts
    assert named_and_alarms(blind_verdicts)[0] >= BLIND_NAMED, blind_verdicts
    assert named_and_alarms(blind_verdicts)[1] <= BLIND_ALARMS, blind_verdicts
    assert named_and_alarms(blind2_verdicts)[0] >= BLIND2_NAMED, blind2_verdicts
    assert named_and_alarms(blind2_verdicts)[1] <= BLIND2_ALARMS, blind2_verdicts
    assert named_and_alarms(blind3_verdicts)[0] >= BLIND3_NAMED, blind3_verdicts
    assert named_and_alarms(blind3_verdicts)[1] <= BLIND3_ALARMS, blind3_verdicts
    assert named_and_alarms(blind4_verdicts)[0] >= BLIND4_NAMED, blind4_verdicts
    assert named_and_alarms(blind4_verdicts)[1] <= BLIND4_ALARMS, blind4_verdicts


# The rate-dependent PI plant (tests/foreign_plant.py) that the method before v4 named right on
# all seven records. v4 named 1/7: on its effect-free records a velocity-squared lag element
# gained 16-23 % on every fold by fitting the plant's 30 ms lag *after* the hysteresis. Since
# rate dependence must beat a linear lag after the hysteresis (output_lag), the effect-free
# records read none (3/7). Still missed: its rate effects (the rate terms gain 0-5 %: none) and
# one dead time (creep). Recorded as strict xfail so that a fix shows up.
_MISS = pytest.mark.xfail(strict=True, reason="missed on the rate-dependent PI plant (see comment)")
FOREIGN_CASES = [
    ("none", 1, {}),
    ("none", 2, {}),
    pytest.param("transport_delay", 1, {}, marks=_MISS),
    ("transport_delay", 2, {}),
    pytest.param("rate_dependence", 1, {"widening": 0.5}, marks=_MISS),
    pytest.param("rate_dependence", 1, {"widening": 1.5}, marks=_MISS),
    pytest.param("rate_dependence", 2, {"widening": 1.0, "power": 2.0}, marks=_MISS),
]


@pytest.mark.slow
@pytest.mark.parametrize("effect, seed, options", FOREIGN_CASES)
def test_the_rate_dependent_pi_plant_is_diagnosed(effect, seed, options):
    from tests.foreign_plant import rate_dependent_pi

    kind = {"none": "none", "transport_delay": "delay", "rate_dependence": "rate"}[effect]
    result = diagnose(rate_dependent_pi(kind, seed, **options), progress=False)
    assert result.cause == effect, (result.reason, result.scores)
