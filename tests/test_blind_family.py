"""Properties of the blind held-out plant family (never the diagnosis's numbers; it is not run here).

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols and rates), determinism by seed, finite output, effect-free records identical
to a separate effect-off render, every effect visible (>= 5x noise) yet modest (<= 12 % of span),
delays that really lag, columns present and moving, temperature that cycles rather than rises
with time; and each core for what a muscle does (closed, monotone, real loops).
"""

from __future__ import annotations

from collections import Counter
from functools import cache
from typing import Any

import numpy as np
import pytest

from bench.plants import effects, family, fresh_effects, fresh_family, fresh_protocols
from bench.plants.blind_cores import BLIND_CORES, Hooks
from bench.plants.blind_effects import BLIND_FORMS, render
from bench.plants.blind_family import (
    BLIND_PLANTS,
    NONE_PER_PLANT,
    blind_cases,
    blind_measurement,
    draw_blind_params,
    measurement_from,
    simulate,
)
from bench.plants.blind_protocols import BLIND_PROTOCOLS, vented_start
from bench.plants.visibility import EFFECT_MAX_OVER_SPAN, EFFECT_MIN_OVER_NOISE

DURATION_S = 40.0
CASES = blind_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def test_cases_cover_every_new_form_on_every_new_core_with_new_protocols_and_rates() -> None:
    older_plants = set(family.TUNING_PLANTS + family.SECOND_TUNING_PLANTS + fresh_family.FRESH_PLANTS)
    assert len(BLIND_PLANTS) == 4 and not set(BLIND_PLANTS) & older_plants
    older_forms = {f for forms in (*effects.FORMS.values(), *fresh_effects.FRESH_FORMS.values()) for f in forms}
    assert BLIND_FORMS.keys() == fresh_effects.FRESH_FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND_PLANTS:
        for effect, forms in BLIND_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == len(CASES)
    assert {c.protocol for c in CASES} == set(BLIND_PROTOCOLS) and not set(BLIND_PROTOCOLS) & set(
        fresh_protocols.FRESH_PROTOCOLS
    )
    rates = {c.rate_hz for c in CASES}
    assert (
        all(50.0 <= r <= 500.0 for r in rates)
        and len(rates - set(family.RATES_HZ) - set(fresh_family.FRESH_RATES_HZ)) >= 3
    )
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND_PROTOCOLS) * len(rates)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_case_is_finite_visible_modest_and_has_moving_columns(case: family.Case) -> None:
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    n = int(round(DURATION_S * case.rate_hz))
    assert len(m) == m.u.size == m.y.size == n and np.all(np.isfinite(m.y)) and np.all(np.isfinite(m.u))
    assert np.allclose(np.diff(m.t), 1.0 / case.rate_hz) and m.source == case.name
    assert (truth["effect"], truth["form"]) == (case.effect, case.form)
    assert set(m.extras) == {"load", "temperature"}
    assert np.ptp(m.extras["load"]) >= 0.5 and np.ptp(m.extras["temperature"]) >= 1.0
    assert np.array_equal(m.extras["load"], np.round(m.extras["load"], 3))
    assert np.array_equal(m.extras["temperature"], np.round(m.extras["temperature"], 1))
    assert 5.0 <= truth["span"] <= 50.0 and np.min(sim["off"]) > -0.5  # mm (40 s may not reach the top); rest length
    assert np.all(m.u[: int(round(2.0 * case.rate_hz))] == 0.0) and 0.0 <= m.u.min() and m.u.max() <= 6.0
    assert np.std(m.y - sim["on"]) == pytest.approx(truth["noise"], rel=0.1)
    size = float(np.sqrt(np.mean((sim["on"] - sim["off"]) ** 2)))
    assert size == pytest.approx(truth["effect_size"])
    if case.effect == "none":
        core, params = BLIND_CORES[case.plant], truth["plant_parameters"]
        # the columns are decoys: the record is the same with them held still
        still_load, still_temperature = np.full_like(sim["load"], 2.0), np.full_like(sim["temperature"], 22.0)
        again = render(core, params, sim["u"], 1.0 / case.rate_hz, "none", {}, still_load, still_temperature, None)
        assert size == 0.0 and np.array_equal(again, sim["on"])
        return
    assert EFFECT_MIN_OVER_NOISE * truth["noise"] <= size <= EFFECT_MAX_OVER_SPAN * truth["span"]
    assert 0.25 <= truth["intensity_rescale"] <= 4.0
    if case.effect == "load_dependence":
        assert np.mean(sim["on"] - sim["off"]) < 0.0  # a payload never helps the muscle contract
    if case.effect == "temperature_drift":
        temp = sim["temperature"]
        assert np.max(np.maximum.accumulate(temp) - temp) > 1.0 and np.ptp(temp) > 2.0  # it cools too


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.5 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


def test_measurement_is_deterministic_by_seed() -> None:
    for case in CASES[::11]:
        a, ta = blind_measurement(case)
        b, tb = blind_measurement(case)
        assert np.array_equal(a.y, b.y) and np.array_equal(a.u, b.u) and ta == tb
        assert np.array_equal(a.extras["temperature"], b.extras["temperature"])
    other = family.Case(**{**CASES[0].__dict__, "seed": CASES[0].seed + 1})
    assert not np.array_equal(blind_measurement(CASES[0])[0].y, blind_measurement(other)[0].y)


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
    for case in blind_cases():
        truth = simulate(case)["truth"]
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
