"""Properties of the fourth (blind2) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: protocols start vented stay in
range and excite.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind2_family import (
    SPEC,
)
from bench.plants.blind2_protocols import BLIND2_PROTOCOLS, with_range_check
from bench.plants.case import Case

DURATION_S = 40.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("protocol", list(BLIND2_PROTOCOLS))
def test_protocols_start_vented_stay_in_range_and_excite(protocol: str) -> None:
    dt, peak = 1.0 / 70.0, 4.0
    u = with_range_check(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 4200 and np.all(np.isfinite(u)) and np.all(u[:70] == 0.0)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:420]) >= 0.97 * peak
    assert np.ptp(u[420:]) > 0.4 * peak
