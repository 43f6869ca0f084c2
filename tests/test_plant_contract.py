"""Every plant family keeps the corpus's promises: the checks of :mod:`bench.plants.contract`
run on every family of the registry (scikit-learn's ``parametrize_with_checks`` shape). A check a
family is tagged out of is skipped with the reason; the diagnosis is never run here.

Records are :data:`DURATION_S` long, each simulated once per session.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from typing import Any

import pytest

from bench.plants import contract, engine
from bench.plants.case import Case
from bench.plants.families import FAMILIES
from bench.plants.registry import specs

DURATION_S = 40.0
SPECS = specs()
SIMULATED = [name for name, spec in SPECS.items() if spec.custom_record is None]


@cache
def _cases(family: str) -> tuple[Case, ...]:
    return tuple(engine.cases(SPECS[family], DURATION_S))


@cache
def _simulated(family: str, index: int) -> dict[str, Any]:
    return engine.simulate(SPECS[family], _cases(family)[index])


def _sims(family: str) -> list[tuple[Case, dict[str, Any]]]:
    return [(case, _simulated(family, i)) for i, case in enumerate(_cases(family))]


def _skip_unless_applies(check: Callable[..., None], family: str) -> None:
    if not contract.applies(check, SPECS[family]):
        pytest.skip(f"{family} is tagged out of {check.__name__}")


def test_the_registry_finds_every_family_and_the_benches_see_the_same() -> None:
    assert len(SPECS) >= 13 and list(FAMILIES) == list(SPECS)  # the 13 scored families, and any new one
    for name, spec in SPECS.items():
        assert spec.name == name
        cases_for, record = FAMILIES[name]
        assert cases_for(5.0) == engine.cases(spec, 5.0)


def _family_checks() -> list[Any]:
    """Every (family, check) pair; a pair the family tags ``slow:<check>`` runs under ``-m slow``."""
    return [
        pytest.param(name, check, marks=[pytest.mark.slow] if f"slow:{check.__name__}" in spec.tags else [])
        for name, spec in SPECS.items()
        for check in contract.FAMILY_CHECKS
    ]


@pytest.mark.parametrize(("family", "check"), _family_checks(), ids=lambda v: getattr(v, "__name__", v))
def test_family_check(family: str, check: Callable[[Any], None]) -> None:
    _skip_unless_applies(check, family)
    check(SPECS[family])


@pytest.mark.parametrize("family", list(SPECS))
def test_unlike_every_older_family(family: str) -> None:
    contract.check_unlike_every_older_family(SPECS[family], SPECS.values())


@pytest.mark.parametrize("family", SIMULATED)
def test_delay_forms_lag(family: str) -> None:
    contract.check_delay_forms_lag(_sims(family))


@pytest.mark.parametrize("family", [name for name in SIMULATED if SPECS[name].calibration is not None])
def test_calibrated_sizes_spread_over_the_band(family: str) -> None:
    contract.check_sizes_spread_over_the_band(SPECS[family], _sims(family))


def _every_case(keep: Callable[[Case], bool] = lambda case: True) -> list[tuple[str, int]]:
    return [(name, i) for name in SIMULATED for i, case in enumerate(_cases(name)) if keep(case)]


@pytest.mark.parametrize("check", contract.RECORD_CHECKS, ids=lambda c: c.__name__)
@pytest.mark.parametrize(("family", "index"), _every_case(), ids=lambda v: str(v))
def test_record_check(family: str, index: int, check: Callable[..., None]) -> None:
    _skip_unless_applies(check, family)
    check(SPECS[family], _cases(family)[index], _simulated(family, index))


@pytest.mark.parametrize(("family", "index"), _every_case(contract.load_or_temperature), ids=lambda v: str(v))
def test_columns_act_only_in_their_own_records(family: str, index: int) -> None:
    check = contract.check_columns_act_only_in_their_own_records
    _skip_unless_applies(check, family)
    check(SPECS[family], _cases(family)[index], _simulated(family, index))
