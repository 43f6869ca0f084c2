"""Properties of the seventh (blind5) held-out plant family; the diagnosis is never run here.

Short records (60 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds; every protocol-rate pair; each form meets
several protocols and rates), determinism by seed, finite quantised records with monotone time,
every effect visible (>= 5x noise) yet modest (<= 12 % of span) and sizes spread over the band,
columns that move in every record and do nothing unless they are the effect (and do something
when they are), the rig's confounds in effect-free records (dropped frames repeated on every channel), the
memory known early, delays that lag (the exhaust pilot only on deflation), creep that keeps
moving in a hold, rate forms that grow with speed, the slack take-up moving only the descending
branch, and each core's loop (closed, 3-20 % wide, descending above ascending).
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
from bench.plants.blind5_cores import BLIND5_CORES, draw_params
from bench.plants.blind5_effects import (
    BLIND5_FORMS,
    LOAD_PATTERNS,
    TEMPERATURE_PATTERNS,
    draw_effect_params,
    render,
)
from bench.plants.blind5_family import (
    BLIND5_PLANTS,
    BLIND5_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    SEED_OFFSET,
    blind5_cases,
    blind5_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind5_protocols import BLIND5_PROTOCOLS, with_valve_sweep
from bench.plants.blind5_rig import dropped_frames, regulator, stroke_reading, transducer_reading
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_closed_loop_3_to_20_percent_wide,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
    slow_and_fast_triangles,
    step_and_hold,
)
from bench.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 60.0
CASES = blind5_cases(DURATION_S)
OLDER_FAMILIES = (family, fresh_family, blind_family, blind2_family, blind3_family, blind4_family)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    older_plants |= set(blind4_family.BLIND4_PLANTS)
    assert len(BLIND5_PLANTS) == 4 and not set(BLIND5_PLANTS) & older_plants
    tables = (
        effects.FORMS,
        fresh_effects.FRESH_FORMS,
        blind_effects.BLIND_FORMS,
        blind2_effects.BLIND2_FORMS,
        blind3_effects.BLIND3_FORMS,
        blind4_effects.BLIND4_FORMS,
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND5_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND5_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND5_PLANTS:
        for effect, forms in BLIND5_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    assert Counter(c.effect == "none" for c in CASES) == {False: 40, True: 20}
    older_seeds = {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    older_seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + family.tuning_cases(1.0)}
    older_seeds |= {c.seed for c in blind3_family.blind3_cases(1.0) + blind4_family.blind4_cases(1.0)}
    assert not {c.seed for c in CASES} & older_seeds
    older_offsets = {blind2_family.SENSORS.seed_offset, blind3_family.SENSORS.seed_offset}
    assert SEED_OFFSET not in older_offsets | {blind4_family.SENSORS.seed_offset}
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    older_protocols |= set(blind4_protocols.BLIND4_PROTOCOLS)
    assert {c.protocol for c in CASES} == set(BLIND5_PROTOCOLS) and len(BLIND5_PROTOCOLS) == 5
    assert not set(BLIND5_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ, *blind4_family.BLIND4_RATES_HZ}
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND5_RATES_HZ) and all(50.0 <= r <= 500.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND5_PROTOCOLS) * len(rates)
    for forms in BLIND5_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects, blind4_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND5_PLANTS)


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
    held = np.flatnonzero(np.diff(m.y) == 0.0) + 1
    fresh = np.setdiff1d(np.arange(n), held)
    assert np.std((m.y - sim["on"])[fresh]) == pytest.approx(truth["noise"], rel=0.2)
    assert_effect_size_as_recorded(case.effect, sim, truth)
    if case.effect != "none":
        assert 1.0 / 3.0 - 1e-9 <= truth["parameters"]["calibration"] <= 3.0 + 1e-9


def test_effect_sizes_spread_over_the_band() -> None:
    """Not all at the bottom: the sizes over span reach from ~1 % to several %."""
    shares = np.array([_simulated(c)["truth"]["effect_size_over_span"] for c in CASES if c.effect != "none"])
    assert np.min(shares) < 0.015 and np.max(shares) > 0.045 and 0.015 <= np.median(shares) <= 0.05


@pytest.mark.parametrize(
    "case", [c for c in CASES if c.effect in ("none", "load_dependence", "temperature_drift")], ids=lambda c: c.name
)
def test_columns_act_only_in_their_own_effects_records(case: family.Case) -> None:
    sim = _simulated(case)
    truth = sim["truth"]
    core, params, q = BLIND5_CORES[case.plant], truth["plant_parameters"], truth["parameters"]
    dt = 1.0 / case.rate_hz
    u = sim["command"]
    assert np.allclose(transducer_reading(u, params), sim["u"])  # the command the recorded input came from
    still_load = np.full_like(sim["load"], float(np.median(sim["load"])))
    still_temp = np.full_like(sim["temperature"], float(sim["temperature"][0]))
    for load, temp, which in ((still_load, sim["temperature"], "load"), (sim["load"], still_temp, "temperature")):
        again = render(core, params, u, dt, case.form, dict(q), load, temp)
        change = rms(again - sim["on"])
        if case.effect in (f"{which}_dependence", f"{which}_drift"):
            assert change > EFFECT_MIN_OVER_NOISE * truth["noise"] / 2.0, (which, change)
        else:
            assert change == 0.0, (which, change)


@pytest.mark.parametrize("plant", BLIND5_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """Regulator lag and play, the transducer's gain error, the mount's settling, aliased hum
    and dropped frames are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    params, dt = truth["plant_parameters"], 1.0 / case.rate_hz
    u = sim["command"]
    gain = sim["u"][u > 0.5 * params["peak"]] / u[u > 0.5 * params["peak"]]
    assert 0.003 <= float(np.max(np.abs(gain - 1.0))) <= 0.03  # the transducer's gain error and offset
    pressure = regulator(u, dt, params)
    loop = pressure - u
    assert 0.003 * params["peak"] <= float(np.max(np.abs(loop[u == u[-1]]))) or np.ptp(loop) > 0.004 * params["peak"]
    still = stroke_reading(np.full(int(60.0 / dt), 10.0), dt, params) - 10.0
    assert 0.01 <= float(np.max(-still)) <= 0.06  # mm: the mount settles, no more than a few noise units
    hum = still - np.convolve(still, np.ones(9) / 9.0, mode="same")
    assert 0.002 <= float(np.std(hum[20:-20])) <= 0.012  # mm: mains hum
    assert truth["dropped_frames"] >= 1 and truth["dropped_frames"] <= 0.01 * len(m)
    assert 0.005 < rms(sim["off"] - BLIND5_CORES[plant](u, dt, params)) < 0.1  # mm: settling and hum


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.15 * sim["u"].size)
    u, off = sim["u"], sim["off"]
    assert u[0] == 0.0 and abs(off[0]) < 0.3
    assert np.max(u[:early]) >= 0.97 * np.max(u) and np.min(u[int(3.0 * case.rate_hz) : early]) <= 0.02 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


def test_exhaust_pilot_delays_only_deflation() -> None:
    dt, peak = 0.005, 4.0
    t = np.arange(int(round(20.0 / dt))) * dt
    u = peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / 10.0) % 1.0) - 1.0)))
    params = draw_params("vector_fibre_play", np.random.default_rng(3), peak)
    q = {"pilot_s": 0.2}
    still = np.zeros_like(u)
    diff = render(BLIND5_CORES["vector_fibre_play"], params, u, dt, "exhaust_pilot", q, still, still + 21.0)
    diff -= render(BLIND5_CORES["vector_fibre_play"], params, u, dt, "none", q, still, still + 21.0)
    phase = (t / 10.0) % 1.0
    late_rise, falling = (phase > 0.3) & (phase < 0.5), (phase > 0.55) & (phase < 0.95)
    assert np.max(diff[falling]) > 0.05 and np.max(np.abs(diff[late_rise])) < 0.1 * np.max(diff[falling])


@pytest.mark.parametrize("plant", BLIND5_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND5_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28 = int(10.0 / dt), int(28.0 / dt)
    assert abs(base[i28] - base[i10]) < 0.01 * span  # the effect-free core settles
    still = np.zeros_like(u)
    off = render(BLIND5_CORES[plant], params, u, dt, "none", {}, still, still + 22.0)
    for form in BLIND5_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        change = render(BLIND5_CORES[plant], params, u, dt, form, q, still, still + 22.0) - off
        assert abs(change[i28] - change[i10]) > 0.003 * span, form  # still moving 8-26 s after the step


@pytest.mark.parametrize("plant", BLIND5_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND5_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            temps, loads = np.full_like(u, 22.0), np.zeros_like(u)
            off = render(BLIND5_CORES[plant], params, u, dt, "none", q, loads, temps)
            on = render(BLIND5_CORES[plant], params, u, dt, form, q, loads, temps)
            sizes.append(rms(on - off))
        assert sizes[1] > 2.0 * sizes[0], (form, sizes)


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind5_measurement)


@pytest.mark.parametrize("duration_s", [40.0, 300.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind5_cases, blind5_measurement, duration_s)


@pytest.mark.parametrize("core", list(BLIND5_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND5_CORES[core], partial(draw_params, core))


@pytest.mark.parametrize("protocol", list(BLIND5_PROTOCOLS))
def test_protocols_start_vented_sweep_the_range_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 84.0, 4.0
    u = with_valve_sweep(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 5040 and np.all(np.isfinite(u)) and np.all(u[:33] == 0.0)
    early = int(0.15 * u.size)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.97 * peak
    body = u[early:]
    assert np.ptp(body) > 0.5 * peak
    crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
    assert crossings >= 2  # the range is covered again, not once


def test_dropped_frames_repeat_the_frame_before_on_every_channel() -> None:
    case = next(c for c in CASES if c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    drops = dropped_frames(
        len(m), np.random.default_rng(case.seed + SEED_OFFSET + 1), truth["plant_parameters"]["drop_share"]
    )
    assert drops.size == truth["dropped_frames"] >= 1
    for column in (m.y, m.u, m.extras["load"], m.extras["temperature"]):
        assert np.array_equal(column[drops], column[drops - 1])
    assert np.array_equal(m.t, sim["t"])  # the time stamps stay uniform


def test_slack_takeup_moves_only_the_descending_branch() -> None:
    dt, peak = 0.005, 4.0
    t = np.arange(int(round(40.0 / dt))) * dt
    u = peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / 10.0) % 1.0) - 1.0)))
    params = draw_params("rolling_lobe_peel", np.random.default_rng(4), peak)
    q = draw_effect_params("load_dependence", "slack_takeup", np.random.default_rng(4))
    load, temps = np.where(t < 10.0, 0.5, 3.0), np.full_like(u, 21.0)
    core = BLIND5_CORES["rolling_lobe_peel"]
    diff = render(core, params, u, dt, "slack_takeup", q, load, temps)
    diff -= render(core, params, u, dt, "slack_takeup", q, np.full_like(load, 0.5), temps)
    phase = (t / 10.0) % 1.0
    late = t > 12.0
    rising, falling = late & (phase > 0.25) & (phase < 0.45), late & (phase > 0.75) & (phase < 0.95)
    assert np.max(np.abs(diff[rising])) < 1e-9 and np.min(diff[falling]) < -0.1  # mm: heavier, lower way down
