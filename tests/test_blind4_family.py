"""Properties of the sixth (blind4) held-out plant family; the diagnosis is never run here.

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds; every protocol-rate pair; each form meets
several protocols and rates), determinism by seed, finite quantised records, every effect
visible (>= 5x noise) yet modest (<= 12 % of span), columns that move in every record and do
nothing unless they are the effect (and do something when they are), the rig's confounds in
effect-free records, the memory known early (full range in the first 15 %), delays that lag,
creep that keeps moving in a hold, rate forms that grow with speed, return-point memory where
the model has it, and each core's loop (closed, 3-20 % wide, descending above ascending).
"""

from __future__ import annotations

from collections import Counter
from functools import cache, partial
from typing import Any

import numpy as np
import pytest

from bench.plants import (
    blind2_effects,
    blind2_family,
    blind2_protocols,
    blind3_effects,
    blind3_family,
    blind3_protocols,
    blind_effects,
    blind_family,
    blind_protocols,
    effects,
    family,
    fresh_effects,
    fresh_family,
    fresh_protocols,
    protocols,
)
from bench.plants.blind4_cores import BLIND4_CORES, draw_params, masing, stoner_crimps
from bench.plants.blind4_effects import (
    BLIND4_FORMS,
    LOAD_PATTERNS,
    TEMPERATURE_PATTERNS,
    draw_effect_params,
    render,
)
from bench.plants.blind4_family import (
    BLIND4_PLANTS,
    BLIND4_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    blind4_cases,
    blind4_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind4_protocols import BLIND4_PROTOCOLS, with_s_sweep
from bench.plants.blind4_rig import RANGE_MM, rig_reading, supply_droop
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_closed_loop_3_to_20_percent_wide,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
    slow_and_fast_triangles,
    step_and_hold,
)
from bench.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 40.0
CASES = blind4_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    assert len(BLIND4_PLANTS) == 4 and not set(BLIND4_PLANTS) & older_plants
    tables = (
        effects.FORMS,
        fresh_effects.FRESH_FORMS,
        blind_effects.BLIND_FORMS,
        blind2_effects.BLIND2_FORMS,
        blind3_effects.BLIND3_FORMS,
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND4_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND4_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND4_PLANTS:
        for effect, forms in BLIND4_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    older_seeds = {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    older_seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + family.tuning_cases(1.0)}
    older_seeds |= {c.seed for c in blind3_family.blind3_cases(1.0)}
    assert not {c.seed for c in CASES} & older_seeds
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    assert {c.protocol for c in CASES} == set(BLIND4_PROTOCOLS) and len(BLIND4_PROTOCOLS) >= 5
    assert not set(BLIND4_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ}
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND4_RATES_HZ) and all(50.0 <= r <= 500.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND4_PROTOCOLS) * len(rates)
    for forms in BLIND4_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND4_PLANTS)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_case_is_finite_quantised_visible_modest_with_moving_columns(case: family.Case) -> None:
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    n = int(round(DURATION_S * case.rate_hz))
    assert len(m) == m.u.size == m.y.size == n and np.all(np.isfinite(m.y)) and np.all(np.isfinite(m.u))
    assert np.allclose(np.diff(m.t), 1.0 / case.rate_hz) and m.source == case.name
    assert (truth["effect"], truth["form"]) == (case.effect, case.form)
    assert set(m.extras) == {"load", "temperature"}
    assert np.ptp(m.extras["load"]) >= 0.5 and np.ptp(m.extras["temperature"]) >= 1.0
    assert np.allclose(m.y / QUANT_MM, np.round(m.y / QUANT_MM), atol=1e-6)
    assert 8.0 <= truth["span"] <= 60.0 and np.min(sim["off"]) >= RANGE_MM[0]  # mm; the transducer's range
    assert np.std(m.y - sim["on"]) == pytest.approx(truth["noise"], rel=0.15)
    assert_effect_size_as_recorded(case.effect, sim, truth)


@pytest.mark.parametrize(
    "case", [c for c in CASES if c.effect in ("none", "load_dependence", "temperature_drift")], ids=lambda c: c.name
)
def test_columns_act_only_in_their_own_effects_records(case: family.Case) -> None:
    sim = _simulated(case)
    truth = sim["truth"]
    core, params, q = BLIND4_CORES[case.plant], truth["plant_parameters"], truth["parameters"]
    dt = 1.0 / case.rate_hz
    still_load = np.full_like(sim["load"], float(np.median(sim["load"])))
    still_temp = np.full_like(sim["temperature"], float(sim["temperature"][0]))
    for load, temp, which in ((still_load, sim["temperature"], "load"), (sim["load"], still_temp, "temperature")):
        again = render(core, params, sim["u"], dt, case.form, dict(q), load, temp)
        change = rms(again - sim["on"])
        if case.effect in (f"{which}_dependence", f"{which}_drift"):
            assert change > EFFECT_MIN_OVER_NOISE * truth["noise"] / 2.0, (which, change)
        else:
            assert change == 0.0, (which, change)


@pytest.mark.parametrize("plant", BLIND4_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """Supply droop, guide play, mounting plate and the transducer's errors are in every record."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    params, dt = sim["truth"]["plant_parameters"], 1.0 / case.rate_hz
    core = BLIND4_CORES[plant]
    droop = supply_droop(sim["u"], dt, params)
    assert 0.003 <= float(np.max(1.0 - droop[sim["u"] > 0] / sim["u"][sim["u"] > 0])) <= 0.015
    confound = sim["off"] - core(sim["u"], dt, params)
    assert 0.05 <= rms(confound) <= 1.5  # mm: droop, play, plate and transducer together
    still = rig_reading(np.full(int(200.0 / dt), 10.0), dt, params) - 10.0  # a still stroke, 200 s
    spikes = np.abs(still - np.median(still)) > 0.25
    assert 1 <= np.count_nonzero(spikes) <= 30  # rare spikes
    calm = still[~spikes]
    assert 0.005 <= float(np.std(calm)) <= 0.3  # the offset wanders and the 1/f noise jitters
    slow, fast = np.std(np.diff(calm[:: int(5.0 / dt)])), np.std(np.diff(calm))
    assert slow > fast  # the wander is slow: more change over 5 s than from sample to sample


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.15 * sim["u"].size)
    u, off = sim["u"], sim["off"]
    assert u[0] == 0.0 and abs(off[0]) < 0.3
    assert np.max(u[:early]) >= 0.97 * np.max(u) and np.min(u[int(2.0 * case.rate_hz) : early]) <= 0.02 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


@pytest.mark.parametrize("plant", BLIND4_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND4_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28 = int(10.0 / dt), int(28.0 / dt)
    assert abs(base[i28] - base[i10]) < 0.01 * span  # the effect-free core settles
    still = np.zeros_like(u)
    off = render(BLIND4_CORES[plant], params, u, dt, "none", {}, still, still + 22.0)
    for form in BLIND4_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        change = render(BLIND4_CORES[plant], params, u, dt, form, q, still, still + 22.0) - off
        assert change[i10] - change[i28] > 0.003 * span, form  # still lengthening 8-26 s after the step


@pytest.mark.parametrize("plant", BLIND4_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND4_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            temps, loads = np.full_like(u, 22.0), np.zeros_like(u)
            off = render(BLIND4_CORES[plant], params, u, dt, "none", q, loads, temps)
            on = render(BLIND4_CORES[plant], params, u, dt, form, q, loads, temps)
            sizes.append(rms(on - off))
        assert sizes[1] > 3.0 * sizes[0], (form, sizes)


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind4_measurement)


@pytest.mark.parametrize("duration_s", [40.0, 300.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind4_cases, blind4_measurement, duration_s)


@pytest.mark.parametrize("core", list(BLIND4_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND4_CORES[core], partial(draw_params, core))


def _excursion(dt: float, peak: float) -> np.ndarray:
    """0 -> 0.8 -> 0.3 -> 0.6 -> 0.45 -> 0.6 -> 0.2 ``peak``: a minor loop inside a branch."""
    knots = np.array([0.0, 0.8, 0.3, 0.6, 0.45, 0.6, 0.2]) * peak
    return np.concatenate([np.linspace(a, b, int(round(8.0 / dt)))[1:] for a, b in zip(knots[:-1], knots[1:])])


def test_masing_and_stoner_cores_have_return_point_memory() -> None:
    """Leaving a branch for a minor loop and coming back to the reversal point returns to the
    same output, and the way down afterwards is the way down without the minor loop (wiping out)."""
    dt, peak = 0.005, 4.0
    p = _excursion(dt, peak)
    n = int(round(8.0 / dt)) - 1
    a, b = 3 * n - 1, 5 * n - 1  # the first and the second arrival at 0.6 peak
    h = masing(p, 0.2, 0.3)
    assert h[b] == pytest.approx(h[a], abs=1e-9)
    direct = masing(np.concatenate([p[: a + 1], p[b + 1 :]]), 0.2, 0.3)
    assert np.allclose(direct[a + 1 :], h[b + 1 :], atol=1e-9)
    params = draw_params("stoner_crimps", np.random.default_rng(8), peak)
    params["tau_valve_s"] = 1e-6  # the pressure is the command: no valve lag between the visits
    y = stoner_crimps(p, dt, params)
    assert y[b] == pytest.approx(y[a], abs=1e-6)
    direct_y = stoner_crimps(np.concatenate([p[: a + 1], p[b + 1 :]]), dt, params)
    assert np.allclose(direct_y[a + 1 :], y[b + 1 :], atol=1e-6)


@pytest.mark.parametrize("protocol", list(BLIND4_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 72.0, 4.0
    u = with_s_sweep(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 4320 and np.all(np.isfinite(u)) and np.all(u[:36] == 0.0)
    early = int(0.15 * u.size)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
    body = u[early:]
    assert np.ptp(body) > 0.5 * peak
    crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
    assert crossings >= 4  # the range is covered again and again, not once
