"""Properties of the thirteenth (blind11) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; protocols start vented condition early and then keep covering it. Each form's and
core's own physics: :mod:`tests.test_blind11_forms`.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind11_family import (
    BLIND11_PLANTS,
    SPEC,
)
from bench.plants.blind11_protocols import BLIND11_PROTOCOLS, with_ringdown_conditioning
from bench.plants.blind11_rig import (
    TC_CONVERSION_S,
    load_reading,
    muscle_pressure,
    regulator_pressure,
    second_order,
    stroke_reading,
    triangulation_error,
)
from bench.plants.case import Case
from bench.plants.visibility import rms

DURATION_S = 30.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND11_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The regulator's dead band, the line's ringing and the bridge's warm-up drift in the recorded
    input, the triangulation and speckle errors and the averaging on the stroke, the hum and the
    12-bit count on the load, the thermocouple's held conversions: in every record, none an effect
    of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    params, dt, u = truth["plant_parameters"], 1.0 / case.rate_hz, sim["command"]
    t = np.arange(u.size) * dt
    outlet = regulator_pressure(u, dt, params)
    band = params["deadband_bar"]
    assert np.all(outlet <= np.maximum.accumulate(u) + 1e-12) and np.max(np.abs(outlet - u)) > band
    inside = np.abs(u[1:] - outlet[:-1]) <= band  # the set pressure within the band: no port opens
    assert np.all(outlet[1:][inside] == outlet[:-1][inside]) and np.count_nonzero(inside) > 0.05 * u.size
    ringing = second_order(outlet, dt, params["line_ring_hz"], params["line_ring_zeta"]) - outlet
    drift = sim["u"] - outlet - params["ring_share"] * ringing
    assert np.allclose(drift, params["warm_bar"] * (1.0 - np.exp(-t / params["warm_tau_s"])), atol=1e-12)
    assert 0.0 < rms(params["ring_share"] * ringing) < 0.01 * params["peak"]
    muscle = muscle_pressure(u, dt, params)
    assert rms(sim["u"] - muscle) > 0.0 and np.std(m.u - sim["u"]) < 0.01  # leads the muscle; converter noise
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], dt, params))
    static = triangulation_error(sim["base"], params)
    assert np.max(np.abs(static)) <= abs(params["lin_mm"]) + 4.0 * params["speckle_mm"]
    assert rms(static) > 0.002
    load_err = load_reading(np.full(u.size, 3.0), dt, params, np.random.default_rng(0)) - 3.0
    assert 0.5 * params["hum_kg"] / np.sqrt(2.0) < rms(load_err) < 3.0 * (params["hum_kg"] + params["load_step_kg"])
    temp = m.extras["temperature"]
    changes = np.flatnonzero(np.diff(temp))
    assert changes.size >= 2 and np.min(np.diff(changes)) * dt >= TC_CONVERSION_S - 1.5 * dt


@pytest.mark.parametrize("protocol", list(BLIND11_PROTOCOLS))
def test_protocols_start_vented_condition_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 58.0, 4.0
    for seed in range(3):
        u = with_ringdown_conditioning(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3480 and np.all(np.isfinite(u)) and np.all(u[: int(0.3 / dt)] == 0.0)
        early = int(0.12 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(4.8 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 2  # two fills
        assert np.count_nonzero(lead[int(1.0 / dt) :] == 0.0) >= 2  # vented between them
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
