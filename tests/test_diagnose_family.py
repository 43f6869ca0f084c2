"""The plant-family scorecards (slow): effects named on the tuning plants and on plants never tuned on.

``bench/plants/family.py`` holds the tuning plants (Bouc-Wen, generalised play, friction +
spring, the HIL); ``bench/plants/fresh_family.py`` the first held-out set (four other cores, other
effect forms, protocols and rates), built separately; its verdicts were read while the method
was changed after v4, so it is no longer blind. ``bench/plants/blind_family.py`` is the third set
(four more cores, new forms, protocols and rates), built blind and scored three times, never to
choose between variants; ``bench/plants/blind2_family.py`` the fourth, built blind for v6 and
scored once, at its end, then used with the other three to calibrate v7's gain floor;
``bench/plants/blind3_family.py`` the fifth, built blind for v7 and scored once, at its end;
``bench/plants/blind4_family.py`` the sixth, built blind for v8 and scored once, at its end;
``bench/plants/blind5_family.py`` the seventh and ``bench/plants/blind6_family.py`` the eighth,
built blind for v9 and scored once each (blind5 before v9's thermal-lag terms, blind6 after);
``bench/plants/blind7_family.py`` the ninth, built blind for v10 and scored once, at its end
(its report was read before v11, whose 3 s thermal lag answers one of its forms);
``bench/plants/blind8_family.py`` the tenth, built blind for v11 and scored once, at its end;
``bench/plants/blind9_family.py`` the eleventh, built blind for v12 and scored once, at its end;
``bench/plants/blind10_family.py`` the twelfth, built blind for v13 and scored once, at its end;
``bench/plants/blind11_family.py`` the thirteenth, built blind for v14 and scored once, at its end.
The targets are the
issue's, on the held-out set: at least 90 % of the effects named, at most 1 false alarm in 10
effect-free records. ``python bench/diagnose_scorecard.py`` prints the same tables with every verdict.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import pytest

from bench.plants.families import FAMILIES as REGISTRY
from bench.plants.families import Cases, Record
from host.diagnose.run import diagnose


@dataclass(frozen=True)
class Family:
    """A plant family and its measured scorecard (``bench/diagnose_scorecard.py --duration 100``)."""

    cases: Cases
    record: Record
    named: int
    effects: int
    alarms: int
    effect_free: int


# the recorded scorecards (named, effects, false alarms, effect-free records) of each family
SCORECARDS = {
    "tuning": (18, 35, 2, 20),
    "fresh": (12, 40, 1, 20),
    "blind": (14, 40, 0, 20),
    "blind2": (17, 40, 2, 20),
    "blind3": (8, 40, 0, 20),
    "blind4": (11, 40, 0, 20),
    "blind5": (12, 40, 0, 20),
    "blind6": (17, 40, 0, 20),
    "blind7": (11, 40, 1, 20),
    "blind8": (15, 40, 0, 20),
    "blind9": (14, 40, 0, 20),
    "blind10": (8, 40, 1, 20),
    "blind11": (21, 40, 2, 20),
}
FAMILIES = {name: Family(*REGISTRY[name], *scorecard) for name, scorecard in SCORECARDS.items()}
HELD_OUT = [name for name in FAMILIES if name != "tuning"]
_VERDICTS: dict[str, list[tuple[str, str]]] = {}


def family_verdicts(name: str) -> list[tuple[str, str]]:
    """(true effect, verdict) of every record of family ``name`` at 100 s, diagnosed once per run."""
    if name not in _VERDICTS:
        family, out = FAMILIES[name], []
        for case in family.cases(100.0):
            m, _ = family.record(case)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out.append((case.effect, diagnose(m, progress=False).cause))
        _VERDICTS[name] = out
    return _VERDICTS[name]


def named_and_alarms(verdicts: list[tuple[str, str]]) -> tuple[int, int]:
    named = sum(truth == verdict for truth, verdict in verdicts if truth != "none")
    alarms = sum(verdict != "none" for truth, verdict in verdicts if truth == "none")
    return named, alarms


def _below_target(name: str) -> pytest.MarkDecorator:
    f = FAMILIES[name]
    return pytest.mark.xfail(
        strict=True, reason=f"below target: {f.named}/{f.effects} named, {f.alarms}/{f.effect_free} false alarms"
    )


@pytest.mark.slow
@pytest.mark.parametrize("name", [pytest.param(name, marks=_below_target(name)) for name in HELD_OUT])
def test_the_targets_hold_on_plants_never_tuned_on(name):
    """The issue's targets: at least 90 % of the effects named and at most 1 false alarm in 10
    effect-free records, on every held-out family (strict xfail: a family that meets them shows up)."""
    f = FAMILIES[name]
    named, alarms = named_and_alarms(family_verdicts(name))
    assert named >= 0.9 * f.effects and alarms <= f.effect_free / 10, family_verdicts(name)


def _alarms_over_target(name: str) -> pytest.MarkDecorator:
    f = FAMILIES[name]
    return pytest.mark.xfail(strict=True, reason=f"{f.alarms}/{f.effect_free} false alarms (recorded)")


@pytest.mark.slow
@pytest.mark.parametrize(
    "name",
    [
        pytest.param(name, marks=_alarms_over_target(name))
        if FAMILIES[name].alarms > FAMILIES[name].effect_free / 10
        else name
        for name in HELD_OUT
    ],
)
def test_at_most_one_false_alarm_in_ten_effect_free_held_out_records(name):
    """Met on every held-out family but the ones marked (strict xfail). blind6 had 4/20 in v9 (an
    input read through a 4-15 ms snubber: the output leads it, which a rate term fitted) and has
    0/20 since the baseline can undo such a lag (v10). The fresh and blind2 sets were judged on
    while the method changed, blind3 to blind7 were scored once each at the end of the round
    they were built for."""
    alarms = named_and_alarms(family_verdicts(name))[1]
    assert alarms <= FAMILIES[name].effect_free / 10, family_verdicts(name)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(FAMILIES))
def test_the_scorecards_do_not_fall_below_the_recorded_numbers(name):
    """What README and docs/benchmarks.md report (``--duration 100``); a change of the method that
    names fewer or alarms more must show up here, not only in a re-run of the bench."""
    named, alarms = named_and_alarms(family_verdicts(name))
    assert named >= FAMILIES[name].named and alarms <= FAMILIES[name].alarms, family_verdicts(name)


# The rate-dependent PI plant (tests/foreign_plant.py) that the method before v4 named right on
# all seven records. v4 named 1/7: on its effect-free records a velocity-squared lag element
# gained 16-23 % on every fold by fitting the plant's 30 ms lag *after* the hysteresis. Since
# rate dependence must beat a linear lag after the hysteresis (output_lag), the effect-free
# records read none (3/7). Still missed: its rate effects (the rate terms gain 0-5 %: none); the
# dead time that read as creep was named from v11 to v13 (4/7), and is none again since v14
# (below). Recorded as strict xfail so that a fix shows up.
_MISS = pytest.mark.xfail(strict=True, reason="missed on the rate-dependent PI plant (see comment)")
# named from v11 to v13; since v14 the output_lag yardstick holds a payload on a fixed stiffness (a
# second-order element), which follows this plant's dead time as well: seed 1 +81.8 % against the
# dead time's +77.5 %, so the verdict is none ("cannot tell transport_delay from output_lag")
_DELAY_TIE = pytest.mark.xfail(
    strict=True,
    reason="v14: a second-order mechanics yardstick explains this dead time as well as the dead time does",
)
FOREIGN_CASES = [
    ("none", 1, {}),
    ("none", 2, {}),
    pytest.param("transport_delay", 1, {}, marks=_DELAY_TIE),
    pytest.param("transport_delay", 2, {}, marks=_DELAY_TIE),
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
