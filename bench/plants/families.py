"""Every plant family the diagnosis is scored on, by name: how to list its cases and record one.

One registry for ``bench/diagnose_scorecard.py``, ``bench/diagnose_ceiling.py`` and the slow
family test (``tests/test_diagnose_family.py``), built by scanning (:mod:`bench.plants.registry`),
so a new family is one module in ``bench/plants`` and nothing else.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from functools import partial
from typing import Any

from bench.plants import engine
from bench.plants.case import Case
from bench.plants.registry import specs
from host.data import Measurement

Cases = Callable[[float], list[Case]]  # a family's cases for a record duration [s]
Record = Callable[[Case], tuple[Measurement, dict[str, Any]]]  # a case's recording and its truth

FAMILIES: dict[str, tuple[Cases, Record]] = {
    name: (partial(engine.cases, spec), partial(engine.measurement, spec)) for name, spec in specs().items()
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
