"""Properties of the eleventh (blind9) held-out plant family; the diagnosis is never run here.

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds, noise seed offset; every protocol-rate pair;
each form meets several protocols and rates), determinism by seed, finite quantised records
with monotone time, every effect visible (>= 5x noise) yet modest (<= 12 % of span) and sizes
spread over the band, columns that move in every record and do nothing unless they are the
effect (and do something when they are), the rig's confounds in effect-free records, the memory
known early, delays that lag, any duration building, and the protocols' vented start and
shakedown. Each form's and core's own physics: :mod:`tests.test_blind9_forms`.
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
from bench.plants.blind9_effects import BLIND9_FORMS, LOAD_PATTERNS, TEMPERATURE_PATTERNS, render
from bench.plants.blind9_family import (
    BLIND9_PLANTS,
    BLIND9_RATES_HZ,
    LOAD_READ_KG,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    SEED_OFFSET,
    blind9_cases,
    blind9_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind9_protocols import BLIND9_PROTOCOLS, with_shakedown
from bench.plants.blind9_rig import (
    load_cell_zero_shift,
    muscle_pressure,
    rail_dip,
    rc_filter,
    slew_limited,
    stroke_reading,
    wire_wound,
)
from bench.plants.families import FAMILIES
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
)
from bench.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 40.0
CASES = blind9_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def _older_seeds() -> set[int]:
    seeds = {c.seed for c in family.tuning_cases(1.0)}
    seeds |= {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + blind3_family.blind3_cases(1.0)}
    seeds |= {c.seed for c in blind4_family.blind4_cases(1.0) + blind5_family.blind5_cases(1.0)}
    seeds |= {c.seed for c in blind6_family.blind6_cases(1.0) + blind7_family.blind7_cases(1.0)}
    return seeds | {c.seed for c in blind8_family.blind8_cases(1.0)}


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    older_plants |= {*blind4_family.BLIND4_PLANTS, *blind5_family.BLIND5_PLANTS, *blind6_family.BLIND6_PLANTS}
    older_plants |= {*blind7_family.BLIND7_PLANTS, *blind8_family.BLIND8_PLANTS}
    assert len(BLIND9_PLANTS) == 4 and not set(BLIND9_PLANTS) & older_plants
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
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND9_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND9_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND9_PLANTS:
        for effect, forms in BLIND9_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    assert Counter(c.effect == "none" for c in CASES) == {False: 40, True: 20}
    assert not {c.seed for c in CASES} & _older_seeds()
    older_offsets = {blind2_family.SENSORS.seed_offset, blind3_family.SENSORS.seed_offset}
    older_offsets |= {blind4_family.SENSORS.seed_offset, blind5_family.SEED_OFFSET, blind6_family.SEED_OFFSET}
    older_offsets |= {blind7_family.SEED_OFFSET, blind8_family.SEED_OFFSET}
    assert SEED_OFFSET not in older_offsets | {10_000, 50_000}
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    older_protocols |= {*blind4_protocols.BLIND4_PROTOCOLS, *blind5_protocols.BLIND5_PROTOCOLS}
    older_protocols |= {*blind6_protocols.BLIND6_PROTOCOLS, *blind7_protocols.BLIND7_PROTOCOLS}
    older_protocols |= set(blind8_protocols.BLIND8_PROTOCOLS)
    assert {c.protocol for c in CASES} == set(BLIND9_PROTOCOLS) and len(BLIND9_PROTOCOLS) == 5
    assert not set(BLIND9_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ, *blind4_family.BLIND4_RATES_HZ}
    older_rates |= {*blind5_family.BLIND5_RATES_HZ, *blind6_family.BLIND6_RATES_HZ, *blind7_family.BLIND7_RATES_HZ}
    older_rates |= set(blind8_family.BLIND8_RATES_HZ)
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND9_RATES_HZ) and all(40.0 <= r <= 600.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND9_PROTOCOLS) * len(rates)
    for forms in BLIND9_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects, blind4_effects, blind5_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    for later in (blind6_effects, blind7_effects, blind8_effects):
        older_columns |= {*later.LOAD_PATTERNS, *later.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND9_PLANTS)
    patterns = Counter(
        (_simulated(c)["truth"]["load_pattern"], _simulated(c)["truth"]["temperature_pattern"]) for c in CASES
    )
    assert {lp for lp, _ in patterns} == set(LOAD_PATTERNS) and {tp for _, tp in patterns} == set(TEMPERATURE_PATTERNS)


def test_family_is_registered() -> None:
    cases_for, record = FAMILIES["blind9"]
    assert cases_for is blind9_cases and record is blind9_measurement


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
    assert np.allclose(m.extras["load"] / LOAD_READ_KG, np.round(m.extras["load"] / LOAD_READ_KG), atol=1e-6)
    assert np.allclose(m.extras["temperature"] * 16.0, np.round(m.extras["temperature"] * 16.0), atol=1e-6)
    assert np.allclose(m.y / QUANT_MM[case.plant], np.round(m.y / QUANT_MM[case.plant]), atol=1e-6)
    step = truth["plant_parameters"]["input_step_bar"]
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
    assert np.min(shares) < 0.015 and np.max(shares) > 0.06 and 0.015 <= np.median(shares) <= 0.06


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


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The manifold's carrier ripple and the amplifier's slew limit in the recorded input, the
    pot's turn steps and the rail's dip on the stroke, the RC filters, and the load cell's thermal
    zero shift are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    params, dt, u = truth["plant_parameters"], 1.0 / case.rate_hz, sim["command"]
    pressure = muscle_pressure(u, dt, params)
    smooth = rc_filter(
        slew_limited(pressure, dt, params["amp_slew_per_s"] * params["peak"]), dt, params["aa_share"] / dt
    )
    ripple = sim["u"] - smooth
    assert 0.0 < rms(ripple) < 0.01 * params["peak"]
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], u, dt, params))
    steps = wire_wound(sim["base"], params) - sim["base"]
    pitch = params["pot_pitch_mm"]
    assert np.max(np.abs(steps)) <= (0.5 + params["pot_irregularity"]) * pitch + 1e-9 and np.std(steps) > 0.1 * pitch
    dip = rail_dip(u, dt, params)
    assert np.all(dip >= 0.0) and 0.0 < np.max(dip) <= params["rail_dip"] * (1.0 + 1e-9)
    assert np.corrcoef(dip, u)[0, 1] > 0.5  # the dip follows the input: a decoy
    corner = params["aa_share"] * (1.0 + params["aa_mismatch"]) / dt
    assert rms(sim["off"] - rc_filter(sim["base"], dt, corner)) < 3.0 * truth["noise"]  # a few noise units at most
    assert np.std(m.u - sim["u"]) < 0.01  # bar: the converter's noise and step
    shift = load_cell_zero_shift(sim["temperature"], params)
    assert np.std(m.extras["load"] - sim["load"] - shift) < 0.01 and np.any(shift != 0.0)


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.2 * sim["u"].size)
    u, off = sim["command"], sim["off"]
    assert u[0] == 0.0 and abs(sim["u"][0]) < 1e-9 and abs(off[0]) < 0.3
    assert np.max(u[:early]) >= 0.96 * np.max(u) and np.min(u[int(1.5 * case.rate_hz) : early]) <= 0.02 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind9_measurement)


@pytest.mark.parametrize("duration_s", [30.0, 200.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind9_cases, blind9_measurement, duration_s)


@pytest.mark.parametrize("protocol", list(BLIND9_PROTOCOLS))
def test_protocols_start_vented_shake_down_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 56.0, 4.0
    for seed in range(3):
        u = with_shakedown(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 3360 and np.all(np.isfinite(u)) and np.all(u[: int(0.4 / dt)] == 0.0)
        early = int(0.15 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(6.5 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 4  # four shakedown pulses
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
