"""Properties of the blind held-out plant family (never the diagnosis's numbers; it is not run here).

What every family promises (coverage, novelty, determinism, visibility, columns, memory, delays,
durations, creep, rate growth, core loops) is checked once over every family by
:mod:`tests.test_plant_contract`; here only this family's own: core draws a closed monotone loop
with descending above ascending; protocols start vented stay in range and excite; full length
cases keep their effects visible and modest; preisach memory matches a brute force plane of
crisp relays; chamber air heats on filling and leaves a thermal tail.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import engine
from bench.plants.blind_cores import BLIND_CORES, Hooks
from bench.plants.blind_family import (
    SPEC,
    draw_blind_params,
)
from bench.plants.blind_protocols import BLIND_PROTOCOLS, vented_start
from bench.plants.case import Case
from bench.plants.visibility import EFFECT_MAX_OVER_SPAN, EFFECT_MIN_OVER_NOISE

DURATION_S = 40.0
CASES = engine.cases(SPEC, DURATION_S)


@cache
def _simulated(case: Case) -> dict[str, Any]:
    return engine.simulate(SPEC, case)


@pytest.mark.parametrize("core", list(BLIND_CORES))
def test_core_draws_a_closed_monotone_loop_with_descending_above_ascending(core: str) -> None:
    for seed in range(2):
        rng = np.random.default_rng(seed)
        peak = float(rng.uniform(3.0, 6.0))
        params = draw_blind_params(core, rng, peak)
        dt, period = 0.01, 30.0
        t = np.arange(int(round(4 * period / dt))) * dt
        u = peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / period) % 1.0) - 1.0)))
        y = BLIND_CORES[core](u, dt, params, Hooks.neutral(u.size))
        per, span = int(round(period / dt)), float(np.ptp(y))
        assert 10.0 <= span <= 50.0
        assert np.max(np.abs(y[-per:] - y[-2 * per : -per])) < 0.01 * span
        rising = np.diff(u[per:]) > 0
        assert np.min(np.diff(y[per:])[rising]) > -0.005 * span and np.max(np.diff(y[per:])[~rising]) < 0.005 * span
        grid = np.linspace(0.35, 0.65, 7) * peak
        cu, cy, half = u[-per:], y[-per:], per // 2
        up = np.interp(grid, cu[:half], cy[:half])
        down = np.interp(grid, cu[half:][::-1], cy[half:][::-1])
        assert np.all(down - up > 0.02 * span)


@pytest.mark.parametrize("protocol", list(BLIND_PROTOCOLS))
def test_protocols_start_vented_stay_in_range_and_excite(protocol: str) -> None:
    dt, peak = 1.0 / 60.0, 4.0
    u = vented_start(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 3600 and np.all(np.isfinite(u)) and np.all(u[:120] == 0.0)
    assert u.min() >= 0.0 and u.max() <= peak and np.ptp(u[210:]) > 0.4 * peak


@pytest.mark.slow
def test_full_length_cases_keep_their_effects_visible_and_modest() -> None:
    """The lead's records (150 s, the default): every effect in its band, every column moving."""
    for case in engine.cases(
        SPEC,
    ):
        truth = engine.simulate(SPEC, case)["truth"]
        assert 10.0 <= truth["span"] <= 50.0, case.name
        if case.effect == "none":
            assert truth["effect_size"] == 0.0
        else:
            low, high = EFFECT_MIN_OVER_NOISE * truth["noise"], EFFECT_MAX_OVER_SPAN * truth["span"]
            assert low <= truth["effect_size"] <= high, case.name


def test_preisach_memory_matches_a_brute_force_plane_of_crisp_relays() -> None:
    """The Everett/wiping-out shortcut equals switching every relay of the same grid one by one."""
    from bench.plants.blind_cores import _everett_tables, preisach_share

    rng = np.random.default_rng(3)
    params = draw_blind_params("preisach_resonant", rng, 4.0)
    table = _everett_tables(params)[4]  # the nominal spread
    n = table.shape[0]
    padded = np.zeros((n + 1, n + 1))
    padded[1:, :n] = table  # padded[i + 1, j] = E(alpha_i, beta_j); zero outside the grid
    weights = padded[1:, :n] - padded[:-1, :n] - padded[1:, 1:] + padded[:-1, 1:]  # relay (alpha_i, beta_j)
    levels = np.clip(np.cumsum(rng.integers(-12, 13, 400)), 0, n - 1)
    v = levels / (n - 1.0)
    state = np.zeros((n, n), dtype=bool)
    brute = np.empty(v.size)
    for k, level in enumerate(levels.tolist()):
        state[: level + 1, :] |= np.tri(n, n, -1, dtype=bool)[: level + 1, :]  # alpha_i <= v: on
        state[:, level:] = False  # beta_j >= v: off
        brute[k] = float(np.sum(weights[state]))
    shortcut = preisach_share(v, np.ones(v.size), params)
    assert np.max(np.abs(shortcut - brute)) < 1e-9
    assert np.ptp(shortcut) > 0.3  # the walk really opened and wiped out loops


def test_chamber_air_heats_on_filling_and_leaves_a_thermal_tail() -> None:
    from bench.plants.blind_cores import chamber_pressure

    rng = np.random.default_rng(4)
    params = draw_blind_params("valve_chamber", rng, 4.0)
    dt = 0.01
    t = np.arange(int(20.0 / dt)) * dt
    u = np.where((t > 1.0) & (t < 12.0), 4.0, 0.0)
    hot = chamber_pressure(u, dt, params)
    isothermal = chamber_pressure(u, dt, {**params, "tau_th_s": 0.05})
    at = {s: int(round(s / dt)) for s in (1.1, 2.0, 11.9, 12.1, 14.0)}
    assert hot[at[1.1]] > isothermal[at[1.1]] + 0.2  # adiabatic filling: the pressure rises faster
    assert hot[at[11.9]] - hot[at[2.0]] > 0.003  # then sags as the air cools, the valve tops it up
    assert hot[at[12.1]] < isothermal[at[12.1]] - 0.1  # venting cools the air: the pressure falls faster
    assert hot[at[14.0]] > isothermal[at[14.0]] + 0.01  # and rewarming holds some back: a slow tail
