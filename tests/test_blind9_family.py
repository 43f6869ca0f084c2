"""Properties of the eleventh (blind9) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; protocols start vented shake down early and then keep covering it. Each form's and
core's own physics: :mod:`tests.test_blind9_forms`.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind9_family import (
    BLIND9_PLANTS,
    SPEC,
)
from bench.plants.blind9_protocols import BLIND9_PROTOCOLS, with_shakedown
from bench.plants.blind9_rig import (
    load_cell_zero_shift,
    muscle_pressure,
    rail_dip,
    rc_filter,
    slew_limited,
    stroke_reading,
    wire_wound,
)
from bench.plants.case import Case
from bench.plants.visibility import rms

DURATION_S = 40.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The manifold's carrier ripple and the amplifier's slew limit in the recorded input, the
    pot's turn steps and the rail's dip on the stroke, the RC filters, and the load cell's thermal
    zero shift are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    params, dt, u = truth["plant_parameters"], 1.0 / case.rate_hz, sim["command"]
    pressure = muscle_pressure(u, dt, params)
    smooth = rc_filter(
        slew_limited(pressure, dt, params["amp_slew_per_s"] * params["peak"]), dt, params["aa_share"] / dt
    )
    ripple = sim["u"] - smooth
    assert 0.0 < rms(ripple) < 0.01 * params["peak"]
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], u, dt, params))
    steps = wire_wound(sim["base"], params) - sim["base"]
    pitch = params["pot_pitch_mm"]
    assert np.max(np.abs(steps)) <= (0.5 + params["pot_irregularity"]) * pitch + 1e-9 and np.std(steps) > 0.1 * pitch
    dip = rail_dip(u, dt, params)
    assert np.all(dip >= 0.0) and 0.0 < np.max(dip) <= params["rail_dip"] * (1.0 + 1e-9)
    assert np.corrcoef(dip, u)[0, 1] > 0.5  # the dip follows the input: a decoy
    corner = params["aa_share"] * (1.0 + params["aa_mismatch"]) / dt
    assert rms(sim["off"] - rc_filter(sim["base"], dt, corner)) < 3.0 * truth["noise"]  # a few noise units at most
    assert np.std(m.u - sim["u"]) < 0.01  # bar: the converter's noise and step
    shift = load_cell_zero_shift(sim["temperature"], params)
    assert np.std(m.extras["load"] - sim["load"] - shift) < 0.01 and np.any(shift != 0.0)


@pytest.mark.parametrize("protocol", list(BLIND9_PROTOCOLS))
def test_protocols_start_vented_shake_down_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 56.0, 4.0
    for seed in range(3):
        u = with_shakedown(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3360 and np.all(np.isfinite(u)) and np.all(u[: int(0.4 / dt)] == 0.0)
        early = int(0.15 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(6.5 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 4  # four shakedown pulses
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
