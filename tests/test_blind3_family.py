"""Properties of the fifth (blind3) held-out plant family; the diagnosis is never run here.

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds; every protocol-rate pair; each form meets
several protocols and rates), determinism by seed, finite quantised records, every effect
visible (>= 5x noise) yet modest (<= 12 % of span), columns that move in every record and do
nothing unless they are the effect (and do something when they are), the sensor confounds in
effect-free records, the memory known early (full range in the first 15 %), delays that lag,
creep that keeps moving in a hold, rate forms that grow with speed, and each core's loop
(closed, 3-20 % wide, descending above ascending).
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
from bench.plants.blind3_cores import BLIND3_CORES, draw_params, position_sensor
from bench.plants.blind3_effects import (
    BLIND3_FORMS,
    LOAD_PATTERNS,
    TEMPERATURE_PATTERNS,
    draw_effect_params,
    render,
)
from bench.plants.blind3_family import (
    BLIND3_PLANTS,
    BLIND3_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    blind3_cases,
    blind3_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind3_protocols import BLIND3_PROTOCOLS, with_full_sweep
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
CASES = blind3_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS}
    assert len(BLIND3_PLANTS) == 4 and not set(BLIND3_PLANTS) & older_plants
    tables = (effects.FORMS, fresh_effects.FRESH_FORMS, blind_effects.BLIND_FORMS, blind2_effects.BLIND2_FORMS)
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND3_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND3_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND3_PLANTS:
        for effect, forms in BLIND3_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    older_seeds = {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    older_seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + family.tuning_cases(1.0)}
    assert not {c.seed for c in CASES} & older_seeds
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= set(blind2_protocols.BLIND2_PROTOCOLS)
    assert {c.protocol for c in CASES} == set(BLIND3_PROTOCOLS) and len(BLIND3_PROTOCOLS) >= 5
    assert not set(BLIND3_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= set(blind2_family.BLIND2_RATES_HZ)
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND3_RATES_HZ) and all(50.0 <= r <= 500.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND3_PROTOCOLS) * len(rates)
    for forms in BLIND3_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns = {*fresh_effects.LOAD_PATTERNS, *fresh_effects.TEMPERATURE_PATTERNS, *blind_effects.LOAD_PATTERNS}
    older_columns |= {
        *blind_effects.TEMPERATURE_PATTERNS,
        *blind2_effects.LOAD_PATTERNS,
        *blind2_effects.TEMPERATURE_PATTERNS,
    }
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns


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
    assert 8.0 <= truth["span"] <= 60.0 and np.min(sim["off"]) > -1.0  # mm; the rest length
    assert np.std(m.y - sim["on"]) == pytest.approx(truth["noise"], rel=0.15)
    assert_effect_size_as_recorded(case.effect, sim, truth)


@pytest.mark.parametrize(
    "case", [c for c in CASES if c.effect in ("none", "load_dependence", "temperature_drift")], ids=lambda c: c.name
)
def test_columns_act_only_in_their_own_effects_records(case: family.Case) -> None:
    sim = _simulated(case)
    truth = sim["truth"]
    core, params, q = BLIND3_CORES[case.plant], truth["plant_parameters"], truth["parameters"]
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


@pytest.mark.parametrize("plant", BLIND3_PLANTS)
def test_effect_free_records_carry_the_sensor_confounds(plant: str) -> None:
    """The transducer's nonlinearity and mains hum are in every record, effect-free ones too."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    params, dt = sim["truth"]["plant_parameters"], 1.0 / case.rate_hz
    core_out = BLIND3_CORES[plant](sim["u"], dt, params)
    confound = sim["off"] - core_out
    assert 0.03 <= rms(confound) <= 0.5  # mm: bow and ripple of the nonlinearity, plus hum
    held = position_sensor(np.full(4000, 10.0), dt, params) - 10.0  # a still stroke: only the hum moves
    assert 0.005 <= float(np.std(held)) <= 0.03


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.15 * sim["u"].size)
    u, off = sim["u"], sim["off"]
    assert u[0] == 0.0 and abs(off[0]) < 0.1
    assert np.max(u[:early]) >= 0.97 * np.max(u) and np.min(u[int(2.0 * case.rate_hz) : early]) <= 0.02 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


@pytest.mark.parametrize("plant", BLIND3_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND3_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28 = int(10.0 / dt), int(28.0 / dt)
    assert abs(base[i28] - base[i10]) < 0.01 * span  # the effect-free rig settles (tails < 4 s)
    still = np.zeros_like(u)
    for form in BLIND3_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        on = render(BLIND3_CORES[plant], params, u, dt, form, q, still, still + 22.0, base)
        assert on[i10] - on[i28] > 0.003 * span, form  # still lengthening 8-26 s after the step


@pytest.mark.parametrize("plant", BLIND3_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND3_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            base = BLIND3_CORES[plant](u, dt, params)
            temps, loads = np.full_like(u, 22.0), np.zeros_like(u)
            off = render(BLIND3_CORES[plant], params, u, dt, "none", q, loads, temps, base)
            on = render(BLIND3_CORES[plant], params, u, dt, form, q, loads, temps, base)
            sizes.append(rms(on - off))
        assert sizes[1] > 3.0 * sizes[0], (form, sizes)


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind3_measurement)


@pytest.mark.parametrize("duration_s", [40.0, 300.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind3_cases, blind3_measurement, duration_s)


@pytest.mark.parametrize("core", list(BLIND3_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND3_CORES[core], partial(draw_params, core))


@pytest.mark.parametrize("protocol", list(BLIND3_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 64.0, 4.0
    u = with_full_sweep(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 3840 and np.all(np.isfinite(u)) and np.all(u[:38] == 0.0)
    early = int(0.15 * u.size)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
    body = u[early:]
    assert np.ptp(body) > 0.5 * peak
    crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
    assert crossings >= 4  # the range is covered again and again, not once
