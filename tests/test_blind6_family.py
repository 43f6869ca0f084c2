"""Properties of the eighth (blind6) held-out plant family; the diagnosis is never run here.

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: effect free records carry the rig
confounds; pilot dead time is longest for slow changes; creep forms keep moving in a hold and
the core alone settles; one way damper lags only the falling branch; ptfe liner acts through the
loop width; protocols start vented sweep the range early and then keep covering it.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    engine,
)
from bench.plants.blind6_cores import BLIND6_CORES, draw_params
from bench.plants.blind6_effects import (
    BLIND6_FORMS,
    draw_effect_params,
    pilot_lag_s,
    render,
)
from bench.plants.blind6_family import (
    BLIND6_PLANTS,
    SPEC,
)
from bench.plants.blind6_protocols import BLIND6_PROTOCOLS, with_choked_sweep
from bench.plants.blind6_rig import compressor_bursts, spool_valve, stroke_reading
from bench.plants.case import Case
from bench.plants.properties import (
    step_and_hold,
    triangles,
)
from bench.plants.visibility import rms

DURATION_S = 60.0
CASES = engine.cases(SPEC, DURATION_S)
STILL_TEMP_C = 22.0


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("plant", BLIND6_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The snubbed pressure port, the valve's overshoot, compressor vibration, crosstalk and
    sampling jitter are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = engine.measurement_from(SPEC, case, sim)
    params, dt = truth["plant_parameters"], 1.0 / case.rate_hz
    u = sim["command"]
    assert 0.003 < rms(sim["u"] - u) / params["peak"] < 0.1  # the recorded input is the muscle's, lagged
    step = np.where(np.arange(int(2.0 / dt)) * dt < 0.5, 0.0, params["peak"])
    overshoot = float(np.max(spool_valve(step, dt, params))) / params["peak"] - 1.0
    assert 0.01 < overshoot < 0.15  # the spool valve's second order
    t = np.arange(int(120.0 / dt), dtype=np.float64) * dt
    vibration = compressor_bursts(t, params)
    assert 0.005 <= float(np.max(np.abs(vibration))) <= 0.03 and np.mean(vibration == 0.0) > 0.2  # mm, in bursts
    still = stroke_reading(np.full(u.size, 10.0), u, dt, params) - 10.0
    assert float(np.max(still)) <= 0.07  # mm: vibration and crosstalk stay a few noise units
    confounds = sim["off"] - BLIND6_CORES[plant](u, dt, params)
    assert 0.002 < rms(confounds) < 0.05
    assert 1e-5 < truth["jitter_s"] < 1.2e-4


def test_pilot_dead_time_is_longest_for_slow_changes() -> None:
    dt, peak, q = 0.004, 4.0, {"pilot_dead_s": 0.08}
    slow, fast = (triangles(peak, dt, period, 2) for period in (40.0, 2.0))
    mid_slow, mid_fast = (
        lag[lag.size // 8 : lag.size // 4] for lag in (pilot_lag_s(x, dt, q, peak) for x in (slow, fast))
    )
    assert np.all(mid_slow > 1.8 * 0.08) and np.all(mid_fast < 1.5 * 0.08) and np.all(mid_fast >= 0.08)
    assert np.max(pilot_lag_s(slow, dt, {"pilot_dead_s": 1.0}, peak)) <= 0.3  # s: never slower than a pilot valve


@pytest.mark.parametrize("plant", BLIND6_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND6_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28, i40, i58 = (int(s / dt) for s in (10.0, 28.0, 40.0, 58.0))
    assert abs(base[i28] - base[i10]) < 0.01 * span and abs(base[i58] - base[i40]) < 0.01 * span  # it settles
    still = np.zeros_like(u)
    off = render(BLIND6_CORES[plant], params, u, dt, "none", {}, still, still + STILL_TEMP_C)
    for form in BLIND6_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        change = render(BLIND6_CORES[plant], params, u, dt, form, q, still, still + STILL_TEMP_C) - off
        assert abs(change[i28] - change[i10]) > 0.003 * span, form  # still moving 8-26 s after the step up
        if form == "hold_slip_log":  # the crossings slip on in the direction of the last move
            assert change[i28] - change[i10] > 0.0 and change[i58] - change[i40] < -0.002 * span


def test_one_way_damper_lags_only_the_falling_branch() -> None:
    dt, peak = 0.005, 4.0
    u = triangles(peak, dt, 4.0, 3)
    params = draw_params("rayleigh_lambert", np.random.default_rng(7), peak)
    still = np.zeros_like(u)
    core, q = BLIND6_CORES["rayleigh_lambert"], {"damper_tau_s": 0.1}
    diff = render(core, params, u, dt, "one_way_damper", q, still, still + STILL_TEMP_C)
    diff -= render(core, params, u, dt, "none", q, still, still + STILL_TEMP_C)
    phase = (np.arange(u.size) * dt / 4.0) % 1.0
    rising, falling = (phase > 0.1) & (phase < 0.45), (phase > 0.6) & (phase < 0.95)
    assert np.max(np.abs(diff[rising])) < 1e-9 and np.min(diff[falling]) > 0.0 and np.max(diff[falling]) > 0.3


def test_ptfe_liner_acts_through_the_loop_width() -> None:
    """Warming through the liner's transition widens the core's loop (descending minus
    ascending), not the whole curve."""
    dt, peak = 0.01, 4.0
    u = triangles(peak, dt, 20.0, 4)
    q = {"transition_gain": 1.0, "width_19_k": 3.0, "width_30_k": 3.0, "liner_tau_s": 5.0}
    per = int(20.0 / dt)
    for plant in BLIND6_PLANTS:
        params = draw_params(plant, np.random.default_rng(8), peak)
        cold, warm = np.full_like(u, 14.0), np.where(np.arange(u.size) * dt < 30.0, 14.0, 26.0)
        widths = []
        for temp in (cold, warm):
            y = render(BLIND6_CORES[plant], params, u, dt, "ptfe_transition", q, np.zeros_like(u), temp)
            last, half = y[-per:], per // 2
            widths.append(float(np.mean(last[half:][::-1][per // 8 : -per // 8] - last[:half][per // 8 : -per // 8])))
        assert widths[1] > 1.2 * widths[0] > 0.0, (plant, widths)


@pytest.mark.parametrize("protocol", list(BLIND6_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 66.0, 4.0
    for seed in range(3):
        u = with_choked_sweep(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3960 and np.all(np.isfinite(u)) and np.all(u[:19] == 0.0)
        early = int(0.15 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
        body = u[early:]
        assert np.ptp(body) > 0.5 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
