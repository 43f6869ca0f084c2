"""Properties of the fresh held-out plant family (never the diagnosis's numbers).

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: core is a closed monotone
hysteresis loop; rate independent cores draw the same loop at two slow speeds; mckibben balance
holds and has a dead zone under load; protocols start vented and stay in range; viscous
hysteresis state matters fast and fades slow; full length cases keep their effects visible and
modest.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import engine
from bench.plants.case import Case
from bench.plants.fresh_cores import (
    FRESH_CORES,
    RATE_INDEPENDENT,
    Hooks,
    draw_fresh_params,
    mckibben_contraction,
)
from bench.plants.fresh_family import (
    SPEC,
)
from bench.plants.fresh_protocols import FRESH_PROTOCOLS, vented_full_cycle

DURATION_S = 30.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


def _triangles(peak: float, period_s: float, cycles: int, dt_s: float) -> np.ndarray:
    t = np.arange(int(round(cycles * period_s / dt_s))) * dt_s
    return peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / period_s) % 1.0) - 1.0)))


def _branches(u: np.ndarray, y: np.ndarray, grid: np.ndarray, per_cycle: int) -> tuple[np.ndarray, np.ndarray]:
    """The last cycle's ascending and descending branch sampled on ``grid``."""
    cu, cy = u[-per_cycle:], y[-per_cycle:]
    half = per_cycle // 2
    return np.interp(grid, cu[:half], cy[:half]), np.interp(grid, cu[half:][::-1], cy[half:][::-1])


@pytest.mark.parametrize("core", list(FRESH_CORES))
def test_core_is_a_closed_monotone_hysteresis_loop(core: str) -> None:
    for seed in range(3):
        rng = np.random.default_rng(seed)
        peak = float(rng.uniform(2.5, 6.0))
        params = draw_fresh_params(core, rng, peak)
        dt, period = 0.02, 16.0
        u = _triangles(peak, period, 4, dt)
        y = FRESH_CORES[core](u, dt, params, Hooks.neutral(u.size))
        span = float(np.ptp(y))
        per = int(round(period / dt))
        assert 10.0 <= span <= 50.0
        assert np.max(np.abs(y[-per:] - y[-2 * per : -per])) < 0.01 * span  # the loop closes
        rising = np.diff(u[per:]) > 0  # after the first cycle (the start-up settles in it)
        assert np.min(np.diff(y[per:])[rising]) > -0.005 * span  # ascending branches rise (dynamics: a hair)
        assert np.max(np.diff(y[per:])[~rising]) < 0.005 * span
        up, down = _branches(u, y, np.linspace(0.3, 0.7, 9) * peak, per)
        assert np.all(down - up > 0.02 * span)  # a real loop, descending above ascending


@pytest.mark.parametrize("core", RATE_INDEPENDENT)
def test_rate_independent_cores_draw_the_same_loop_at_two_slow_speeds(core: str) -> None:
    rng = np.random.default_rng(5)
    peak = 4.0
    params = draw_fresh_params(core, rng, peak)
    grid = np.linspace(0.2, 0.8, 13) * peak
    loops = []
    for period, dt in ((12.0, 0.01), (40.0, 0.02)):
        u = _triangles(peak, period, 3, dt)
        y = FRESH_CORES[core](u, dt, params, Hooks.neutral(u.size))
        loops.append(np.concatenate(_branches(u, y, grid, int(round(period / dt)))))
    assert np.max(np.abs(loops[0] - loops[1])) < 0.01 * np.ptp(loops[0])


def test_mckibben_balance_holds_and_has_a_dead_zone_under_load() -> None:
    p = np.linspace(0.0, 1.0, 101)
    x = mckibben_contraction(p, 0.1, 0.7)
    assert np.all(x[p <= 0.1] == 0.0) and np.all(np.diff(x[p > 0.1]) > 0)
    live = p > 0.1
    assert np.allclose(p[live] * (1 - x[live]) ** 2, 0.1 + 0.7 * x[live])
    assert np.all(mckibben_contraction(p, 0.2, 0.7)[live] <= x[live])


@pytest.mark.parametrize("protocol", list(FRESH_PROTOCOLS))
def test_protocols_start_vented_and_stay_in_range(protocol: str) -> None:
    dt, peak = 1.0 / 80.0, 4.0
    u = vented_full_cycle(protocol, 60.0, dt, peak, np.random.default_rng(1))
    assert u.size == int(round(60.0 / dt)) and np.all(np.isfinite(u))
    assert np.all(u[: int(2.0 / dt)] == 0.0) and u[: int(12.0 / dt)].max() == pytest.approx(peak, rel=0.01)
    assert u.min() >= 0.0 and u.max() <= peak
    assert np.ptp(u[int(13.0 / dt) :]) > 0.3 * peak  # the protocol itself excites the loop


@pytest.mark.parametrize("core", list(FRESH_CORES))
def test_viscous_hysteresis_state_matters_fast_and_fades_slow(core: str) -> None:
    rng = np.random.default_rng(11)
    params = draw_fresh_params(core, rng, 4.0)
    gaps = []
    for period, dt, cycles in ((2.0, 0.004, 3), (24.0, 0.02, 2)):
        u = _triangles(4.0, period, cycles, dt)
        plain = FRESH_CORES[core](u, dt, params, Hooks.neutral(u.size))
        n = u.size
        viscous = FRESH_CORES[core](u, dt, params, Hooks(np.ones(n), np.zeros(n), np.ones(n), relax_s=0.2))
        per = int(round(period / dt))
        gaps.append(float(np.sqrt(np.mean((viscous[-per:] - plain[-per:]) ** 2))))
    assert gaps[0] > 2.0 * gaps[1] and gaps[0] > 0.2  # rate dependence: mm at 0.5 Hz, shrinking when slow


@pytest.mark.slow
def test_full_length_cases_keep_their_effects_visible_and_modest() -> None:
    """The lead's records (150 s, the default): every effect still in its band, every column moving."""
    for case in engine.cases(
        SPEC,
    ):
        sim = engine.simulate(SPEC, case)
        truth = sim["truth"]
        assert 10.0 <= truth["span"] <= 50.0, case.name
        assert np.ptp(sim["load"]) >= 1.0 and np.ptp(sim["temperature"]) >= 0.5, case.name
        if case.effect == "none":
            assert truth["effect_size"] == 0.0
        else:
            assert 4.0 * truth["noise"] <= truth["effect_size"] <= 0.15 * truth["span"], case.name
