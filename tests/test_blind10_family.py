"""Properties of the twelfth (blind10) held-out plant family; the diagnosis is never run here.

Short records (30 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds, noise seed offset; every protocol-rate pair;
each form meets several protocols and rates), determinism by seed, finite records on their
sensors' grids (stroke step, input step, the load converter's count held between conversions,
the NTC's whole counts) with monotone time, every effect visible (>= 5x noise) yet modest (<= 12 %
of span) and sizes spread over the band, columns that move in every record and do nothing unless
they are the effect (and do something when they are), the rig's confounds in effect-free
records, the memory known early, delays that lag, any duration building, and the protocols'
vented start and shakedown. Each form's and core's own physics: :mod:`tests.test_blind10_forms`.
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
from bench.plants.blind10_effects import BLIND10_FORMS, LOAD_PATTERNS, TEMPERATURE_PATTERNS, render
from bench.plants.blind10_family import (
    BLIND10_PLANTS,
    BLIND10_RATES_HZ,
    LOAD_STEP_KG,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    SEED_OFFSET,
    blind10_cases,
    blind10_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind10_protocols import BLIND10_PROTOCOLS, with_exhaust_shakedown
from bench.plants.blind10_rig import (
    hart_bursts,
    held,
    muscle_pressure,
    ntc_counts,
    stroke_reading,
    triboelectric,
    waveguide_error,
)
from bench.plants.families import FAMILIES
from bench.plants.filters import lowpass
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
)
from bench.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 30.0
CASES = blind10_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def _older_seeds() -> set[int]:
    seeds = {c.seed for c in family.tuning_cases(1.0)}
    seeds |= {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + blind3_family.blind3_cases(1.0)}
    seeds |= {c.seed for c in blind4_family.blind4_cases(1.0) + blind5_family.blind5_cases(1.0)}
    seeds |= {c.seed for c in blind6_family.blind6_cases(1.0) + blind7_family.blind7_cases(1.0)}
    return seeds | {c.seed for c in blind8_family.blind8_cases(1.0) + blind9_family.blind9_cases(1.0)}


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    older_plants |= {*blind4_family.BLIND4_PLANTS, *blind5_family.BLIND5_PLANTS, *blind6_family.BLIND6_PLANTS}
    older_plants |= {*blind7_family.BLIND7_PLANTS, *blind8_family.BLIND8_PLANTS, *blind9_family.BLIND9_PLANTS}
    assert len(BLIND10_PLANTS) == 4 and not set(BLIND10_PLANTS) & older_plants
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
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND10_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND10_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND10_PLANTS:
        for effect, forms in BLIND10_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    assert Counter(c.effect == "none" for c in CASES) == {False: 40, True: 20}
    assert not {c.seed for c in CASES} & _older_seeds()
    older_offsets = {blind2_family.SENSORS.seed_offset, blind3_family.SENSORS.seed_offset}
    older_offsets |= {blind4_family.SENSORS.seed_offset, blind5_family.SEED_OFFSET, blind6_family.SEED_OFFSET}
    older_offsets |= {blind7_family.SEED_OFFSET, blind8_family.SEED_OFFSET, blind9_family.SEED_OFFSET}
    assert SEED_OFFSET not in older_offsets | {10_000, 50_000}
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    older_protocols |= {*blind4_protocols.BLIND4_PROTOCOLS, *blind5_protocols.BLIND5_PROTOCOLS}
    older_protocols |= {*blind6_protocols.BLIND6_PROTOCOLS, *blind7_protocols.BLIND7_PROTOCOLS}
    older_protocols |= {*blind8_protocols.BLIND8_PROTOCOLS, *blind9_protocols.BLIND9_PROTOCOLS}
    assert {c.protocol for c in CASES} == set(BLIND10_PROTOCOLS) and len(BLIND10_PROTOCOLS) == 5
    assert not set(BLIND10_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ, *blind4_family.BLIND4_RATES_HZ}
    older_rates |= {*blind5_family.BLIND5_RATES_HZ, *blind6_family.BLIND6_RATES_HZ, *blind7_family.BLIND7_RATES_HZ}
    older_rates |= {*blind8_family.BLIND8_RATES_HZ, *blind9_family.BLIND9_RATES_HZ}
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND10_RATES_HZ) and len(rates) == 6
    assert all(40.0 <= r <= 600.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND10_PROTOCOLS) * len(rates)
    for forms in BLIND10_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects, blind4_effects, blind5_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    for later in (blind6_effects, blind7_effects, blind8_effects, blind9_effects):
        older_columns |= {*later.LOAD_PATTERNS, *later.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND10_PLANTS)
    patterns = Counter(
        (_simulated(c)["truth"]["load_pattern"], _simulated(c)["truth"]["temperature_pattern"]) for c in CASES
    )
    assert {lp for lp, _ in patterns} == set(LOAD_PATTERNS) and {tp for _, tp in patterns} == set(TEMPERATURE_PATTERNS)


def test_family_is_registered() -> None:
    cases_for, record = FAMILIES["blind10"]
    assert cases_for is blind10_cases and record is blind10_measurement


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
    assert np.allclose(m.extras["load"] / LOAD_STEP_KG, np.round(m.extras["load"] / LOAD_STEP_KG), atol=1e-6)
    counts = ntc_counts(m.extras["temperature"], params)
    assert np.allclose(counts, np.round(counts), atol=1e-3)  # whole counts of the 10-bit divider
    assert np.allclose(m.y / QUANT_MM[case.plant], np.round(m.y / QUANT_MM[case.plant]), atol=1e-6)
    step = params["input_step_bar"]
    assert np.allclose(m.u / step, np.round(m.u / step), atol=1e-6) and np.min(m.u) >= -0.05
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


@pytest.mark.parametrize("plant", BLIND10_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The HART bursts and the transmitter's held updates in the recorded input, the waveguide's
    error and the cable's triboelectric noise on the stroke, the load converter's stairs and the
    NTC's uneven step are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    params, dt, u = truth["plant_parameters"], 1.0 / case.rate_hz, sim["command"]
    pressure = held(muscle_pressure(u, dt, params), dt, params["tx_update_s"], params["tx_phase"])
    bursts = sim["u"] - lowpass(pressure, dt, dt / (2.0 * np.pi * params["aa_share"]))
    assert np.allclose(bursts, hart_bursts(u.size, dt, params))
    assert 0.0 < rms(bursts) < 0.005 * params["peak"] and np.mean(bursts == 0.0) > 0.5  # bursts, then quiet
    assert np.std(m.u - sim["u"]) < 0.01  # bar: the converter's noise and step
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], dt, params))
    static = waveguide_error(sim["base"], params)
    assert np.max(np.abs(static)) <= params["wave_amp_mm"] + abs(params["bow_mm"]) * 1.5 + 1e-9
    tribo = triboelectric(sim["base"], dt, params)
    speed = np.abs(np.gradient(sim["base"], dt))
    fast, still = speed > np.percentile(speed, 80), speed < np.percentile(speed, 20)
    assert rms(tribo[fast]) > 3.0 * rms(tribo[still]) and rms(tribo) < truth["noise"]  # grows with the speed
    assert rms(sim["off"] - sim["base"]) < 2.0 * truth["noise"]  # a few noise units at most
    load = m.extras["load"]
    changes = np.count_nonzero(np.diff(load))
    assert changes <= DURATION_S * params["hx711_sps"] + 1  # stairs at the converter's rate
    temp_steps = np.unique(np.round(np.abs(np.diff(m.extras["temperature"])), 6))
    temp_steps = temp_steps[temp_steps > 0.0]
    assert temp_steps.size >= 2 and np.ptp(temp_steps[temp_steps < 0.2]) > 0.0  # the step is not uniform


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
    assert_deterministic_by_seed(CASES, blind10_measurement)


@pytest.mark.parametrize("duration_s", [20.0, pytest.param(200.0, marks=pytest.mark.slow)])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind10_cases, blind10_measurement, duration_s)


@pytest.mark.parametrize("protocol", list(BLIND10_PROTOCOLS))
def test_protocols_start_vented_shake_down_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 52.0, 4.0
    for seed in range(3):
        u = with_exhaust_shakedown(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3120 and np.all(np.isfinite(u)) and np.all(u[: int(0.3 / dt)] == 0.0)
        early = int(0.12 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(5.5 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 3  # three sawtooth fills
        falls = np.diff(lead) < -0.1 * peak  # a quick exhaust drops a tenth of the range or more per sample
        assert np.count_nonzero(np.diff(falls.astype(np.int64)) > 0) >= 3  # three of them
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
