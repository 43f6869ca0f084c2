"""The plant families are frozen artefacts: every case's record is checked against a checksum.

A family that was scored once must never move, whatever is refactored underneath it. Each case
of every registered family is recorded at :data:`DURATION_S` and its time, input, output, load
and temperature columns (rounded to :data:`DECIMALS` places) and its truth (every number to
:data:`SIGNIFICANT` significant digits) are hashed; the hashes of every case, in the order the
family lists them, are in ``tests/data/plant_checksums.json``.

The default run checks every :data:`DEFAULT_STRIDE`-th case of each family (a few CPU seconds);
``-m slow`` checks them all. Rewrite the file only when a family is meant to change (a new
family, never an old one): ``python -m tests.test_plant_checksums --write``.
"""

from __future__ import annotations

import hashlib
import json
import sys
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from bench.plants.families import FAMILIES

DURATION_S = 20.0  # s: the shortest record every protocol of every family builds
DECIMALS = 6  # of each column, in its own unit (s, bar, mm, kg, degC): far above a BLAS update's reach
SIGNIFICANT = 6  # of every number in the truth
DEFAULT_STRIDE = 13
CHECKSUMS = Path(__file__).resolve().parent / "data" / "plant_checksums.json"


def _rounded(value: Any) -> Any:
    """``value`` with every float written to :data:`SIGNIFICANT` digits (a JSON-able copy)."""
    if isinstance(value, dict):
        return {str(k): _rounded(v) for k, v in sorted(value.items())}
    if isinstance(value, (list, tuple)):
        return [_rounded(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return f"{float(value):.{SIGNIFICANT}g}"
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, np.ndarray):
        return [_rounded(float(v)) for v in value.ravel()]
    return str(value)


def case_checksum(family: str, index: int) -> tuple[str, str]:
    """The name of ``family``'s case ``index`` at :data:`DURATION_S` and its record's checksum."""
    cases_for, record = FAMILIES[family]
    case = cases_for(DURATION_S)[index]
    m, truth = record(case)
    digest = hashlib.sha256()
    for column in (m.t, m.u, m.y, m.extras["load"], m.extras["temperature"]):
        rounded = np.round(np.asarray(column, dtype=np.float64), DECIMALS) + 0.0  # + 0.0: no negative zero
        digest.update(rounded.tobytes())
    digest.update(json.dumps(_rounded(truth), sort_keys=True).encode())
    return case.name, digest.hexdigest()[:20]


def all_checksums() -> dict[str, list[list[str]]]:
    """Every registered family's cases, in order, as ``[name, checksum]`` pairs."""
    out: dict[str, list[list[str]]] = {}
    for family, (cases_for, _) in FAMILIES.items():
        out[family] = [list(case_checksum(family, i)) for i in range(len(cases_for(DURATION_S)))]
    return out


@cache
def _frozen() -> dict[str, list[list[str]]]:
    return dict(json.loads(CHECKSUMS.read_text()))


def _ids(stride: int) -> list[tuple[str, int]]:
    sizes = {family: len(cases_for(DURATION_S)) for family, (cases_for, _) in FAMILIES.items()}
    return [(family, i) for family, size in sizes.items() for i in range(0, size, stride)]


def test_every_frozen_family_is_registered_with_the_same_cases() -> None:
    frozen = _frozen()
    assert set(FAMILIES) == set(frozen)
    for family, (cases_for, _) in FAMILIES.items():
        assert [c.name for c in cases_for(DURATION_S)] == [name for name, _ in frozen[family]], family


@pytest.mark.parametrize(("family", "index"), _ids(DEFAULT_STRIDE), ids=lambda v: str(v))
def test_a_subset_of_cases_is_unchanged(family: str, index: int) -> None:
    assert list(case_checksum(family, index)) == _frozen()[family][index]


@pytest.mark.slow
@pytest.mark.parametrize(("family", "index"), _ids(1), ids=lambda v: str(v))
def test_every_case_is_unchanged(family: str, index: int) -> None:
    assert list(case_checksum(family, index)) == _frozen()[family][index]


if __name__ == "__main__":
    if sys.argv[1:] != ["--write"]:
        sys.exit("usage: python -m tests.test_plant_checksums --write  (rewrites tests/data/plant_checksums.json)")
    families = all_checksums()
    blocks = [
        f"{json.dumps(family)}: [\n" + ",\n".join(f"  {json.dumps(pair)}" for pair in pairs) + "\n ]"
        for family, pairs in families.items()
    ]
    CHECKSUMS.write_text("{\n " + ",\n ".join(blocks) + "\n}\n")
    print(f"wrote {CHECKSUMS}")
