"""Properties of the eighth (blind6) held-out plant family; the diagnosis is never run here.

Short records (60 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds, noise seed offset; every protocol-rate pair;
each form meets several protocols and rates), determinism by seed, finite quantised records
with monotone time, every effect visible (>= 5x noise) yet modest (<= 12 % of span) and sizes
spread over the band, columns that move in every record and do nothing unless they are the
effect (and do something when they are), the rig's confounds in effect-free records, the memory
known early, delays that lag (the pilot's longer for slow changes), creep that keeps moving in a
hold, rate forms that grow with speed, the one-way damper lagging only the falling branch, the
liner's temperature acting through the loop's width, and each core's loop (closed, 3-20 % wide,
descending above ascending).
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
    blind4_effects,
    blind4_family,
    blind4_protocols,
    blind5_effects,
    blind5_family,
    blind5_protocols,
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
from bench.plants.blind6_cores import BLIND6_CORES, draw_params
from bench.plants.blind6_effects import (
    BLIND6_FORMS,
    LOAD_PATTERNS,
    TEMPERATURE_PATTERNS,
    draw_effect_params,
    pilot_lag_s,
    render,
)
from bench.plants.blind6_family import (
    BLIND6_PLANTS,
    BLIND6_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    SEED_OFFSET,
    blind6_cases,
    blind6_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind6_protocols import BLIND6_PROTOCOLS, with_choked_sweep
from bench.plants.blind6_rig import compressor_bursts, snubbed_reading, spool_valve, stroke_reading
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_closed_loop_3_to_20_percent_wide,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
    slow_and_fast_triangles,
    step_and_hold,
    triangles,
)
from bench.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 60.0
CASES = blind6_cases(DURATION_S)
STILL_TEMP_C = 22.0


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def _older_seeds() -> set[int]:
    seeds = {c.seed for c in family.tuning_cases(1.0)}
    seeds |= {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + blind3_family.blind3_cases(1.0)}
    return seeds | {c.seed for c in blind4_family.blind4_cases(1.0) + blind5_family.blind5_cases(1.0)}


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    older_plants |= {*blind4_family.BLIND4_PLANTS, *blind5_family.BLIND5_PLANTS}
    assert len(BLIND6_PLANTS) == 4 and not set(BLIND6_PLANTS) & older_plants
    tables = (
        effects.FORMS,
        fresh_effects.FRESH_FORMS,
        blind_effects.BLIND_FORMS,
        blind2_effects.BLIND2_FORMS,
        blind3_effects.BLIND3_FORMS,
        blind4_effects.BLIND4_FORMS,
        blind5_effects.BLIND5_FORMS,
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND6_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND6_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND6_PLANTS:
        for effect, forms in BLIND6_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    assert Counter(c.effect == "none" for c in CASES) == {False: 40, True: 20}
    assert not {c.seed for c in CASES} & _older_seeds()
    older_offsets = {blind2_family.SENSORS.seed_offset, blind3_family.SENSORS.seed_offset}
    older_offsets |= {blind4_family.SENSORS.seed_offset, blind5_family.SEED_OFFSET, 10_000, 50_000}
    assert SEED_OFFSET not in older_offsets
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    older_protocols |= {*blind4_protocols.BLIND4_PROTOCOLS, *blind5_protocols.BLIND5_PROTOCOLS}
    assert {c.protocol for c in CASES} == set(BLIND6_PROTOCOLS) and len(BLIND6_PROTOCOLS) == 5
    assert not set(BLIND6_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ, *blind4_family.BLIND4_RATES_HZ}
    older_rates |= set(blind5_family.BLIND5_RATES_HZ)
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND6_RATES_HZ) and all(50.0 <= r <= 500.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND6_PROTOCOLS) * len(rates)
    for forms in BLIND6_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects, blind4_effects, blind5_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND6_PLANTS)


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_case_is_finite_quantised_visible_modest_with_moving_columns(case: family.Case) -> None:
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    n = int(round(DURATION_S * case.rate_hz))
    assert len(m) == m.u.size == m.y.size == n and np.all(np.isfinite(m.y)) and np.all(np.isfinite(m.u))
    assert np.all(np.diff(m.t) > 0.0) and np.allclose(np.diff(m.t), 1.0 / case.rate_hz) and m.source == case.name
    assert (truth["effect"], truth["form"]) == (case.effect, case.form)
    assert set(m.extras) == {"load", "temperature"}
    assert all(np.all(np.isfinite(column)) for column in m.extras.values())
    assert np.ptp(m.extras["load"]) >= 0.3 and np.ptp(m.extras["temperature"]) >= 0.5  # kg, K: they move
    assert np.allclose(m.y / QUANT_MM[case.plant], np.round(m.y / QUANT_MM[case.plant]), atol=1e-6)
    assert 8.0 <= truth["span"] <= 60.0 and np.ptp(m.y) > 0.5 * truth["span"]
    residual = m.y - sim["on"]  # noise and reading step, and the sampling jitter in fast moves
    slow = np.abs(np.gradient(sim["on"], 1.0 / case.rate_hz)) < 5.0  # mm/s
    assert np.std(residual[slow]) == pytest.approx(truth["noise"], rel=0.2) and np.std(residual) < 3.0 * truth["noise"]
    assert_effect_size_as_recorded(case.effect, sim, truth)
    if case.effect != "none":
        assert 1.0 / 3.0 - 1e-9 <= truth["parameters"]["calibration"] <= 3.0 + 1e-9


def test_effect_sizes_spread_over_the_band() -> None:
    """Not all at the bottom: the sizes over span reach from ~1 % to several %."""
    shares = np.array([_simulated(c)["truth"]["effect_size_over_span"] for c in CASES if c.effect != "none"])
    assert np.min(shares) < 0.015 and np.max(shares) > 0.06 and 0.015 <= np.median(shares) <= 0.06


@pytest.mark.parametrize(
    "case", [c for c in CASES if c.effect in ("none", "load_dependence", "temperature_drift")], ids=lambda c: c.name
)
def test_columns_act_only_in_their_own_effects_records(case: family.Case) -> None:
    sim = _simulated(case)
    truth = sim["truth"]
    core, params, q = BLIND6_CORES[case.plant], truth["plant_parameters"], truth["parameters"]
    dt = 1.0 / case.rate_hz
    u = sim["command"]
    assert np.allclose(snubbed_reading(u, dt, params), sim["u"])  # the command the recorded input came from
    still_load = np.full_like(sim["load"], float(sim["load"][0]))
    still_temp = np.full_like(sim["temperature"], float(sim["temperature"][0]))
    for load, temp, which in ((still_load, sim["temperature"], "load"), (sim["load"], still_temp, "temperature")):
        again = render(core, params, u, dt, case.form, dict(q), load, temp)
        change = rms(again - sim["on"])
        if case.effect in (f"{which}_dependence", f"{which}_drift"):  # held, it is the effect-free record
            assert change == pytest.approx(truth["effect_size"]) and change >= EFFECT_MIN_OVER_NOISE * truth["noise"]
        else:
            assert change == 0.0, (which, change)


@pytest.mark.parametrize("plant", BLIND6_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The snubbed pressure port, the valve's overshoot, compressor vibration, crosstalk and
    sampling jitter are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
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


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.15 * sim["u"].size)
    u, off = sim["command"], sim["off"]
    assert u[0] == 0.0 and sim["u"][0] == 0.0 and abs(off[0]) < 0.3
    assert np.max(u[:early]) >= 0.97 * np.max(u) and np.min(u[int(3.5 * case.rate_hz) : early]) <= 0.02 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


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


@pytest.mark.parametrize("plant", BLIND6_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND6_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            temps, loads = np.full_like(u, STILL_TEMP_C), np.zeros_like(u)
            off = render(BLIND6_CORES[plant], params, u, dt, "none", q, loads, temps)
            on = render(BLIND6_CORES[plant], params, u, dt, form, q, loads, temps)
            sizes.append(rms(on - off))
        assert sizes[1] > 2.0 * sizes[0], (form, sizes)


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


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind6_measurement)


@pytest.mark.parametrize("duration_s", [40.0, 300.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind6_cases, blind6_measurement, duration_s)


@pytest.mark.parametrize("core", list(BLIND6_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND6_CORES[core], partial(draw_params, core))


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
