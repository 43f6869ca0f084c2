"""Properties of the seventh (blind5) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; exhaust pilot delays only deflation; protocols start vented sweep the range early and
then keep covering it; dropped frames repeat the frame before on every channel; slack takeup
moves only the descending branch.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    blind2_family,
    blind3_family,
    blind4_family,
    blind_family,
    engine,
    family,
    fresh_family,
)
from bench.plants.blind5_cores import BLIND5_CORES, draw_params
from bench.plants.blind5_effects import (
    draw_effect_params,
    render,
)
from bench.plants.blind5_family import (
    BLIND5_PLANTS,
    SEED_OFFSET,
    SPEC,
)
from bench.plants.blind5_protocols import BLIND5_PROTOCOLS, with_valve_sweep
from bench.plants.blind5_rig import dropped_frames, regulator, stroke_reading
from bench.plants.case import Case
from bench.plants.visibility import rms

DURATION_S = 60.0
CASES = engine.cases(SPEC, DURATION_S)
OLDER_FAMILIES = (family, fresh_family, blind_family, blind2_family, blind3_family, blind4_family)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND5_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """Regulator lag and play, the transducer's gain error, the mount's settling, aliased hum
    and dropped frames are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    params, dt = truth["plant_parameters"], 1.0 / case.rate_hz
    u = sim["command"]
    gain = sim["u"][u > 0.5 * params["peak"]] / u[u > 0.5 * params["peak"]]
    assert 0.003 <= float(np.max(np.abs(gain - 1.0))) <= 0.03  # the transducer's gain error and offset
    pressure = regulator(u, dt, params)
    loop = pressure - u
    assert 0.003 * params["peak"] <= float(np.max(np.abs(loop[u == u[-1]]))) or np.ptp(loop) > 0.004 * params["peak"]
    still = stroke_reading(np.full(int(60.0 / dt), 10.0), dt, params) - 10.0
    assert 0.01 <= float(np.max(-still)) <= 0.06  # mm: the mount settles, no more than a few noise units
    hum = still - np.convolve(still, np.ones(9) / 9.0, mode="same")
    assert 0.002 <= float(np.std(hum[20:-20])) <= 0.012  # mm: mains hum
    assert truth["dropped_frames"] >= 1 and truth["dropped_frames"] <= 0.01 * len(m)
    assert 0.005 < rms(sim["off"] - BLIND5_CORES[plant](u, dt, params)) < 0.1  # mm: settling and hum


def test_exhaust_pilot_delays_only_deflation() -> None:
    dt, peak = 0.005, 4.0
    t = np.arange(int(round(20.0 / dt))) * dt
    u = peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / 10.0) % 1.0) - 1.0)))
    params = draw_params("vector_fibre_play", np.random.default_rng(3), peak)
    q = {"pilot_s": 0.2}
    still = np.zeros_like(u)
    diff = render(BLIND5_CORES["vector_fibre_play"], params, u, dt, "exhaust_pilot", q, still, still + 21.0)
    diff -= render(BLIND5_CORES["vector_fibre_play"], params, u, dt, "none", q, still, still + 21.0)
    phase = (t / 10.0) % 1.0
    late_rise, falling = (phase > 0.3) & (phase < 0.5), (phase > 0.55) & (phase < 0.95)
    assert np.max(diff[falling]) > 0.05 and np.max(np.abs(diff[late_rise])) < 0.1 * np.max(diff[falling])


@pytest.mark.parametrize("protocol", list(BLIND5_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 84.0, 4.0
    u = with_valve_sweep(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 5040 and np.all(np.isfinite(u)) and np.all(u[:33] == 0.0)
    early = int(0.15 * u.size)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
    body = u[early:]
    assert np.ptp(body) > 0.5 * peak
    crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
    assert crossings >= 2  # the range is covered again, not once


def test_dropped_frames_repeat_the_frame_before_on_every_channel() -> None:
    case = next(c for c in CASES if c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    drops = dropped_frames(
        len(m), np.random.default_rng(case.seed + SEED_OFFSET + 1), truth["plant_parameters"]["drop_share"]
    )
    assert drops.size == truth["dropped_frames"] >= 1
    for column in (m.y, m.u, m.extras["load"], m.extras["temperature"]):
        assert np.array_equal(column[drops], column[drops - 1])
    assert np.array_equal(m.t, sim["t"])  # the time stamps stay uniform


def test_slack_takeup_moves_only_the_descending_branch() -> None:
    dt, peak = 0.005, 4.0
    t = np.arange(int(round(40.0 / dt))) * dt
    u = peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / 10.0) % 1.0) - 1.0)))
    params = draw_params("rolling_lobe_peel", np.random.default_rng(4), peak)
    q = draw_effect_params("load_dependence", "slack_takeup", np.random.default_rng(4))
    load, temps = np.where(t < 10.0, 0.5, 3.0), np.full_like(u, 21.0)
    core = BLIND5_CORES["rolling_lobe_peel"]
    diff = render(core, params, u, dt, "slack_takeup", q, load, temps)
    diff -= render(core, params, u, dt, "slack_takeup", q, np.full_like(load, 0.5), temps)
    phase = (t / 10.0) % 1.0
    late = t > 12.0
    rising, falling = late & (phase > 0.25) & (phase < 0.45), late & (phase > 0.75) & (phase < 0.95)
    assert np.max(np.abs(diff[rising])) < 1e-9 and np.min(diff[falling]) < -0.1  # mm: heavier, lower way down
