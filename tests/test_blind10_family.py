"""Properties of the twelfth (blind10) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; protocols start vented shake down early and then keep covering it. Each form's and
core's own physics: :mod:`tests.test_blind10_forms`.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind10_family import (
    BLIND10_PLANTS,
    SPEC,
)
from bench.plants.blind10_protocols import BLIND10_PROTOCOLS, with_exhaust_shakedown
from bench.plants.blind10_rig import (
    hart_bursts,
    held,
    muscle_pressure,
    stroke_reading,
    triboelectric,
    waveguide_error,
)
from bench.plants.case import Case
from bench.plants.filters import lowpass
from bench.plants.visibility import rms

DURATION_S = 30.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND10_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The HART bursts and the transmitter's held updates in the recorded input, the waveguide's
    error and the cable's triboelectric noise on the stroke, the load converter's stairs and the
    NTC's uneven step are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    params, dt, u = truth["plant_parameters"], 1.0 / case.rate_hz, sim["command"]
    pressure = held(muscle_pressure(u, dt, params), dt, params["tx_update_s"], params["tx_phase"])
    bursts = sim["u"] - lowpass(pressure, dt, dt / (2.0 * np.pi * params["aa_share"]))
    assert np.allclose(bursts, hart_bursts(u.size, dt, params))
    assert 0.0 < rms(bursts) < 0.005 * params["peak"] and np.mean(bursts == 0.0) > 0.5  # bursts, then quiet
    assert np.std(m.u - sim["u"]) < 0.01  # bar: the converter's noise and step
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], dt, params))
    static = waveguide_error(sim["base"], params)
    assert np.max(np.abs(static)) <= params["wave_amp_mm"] + abs(params["bow_mm"]) * 1.5 + 1e-9
    tribo = triboelectric(sim["base"], dt, params)
    speed = np.abs(np.gradient(sim["base"], dt))
    fast, still = speed > np.percentile(speed, 80), speed < np.percentile(speed, 20)
    assert rms(tribo[fast]) > 3.0 * rms(tribo[still]) and rms(tribo) < truth["noise"]  # grows with the speed
    assert rms(sim["off"] - sim["base"]) < 2.0 * truth["noise"]  # a few noise units at most
    load = m.extras["load"]
    changes = np.count_nonzero(np.diff(load))
    assert changes <= DURATION_S * params["hx711_sps"] + 1  # stairs at the converter's rate
    temp_steps = np.unique(np.round(np.abs(np.diff(m.extras["temperature"])), 6))
    temp_steps = temp_steps[temp_steps > 0.0]
    assert temp_steps.size >= 2 and np.ptp(temp_steps[temp_steps < 0.2]) > 0.0  # the step is not uniform


@pytest.mark.parametrize("protocol", list(BLIND10_PROTOCOLS))
def test_protocols_start_vented_shake_down_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 52.0, 4.0
    for seed in range(3):
        u = with_exhaust_shakedown(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3120 and np.all(np.isfinite(u)) and np.all(u[: int(0.3 / dt)] == 0.0)
        early = int(0.12 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(5.5 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 3  # three sawtooth fills
        falls = np.diff(lead) < -0.1 * peak  # a quick exhaust drops a tenth of the range or more per sample
        assert np.count_nonzero(np.diff(falls.astype(np.int64)) > 0) >= 3  # three of them
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
