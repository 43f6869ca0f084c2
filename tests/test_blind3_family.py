"""Properties of the fifth (blind3) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the
sensor confounds; protocols start vented sweep the range early and then keep covering it.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind3_cores import BLIND3_CORES, position_sensor
from bench.plants.blind3_family import (
    BLIND3_PLANTS,
    SPEC,
)
from bench.plants.blind3_protocols import BLIND3_PROTOCOLS, with_full_sweep
from bench.plants.case import Case
from bench.plants.visibility import rms

DURATION_S = 40.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND3_PLANTS)
def test_effect_free_records_carry_the_sensor_confounds(plant: str) -> None:
    """The transducer's nonlinearity and mains hum are in every record, effect-free ones too."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    params, dt = sim["truth"]["plant_parameters"], 1.0 / case.rate_hz
    core_out = BLIND3_CORES[plant](sim["u"], dt, params)
    confound = sim["off"] - core_out
    assert 0.03 <= rms(confound) <= 0.5  # mm: bow and ripple of the nonlinearity, plus hum
    held = position_sensor(np.full(4000, 10.0), dt, params) - 10.0  # a still stroke: only the hum moves
    assert 0.005 <= float(np.std(held)) <= 0.03


@pytest.mark.parametrize("protocol", list(BLIND3_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 64.0, 4.0
    u = with_full_sweep(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 3840 and np.all(np.isfinite(u)) and np.all(u[:38] == 0.0)
    early = int(0.15 * u.size)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
    body = u[early:]
    assert np.ptp(body) > 0.5 * peak
    crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
    assert crossings >= 4  # the range is covered again and again, not once
