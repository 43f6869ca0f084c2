"""Properties of the tenth (blind8) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; protocols start vented shake down early and then keep covering it. Each form's and
core's own physics: :mod:`tests.test_blind8_forms`.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind8_family import (
    BLIND8_PLANTS,
    SPEC,
)
from bench.plants.blind8_protocols import BLIND8_PROTOCOLS, with_shakedown
from bench.plants.blind8_rig import (
    anti_alias,
    autozero_steps,
    muscle_pressure,
    port_flow_noise,
    sar_bit_error,
    stroke_reading,
)
from bench.plants.case import Case
from bench.plants.visibility import rms

DURATION_S = 60.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND8_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The port's flow noise in the recorded input, the SAR bit errors, the auto-zero steps and
    the anti-alias filters are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    params, dt = truth["plant_parameters"], 1.0 / case.rate_hz
    pressure = muscle_pressure(sim["command"], dt, params)
    flow_noise = sim["u"] - anti_alias(pressure, dt, params["aa_share"])
    assert 0.0 < rms(flow_noise) < 0.01 * params["peak"]
    noise = port_flow_noise(pressure, dt, params)
    flow = np.abs(np.diff(pressure, prepend=pressure[0])) / dt / (params["slew_per_s"] * params["peak"])
    assert np.all(np.abs(noise[flow < 1e-6]) < 1e-6) and np.any(noise != 0.0)  # only while air flows
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], dt, params))
    clean = {**params, "autozero_mm": 0.0, **{k: 0.0 for k in params if k.startswith("sar_w")}}
    corner = params["aa_share"] * (1.0 + params["aa_mismatch"])  # the stroke channel's, a little off
    assert np.allclose(stroke_reading(sim["base"], dt, clean), anti_alias(sim["base"], dt, corner))
    sar = sar_bit_error(sim["base"], params)
    assert 0.0 < np.max(np.abs(sar)) < 30.0 * params["sar_lsb_mm"]
    zero = autozero_steps(sim["base"].size, dt, params)
    assert len(np.unique(zero)) >= 2 and np.max(np.abs(zero)) < 5.0 * params["autozero_mm"]
    assert rms(sar + zero) < 3.0 * truth["noise"]  # a few noise units at most
    assert np.std(m.u - sim["u"]) < 0.01  # bar: the transducer's noise and step


@pytest.mark.parametrize("protocol", list(BLIND8_PROTOCOLS))
def test_protocols_start_vented_shake_down_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 48.0, 4.0
    for seed in range(3):
        u = with_shakedown(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 2880 and np.all(np.isfinite(u)) and np.all(u[:24] == 0.0)
        early = int(0.15 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(7.0 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 4  # four shakedown cycles
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
