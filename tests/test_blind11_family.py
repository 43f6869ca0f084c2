"""Properties of the thirteenth (blind11) held-out plant family; the diagnosis is never run here.

Short records (30 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds, noise seed offset; every protocol-rate pair;
each form meets several protocols and rates), determinism by seed, finite records on their
sensors' grids (stroke step, input step, the load converter's count, the thermocouple's 0.25 K
held for 100 ms) with monotone time, every effect visible (>= 5x noise) yet modest (<= 12 % of
span) and sizes spread over the band, columns that move in every record and do nothing unless
they are the effect (and do something when they are), the rig's confounds in effect-free
records, the memory known early, delays that lag, any duration building, and the protocols'
vented start and conditioning. Each form's and core's own physics: :mod:`tests.test_blind11_forms`.
"""

from __future__ import annotations

from collections import Counter
from functools import cache
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
    blind6_effects,
    blind6_family,
    blind6_protocols,
    blind7_effects,
    blind7_family,
    blind7_protocols,
    blind8_effects,
    blind8_family,
    blind8_protocols,
    blind9_effects,
    blind9_family,
    blind9_protocols,
    blind10_effects,
    blind10_family,
    blind10_protocols,
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
from bench.plants.blind11_effects import BLIND11_FORMS, LOAD_PATTERNS, TEMPERATURE_PATTERNS, render
from bench.plants.blind11_family import (
    BLIND11_PLANTS,
    BLIND11_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    SEED_OFFSET,
    blind11_cases,
    blind11_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind11_protocols import BLIND11_PROTOCOLS, with_ringdown_conditioning
from bench.plants.blind11_rig import (
    TC_CONVERSION_S,
    TC_STEP_K,
    load_reading,
    muscle_pressure,
    regulator_pressure,
    second_order,
    stroke_reading,
    triangulation_error,
)
from bench.plants.families import FAMILIES
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
)
from bench.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 30.0
CASES = blind11_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def _older_seeds() -> set[int]:
    seeds = {c.seed for c in family.tuning_cases(1.0)}
    seeds |= {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + blind3_family.blind3_cases(1.0)}
    seeds |= {c.seed for c in blind4_family.blind4_cases(1.0) + blind5_family.blind5_cases(1.0)}
    seeds |= {c.seed for c in blind6_family.blind6_cases(1.0) + blind7_family.blind7_cases(1.0)}
    seeds |= {c.seed for c in blind8_family.blind8_cases(1.0) + blind9_family.blind9_cases(1.0)}
    return seeds | {c.seed for c in blind10_family.blind10_cases(1.0)}


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    older_plants |= {*blind4_family.BLIND4_PLANTS, *blind5_family.BLIND5_PLANTS, *blind6_family.BLIND6_PLANTS}
    older_plants |= {*blind7_family.BLIND7_PLANTS, *blind8_family.BLIND8_PLANTS, *blind9_family.BLIND9_PLANTS}
    older_plants |= set(blind10_family.BLIND10_PLANTS)
    assert len(BLIND11_PLANTS) == 4 and not set(BLIND11_PLANTS) & older_plants
    tables = (
        effects.FORMS,
        fresh_effects.FRESH_FORMS,
        blind_effects.BLIND_FORMS,
        blind2_effects.BLIND2_FORMS,
        blind3_effects.BLIND3_FORMS,
        blind4_effects.BLIND4_FORMS,
        blind5_effects.BLIND5_FORMS,
        blind6_effects.BLIND6_FORMS,
        blind7_effects.BLIND7_FORMS,
        blind8_effects.BLIND8_FORMS,
        blind9_effects.BLIND9_FORMS,
        blind10_effects.BLIND10_FORMS,
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND11_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND11_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND11_PLANTS:
        for effect, forms in BLIND11_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    assert Counter(c.effect == "none" for c in CASES) == {False: 40, True: 20}
    assert not {c.seed for c in CASES} & _older_seeds()
    older_offsets = {blind2_family.SENSORS.seed_offset, blind3_family.SENSORS.seed_offset}
    older_offsets |= {blind4_family.SENSORS.seed_offset, blind5_family.SEED_OFFSET, blind6_family.SEED_OFFSET}
    older_offsets |= {blind7_family.SEED_OFFSET, blind8_family.SEED_OFFSET, blind9_family.SEED_OFFSET}
    older_offsets |= {blind10_family.SEED_OFFSET}
    assert SEED_OFFSET not in older_offsets | {10_000, 50_000}
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    older_protocols |= {*blind4_protocols.BLIND4_PROTOCOLS, *blind5_protocols.BLIND5_PROTOCOLS}
    older_protocols |= {*blind6_protocols.BLIND6_PROTOCOLS, *blind7_protocols.BLIND7_PROTOCOLS}
    older_protocols |= {*blind8_protocols.BLIND8_PROTOCOLS, *blind9_protocols.BLIND9_PROTOCOLS}
    older_protocols |= set(blind10_protocols.BLIND10_PROTOCOLS)
    assert {c.protocol for c in CASES} == set(BLIND11_PROTOCOLS) and len(BLIND11_PROTOCOLS) == 5
    assert not set(BLIND11_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ, *blind4_family.BLIND4_RATES_HZ}
    older_rates |= {*blind5_family.BLIND5_RATES_HZ, *blind6_family.BLIND6_RATES_HZ, *blind7_family.BLIND7_RATES_HZ}
    older_rates |= {*blind8_family.BLIND8_RATES_HZ, *blind9_family.BLIND9_RATES_HZ, *blind10_family.BLIND10_RATES_HZ}
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND11_RATES_HZ) and len(rates) == 6
    assert all(40.0 <= r <= 600.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND11_PROTOCOLS) * len(rates)
    for forms in BLIND11_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects, blind4_effects, blind5_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    for later in (blind6_effects, blind7_effects, blind8_effects, blind9_effects, blind10_effects):
        older_columns |= {*later.LOAD_PATTERNS, *later.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND11_PLANTS)
    patterns = Counter(
        (_simulated(c)["truth"]["load_pattern"], _simulated(c)["truth"]["temperature_pattern"]) for c in CASES
    )
    assert {lp for lp, _ in patterns} == set(LOAD_PATTERNS) and {tp for _, tp in patterns} == set(TEMPERATURE_PATTERNS)


def test_family_is_registered() -> None:
    cases_for, record = FAMILIES["blind11"]
    assert cases_for is blind11_cases and record is blind11_measurement


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_case_is_finite_on_its_sensors_grids_visible_modest_with_moving_columns(case: family.Case) -> None:
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    params = truth["plant_parameters"]
    n = int(round(DURATION_S * case.rate_hz))
    assert len(m) == m.u.size == m.y.size == n and np.all(np.isfinite(m.y)) and np.all(np.isfinite(m.u))
    assert np.all(np.diff(m.t) > 0.0) and np.allclose(np.diff(m.t), 1.0 / case.rate_hz) and m.source == case.name
    assert (truth["effect"], truth["form"]) == (case.effect, case.form)
    assert set(m.extras) == {"load", "temperature"}
    assert all(np.all(np.isfinite(column)) for column in m.extras.values())
    assert np.ptp(m.extras["load"]) >= 0.3 and np.ptp(m.extras["temperature"]) >= 0.5  # kg, K: they move
    step = params["load_step_kg"]
    assert np.allclose(m.extras["load"] / step, np.round(m.extras["load"] / step), atol=1e-6)
    temp = m.extras["temperature"]
    assert np.allclose(temp / TC_STEP_K, np.round(temp / TC_STEP_K), atol=1e-9)  # the converter's 0.25 K
    assert np.count_nonzero(np.diff(temp)) <= DURATION_S / TC_CONVERSION_S + 1  # one value per conversion
    assert np.allclose(m.y / QUANT_MM[case.plant], np.round(m.y / QUANT_MM[case.plant]), atol=1e-6)
    in_step = params["input_step_bar"]
    assert np.allclose(m.u / in_step, np.round(m.u / in_step), atol=1e-6) and np.min(m.u) >= -0.05
    assert 8.0 <= truth["span"] <= 60.0 and np.ptp(m.y) > 0.5 * truth["span"]
    residual = m.y - sim["on"]  # noise and reading step
    assert np.std(residual) == pytest.approx(truth["noise"], rel=0.2)
    assert_effect_size_as_recorded(case.effect, sim, truth)
    if case.effect != "none":
        assert 1.0 / 3.0 - 1e-9 <= truth["parameters"]["calibration"] <= 3.0 + 1e-9


def test_effect_sizes_spread_over_the_band() -> None:
    """Not all at the bottom: the sizes over span reach from ~1 % to several %."""
    shares = np.array([_simulated(c)["truth"]["effect_size_over_span"] for c in CASES if c.effect != "none"])
    assert np.min(shares) < 0.015 and np.max(shares) > 0.05 and 0.015 <= np.median(shares) <= 0.06


@pytest.mark.parametrize(
    "case", [c for c in CASES if c.effect in ("none", "load_dependence", "temperature_drift")], ids=lambda c: c.name
)
def test_columns_act_only_in_their_own_effects_records(case: family.Case) -> None:
    sim = _simulated(case)
    truth = sim["truth"]
    params, q = truth["plant_parameters"], truth["parameters"]
    dt = 1.0 / case.rate_hz
    u = sim["command"]
    still_load = np.full_like(sim["load"], float(sim["load"][0]))
    still_temp = np.full_like(sim["temperature"], float(sim["temperature"][0]))
    for load, temp, which in ((still_load, sim["temperature"], "load"), (sim["load"], still_temp, "temperature")):
        again = render(case.plant, params, u, dt, case.form, dict(q), load, temp, sim["base"])
        change = rms(again - sim["on"])
        if case.effect in (f"{which}_dependence", f"{which}_drift"):  # held, it is the effect-free record
            assert change == pytest.approx(truth["effect_size"]) and change >= EFFECT_MIN_OVER_NOISE * truth["noise"]
        else:
            assert change == 0.0, (which, change)


@pytest.mark.parametrize("plant", BLIND11_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The regulator's dead band, the line's ringing and the bridge's warm-up drift in the recorded
    input, the triangulation and speckle errors and the averaging on the stroke, the hum and the
    12-bit count on the load, the thermocouple's held conversions: in every record, none an effect
    of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    params, dt, u = truth["plant_parameters"], 1.0 / case.rate_hz, sim["command"]
    t = np.arange(u.size) * dt
    outlet = regulator_pressure(u, dt, params)
    band = params["deadband_bar"]
    assert np.all(outlet <= np.maximum.accumulate(u) + 1e-12) and np.max(np.abs(outlet - u)) > band
    inside = np.abs(u[1:] - outlet[:-1]) <= band  # the set pressure within the band: no port opens
    assert np.all(outlet[1:][inside] == outlet[:-1][inside]) and np.count_nonzero(inside) > 0.05 * u.size
    ringing = second_order(outlet, dt, params["line_ring_hz"], params["line_ring_zeta"]) - outlet
    drift = sim["u"] - outlet - params["ring_share"] * ringing
    assert np.allclose(drift, params["warm_bar"] * (1.0 - np.exp(-t / params["warm_tau_s"])), atol=1e-12)
    assert 0.0 < rms(params["ring_share"] * ringing) < 0.01 * params["peak"]
    muscle = muscle_pressure(u, dt, params)
    assert rms(sim["u"] - muscle) > 0.0 and np.std(m.u - sim["u"]) < 0.01  # leads the muscle; converter noise
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], dt, params))
    static = triangulation_error(sim["base"], params)
    assert np.max(np.abs(static)) <= abs(params["lin_mm"]) + 4.0 * params["speckle_mm"]
    assert rms(static) > 0.002
    load_err = load_reading(np.full(u.size, 3.0), dt, params, np.random.default_rng(0)) - 3.0
    assert 0.5 * params["hum_kg"] / np.sqrt(2.0) < rms(load_err) < 3.0 * (params["hum_kg"] + params["load_step_kg"])
    temp = m.extras["temperature"]
    changes = np.flatnonzero(np.diff(temp))
    assert changes.size >= 2 and np.min(np.diff(changes)) * dt >= TC_CONVERSION_S - 1.5 * dt


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.22 * sim["u"].size)
    u, off = sim["command"], sim["off"]
    assert u[0] == 0.0 and abs(sim["u"][0]) < 0.02 and abs(off[0]) < 0.3
    assert np.max(u[:early]) >= 0.96 * np.max(u) and np.min(u[int(2.5 * case.rate_hz) : early]) <= 0.02 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(blind11_cases(8.0), blind11_measurement)  # short: the seeds are the same


@pytest.mark.parametrize("duration_s", [20.0, pytest.param(200.0, marks=pytest.mark.slow)])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind11_cases, blind11_measurement, duration_s)


@pytest.mark.parametrize("protocol", list(BLIND11_PROTOCOLS))
def test_protocols_start_vented_condition_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 58.0, 4.0
    for seed in range(3):
        u = with_ringdown_conditioning(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3480 and np.all(np.isfinite(u)) and np.all(u[: int(0.3 / dt)] == 0.0)
        early = int(0.12 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(4.8 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 2  # two fills
        assert np.count_nonzero(lead[int(1.0 / dt) :] == 0.0) >= 2  # vented between them
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
