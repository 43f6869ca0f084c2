"""Every plant family the diagnosis is scored on, by name: how to list its cases and record one.

One registry for ``bench/diagnose_scorecard.py``, ``bench/diagnose_ceiling.py`` and the slow
family test (``tests/test_diagnose_family.py``), so a new family is added in one place.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import Any

from bench.plants.blind2_family import blind2_cases, blind2_measurement
from bench.plants.blind3_family import blind3_cases, blind3_measurement
from bench.plants.blind4_family import blind4_cases, blind4_measurement
from bench.plants.blind5_family import blind5_cases, blind5_measurement
from bench.plants.blind6_family import blind6_cases, blind6_measurement
from bench.plants.blind7_family import blind7_cases, blind7_measurement
from bench.plants.blind8_family import blind8_cases, blind8_measurement
from bench.plants.blind9_family import blind9_cases, blind9_measurement
from bench.plants.blind10_family import blind10_cases, blind10_measurement
from bench.plants.blind11_family import blind11_cases, blind11_measurement
from bench.plants.blind_family import blind_cases, blind_measurement
from bench.plants.family import Case, measurement, tuning_cases
from bench.plants.fresh_family import fresh_cases, fresh_measurement
from host.data import Measurement

Cases = Callable[[float], list[Case]]  # a family's cases for a record duration [s]
Record = Callable[[Case], tuple[Measurement, dict[str, Any]]]  # a case's recording and its truth

FAMILIES: dict[str, tuple[Cases, Record]] = {
    "tuning": (tuning_cases, measurement),
    "fresh": (fresh_cases, fresh_measurement),
    "blind": (blind_cases, blind_measurement),
    "blind2": (blind2_cases, blind2_measurement),
    "blind3": (blind3_cases, blind3_measurement),
    "blind4": (blind4_cases, blind4_measurement),
    "blind5": (blind5_cases, blind5_measurement),
    "blind6": (blind6_cases, blind6_measurement),
    "blind7": (blind7_cases, blind7_measurement),
    "blind8": (blind8_cases, blind8_measurement),
    "blind9": (blind9_cases, blind9_measurement),
    "blind10": (blind10_cases, blind10_measurement),
    "blind11": (blind11_cases, blind11_measurement),
}


def family_names(text: str, known: Collection[str] = tuple(FAMILIES)) -> list[str]:
    """The family names in ``text`` (comma-separated, blanks dropped), each one of ``known``;
    ``ValueError`` naming what is unknown (or that none was given) and the names to use, for a
    bench's ``--set`` to report in one line."""
    names = [name for name in text.split(",") if name]
    unknown = [name for name in names if name not in known]
    if unknown or not names:
        raise ValueError(f"unknown family {', '.join(unknown) or '(none given)'}; use some of {', '.join(known)}")
    return names
