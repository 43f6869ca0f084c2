"""Properties of the tenth (blind8) held-out plant family; the diagnosis is never run here.

Short records (60 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, column patterns, seeds, noise seed offset; every protocol-rate pair;
each form meets several protocols and rates), determinism by seed, finite quantised records
with monotone time, every effect visible (>= 5x noise) yet modest (<= 12 % of span) and sizes
spread over the band, columns that move in every record and do nothing unless they are the
effect (and do something when they are), the rig's confounds in effect-free records, the memory
known early, delays that lag (the Bessel demodulator by its group delay, the UART in held frames
no faster than the line), creep that keeps moving in a hold (the cord recovering after a step
down, the crimp re-crimping slower than it straightened), rate forms that grow with speed (the
dashpot viscous when slow and capped by its air spring, the inerter ringing after a step), the
Belleville stack degressive and the Bowden sheath progressive, the cord's thermoelastic
inversion and the drum scaling the whole extension, each core's own physics (Ivshin-Pence
boundaries, the bounding surface, Mindlin's backbone, Fancher's envelopes) and each core's loop
(closed, 3-20 % wide, descending above ascending).
"""

from __future__ import annotations

from collections import Counter
from functools import cache, partial
from typing import Any

import numpy as np
import pytest

from tests.plants import (
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
from tests.plants.blind8_cores import (
    BLIND8_CORES,
    dafalias_popov_friction,
    draw_params,
    fancher_envelope_state,
    ivshin_pence_crystallinity,
    mindlin_friction,
)
from tests.plants.blind8_effects import (
    BLIND8_FORMS,
    LOAD_PATTERNS,
    TEMPERATURE_PATTERNS,
    air_dashpot_lag,
    belleville_deflection,
    bessel_demodulated,
    crimp_state,
    draw_effect_params,
    render,
    sheath_compression,
    uart_stream,
)
from tests.plants.blind8_family import (
    BLIND8_PLANTS,
    BLIND8_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    SEED_BASE,
    SEED_OFFSET,
    blind8_cases,
    blind8_measurement,
    measurement_from,
    simulate,
)
from tests.plants.blind8_protocols import BLIND8_PROTOCOLS, with_shakedown
from tests.plants.blind8_rig import (
    anti_alias,
    autozero_steps,
    muscle_pressure,
    port_flow_noise,
    sar_bit_error,
    stroke_reading,
)
from tests.plants.properties import (
    assert_any_duration_builds,
    assert_closed_loop_3_to_20_percent_wide,
    assert_deterministic_by_seed,
    assert_effect_size_as_recorded,
    slow_and_fast_triangles,
    step_and_hold,
)
from tests.plants.visibility import EFFECT_MIN_OVER_NOISE, rms

DURATION_S = 60.0
CASES = blind8_cases(DURATION_S)
STILL_TEMP_C = 22.0


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def _render(
    plant: str, params: dict[str, float], u: np.ndarray, dt: float, form: str, q: dict[str, float]
) -> np.ndarray:
    """``form`` on ``plant`` for the set pressure ``u`` with still columns."""
    base = BLIND8_CORES[plant](u, dt, params)
    return render(params, u, dt, form, q, np.full_like(u, 2.0), np.full_like(u, STILL_TEMP_C), base)


def _older_seeds() -> set[int]:
    seeds = {c.seed for c in family.tuning_cases(1.0)}
    seeds |= {c.seed for c in fresh_family.fresh_cases(1.0) + blind_family.blind_cases(1.0)}
    seeds |= {c.seed for c in blind2_family.blind2_cases(1.0) + blind3_family.blind3_cases(1.0)}
    seeds |= {c.seed for c in blind4_family.blind4_cases(1.0) + blind5_family.blind5_cases(1.0)}
    return seeds | {c.seed for c in blind6_family.blind6_cases(1.0) + blind7_family.blind7_cases(1.0)}


def test_cases_cover_new_cores_forms_protocols_rates_and_columns() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= {*blind_family.BLIND_PLANTS, *blind2_family.BLIND2_PLANTS, *blind3_family.BLIND3_PLANTS}
    older_plants |= {*blind4_family.BLIND4_PLANTS, *blind5_family.BLIND5_PLANTS, *blind6_family.BLIND6_PLANTS}
    older_plants |= set(blind7_family.BLIND7_PLANTS)
    assert len(BLIND8_PLANTS) == 4 and not set(BLIND8_PLANTS) & older_plants
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
    )
    older_forms = {f for table in tables for e, forms in table.items() if e != "none" for f in forms}
    assert BLIND8_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND8_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND8_PLANTS:
        for effect, forms in BLIND8_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60 and min(c.seed for c in CASES) == SEED_BASE
    assert Counter(c.effect == "none" for c in CASES) == {False: 40, True: 20}
    assert not {c.seed for c in CASES} & _older_seeds()
    older_offsets = {blind2_family.SENSORS.seed_offset, blind3_family.SENSORS.seed_offset}
    older_offsets |= {blind4_family.SENSORS.seed_offset, blind5_family.SEED_OFFSET, blind6_family.SEED_OFFSET}
    assert SEED_OFFSET not in older_offsets | {10_000, 50_000, blind7_family.SEED_OFFSET}
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    older_protocols |= {*blind2_protocols.BLIND2_PROTOCOLS, *blind3_protocols.BLIND3_PROTOCOLS}
    older_protocols |= {*blind4_protocols.BLIND4_PROTOCOLS, *blind5_protocols.BLIND5_PROTOCOLS}
    older_protocols |= {*blind6_protocols.BLIND6_PROTOCOLS, *blind7_protocols.BLIND7_PROTOCOLS}
    assert {c.protocol for c in CASES} == set(BLIND8_PROTOCOLS) and len(BLIND8_PROTOCOLS) == 5
    assert not set(BLIND8_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    older_rates |= {*blind2_family.BLIND2_RATES_HZ, *blind3_family.BLIND3_RATES_HZ, *blind4_family.BLIND4_RATES_HZ}
    older_rates |= {*blind5_family.BLIND5_RATES_HZ, *blind6_family.BLIND6_RATES_HZ, *blind7_family.BLIND7_RATES_HZ}
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND8_RATES_HZ) and all(40.0 <= r <= 600.0 for r in rates) and not rates & older_rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND8_PROTOCOLS) * len(rates)
    for forms in BLIND8_FORMS.values():  # a form is not tied to one protocol or rate
        for form in forms:
            mine = [c for c in CASES if c.form == form]
            assert len({c.protocol for c in mine}) >= 4 and len({c.rate_hz for c in mine}) >= 3, form
    older_columns: set[str] = set()
    for module in (fresh_effects, blind_effects, blind2_effects, blind3_effects, blind4_effects, blind5_effects):
        older_columns |= {*module.LOAD_PATTERNS, *module.TEMPERATURE_PATTERNS}
    for later in (blind6_effects, blind7_effects):
        older_columns |= {*later.LOAD_PATTERNS, *later.TEMPERATURE_PATTERNS}
    assert not {*LOAD_PATTERNS, *TEMPERATURE_PATTERNS} & older_columns
    assert {c.plant for c in CASES if c.effect == "none"} == set(BLIND8_PLANTS)


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
        again = render(params, u, dt, case.form, dict(q), load, temp, sim["base"])
        change = rms(again - sim["on"])
        if case.effect in (f"{which}_dependence", f"{which}_drift"):  # held, it is the effect-free record
            assert change == pytest.approx(truth["effect_size"]) and change >= EFFECT_MIN_OVER_NOISE * truth["noise"]
        else:
            assert change == 0.0, (which, change)


@pytest.mark.parametrize("plant", BLIND8_PLANTS)
def test_effect_free_records_carry_the_rig_confounds(plant: str) -> None:
    """The port's flow noise in the recorded input, the SAR bit errors, the auto-zero steps and
    the anti-alias filters are in every record; none is an effect of its own size."""
    case = next(c for c in CASES if c.plant == plant and c.effect == "none")
    sim = _simulated(case)
    m, truth = measurement_from(case, sim)
    params, dt = truth["plant_parameters"], 1.0 / case.rate_hz
    pressure = muscle_pressure(sim["command"], dt, params)
    flow_noise = sim["u"] - anti_alias(pressure, dt, params["aa_share"])
    assert 0.0 < rms(flow_noise) < 0.01 * params["peak"]
    noise = port_flow_noise(pressure, dt, params)
    flow = np.abs(np.diff(pressure, prepend=pressure[0])) / dt / (params["slew_per_s"] * params["peak"])
    assert np.all(np.abs(noise[flow < 1e-6]) < 1e-6) and np.any(noise != 0.0)  # only while air flows
    assert np.array_equal(sim["off"], stroke_reading(sim["base"], dt, params))
    clean = {**params, "autozero_mm": 0.0, **{k: 0.0 for k in params if k.startswith("sar_w")}}
    corner = params["aa_share"] * (1.0 + params["aa_mismatch"])  # the stroke channel's, a little off
    assert np.allclose(stroke_reading(sim["base"], dt, clean), anti_alias(sim["base"], dt, corner))
    sar = sar_bit_error(sim["base"], params)
    assert 0.0 < np.max(np.abs(sar)) < 30.0 * params["sar_lsb_mm"]
    zero = autozero_steps(sim["base"].size, dt, params)
    assert len(np.unique(zero)) >= 2 and np.max(np.abs(zero)) < 5.0 * params["autozero_mm"]
    assert rms(sar + zero) < 3.0 * truth["noise"]  # a few noise units at most
    assert np.std(m.u - sim["u"]) < 0.01  # bar: the transducer's noise and step


def test_anti_alias_filter_lags_a_ramp_by_its_continuous_time_delay_at_any_rate() -> None:
    """First-order hold: a ramp lags by ``2 zeta / wn`` exactly, with no half-sample extra."""
    for rate in BLIND8_RATES_HZ:
        dt = 1.0 / rate
        t = np.arange(int(20.0 * rate)) * dt
        x = np.asarray(10.0 * t, dtype=np.float64)
        late = (x - anti_alias(x, dt, 0.35))[-10:] / 10.0
        assert np.allclose(late, 2.0 * np.sqrt(0.5) / (2.0 * np.pi * 0.35 * rate), rtol=1e-6)


def test_sar_errors_jump_only_at_carries_into_the_mismatched_bits() -> None:
    params = draw_params("mindlin_crossings", np.random.default_rng(3), 4.0)
    lsb = params["sar_lsb_mm"]
    x = np.linspace(0.0, 4000.0 * lsb, 40001)
    err = sar_bit_error(x, params)
    codes = np.floor(x / lsb).astype(np.int64) + int(params["sar_code0"])
    jumps = np.flatnonzero(np.diff(err) != 0.0) + 1
    assert jumps.size > 0 and np.all(codes[jumps] % 16 == 0)  # bits 4 and up: every 16th code at most


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.15 * sim["u"].size)
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


def test_bessel_delays_a_ramp_by_its_group_delay_and_the_uart_holds_frames() -> None:
    dt = 0.002
    t = np.arange(int(10.0 / dt)) * dt
    x = np.asarray(10.0 * t, dtype=np.float64)  # mm: a steady 10 mm/s
    late = (x - bessel_demodulated(x, dt, {"group_delay_s": 0.03}))[t > 1.0] / 10.0
    assert np.allclose(late, 0.03, atol=0.001)  # a near-constant group delay
    q = {"firmware_latency_s": 0.02, "sensor_hz": 100.0, "baud": 19200.0, "sensor_phase": 0.0}
    read = uart_stream(x, dt, q)
    assert np.all(np.diff(read) >= 0.0) and np.count_nonzero(np.diff(read)) <= 10.0 * 100.0 + 1  # held frames
    behind = (x - read)[t > 1.0] / 10.0
    frame = 10.0 * 8 / 19200.0  # "xx.xxx\r\n"
    assert 0.02 + frame - 0.002 < float(behind.min()) and float(behind.max()) < 0.02 + 2 * frame + 0.01 + 0.002
    slow_line = uart_stream(x, dt, {**q, "baud": 9600.0})  # fewer bits per second: each frame later
    assert np.mean(x - slow_line) > np.mean(x - read)


@pytest.mark.parametrize("plant", BLIND8_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND8_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28, i40, i58 = (int(s / dt) for s in (10.0, 28.0, 40.0, 58.0))
    assert abs(base[i28] - base[i10]) < 0.01 * span and abs(base[i58] - base[i40]) < 0.01 * span  # it settles
    off = _render(plant, params, u, dt, "none", {})
    for form in BLIND8_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        change = _render(plant, params, u, dt, form, q) - off
        assert change[i28] > change[i10] + 0.002 * span > 0.002 * span, form  # still growing 8-26 s after the step
        assert change[i40] < change[i28], form  # and recovering after the step down
        if form == "crimp_interchange":  # re-crimping all the way down
            assert change[i58] < change[i40]


def test_crimp_recrimps_slower_than_it_straightens() -> None:
    dt = 0.01
    t = np.arange(int(60.0 / dt)) * dt
    v = np.where(t < 30.0, 0.8, 0.3)
    q = {"crimp_tau_s": 4.0, "crimp_exhaustion": 2.0, "recrimp_factor": 3.0}
    c = crimp_state(v, dt, q)
    assert c[0] == pytest.approx(0.64 * (1.0 - np.exp(-dt / 4.0)))  # at first at 1 / tau
    first_up = (c[int(1.0 / dt)] - c[0]) / (0.64 - c[0])
    first_down = (c[int(30.0 / dt) - 1] - c[int(31.0 / dt)]) / (c[int(30.0 / dt) - 1] - 0.09)
    assert first_down < first_up and np.all(np.diff(c[: int(30.0 / dt)]) > 0.0)
    slowing = np.diff(c[: int(30.0 / dt)]) / (0.64 - c[: int(30.0 / dt) - 1])
    assert np.all(np.diff(slowing) < 1e-12)  # the used-up crimp straightens ever slower


@pytest.mark.parametrize("plant", BLIND8_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND8_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            sizes.append(rms(_render(plant, params, u, dt, form, q) - _render(plant, params, u, dt, "none", q)))
        assert sizes[1] > 2.0 * sizes[0], (form, sizes)


def test_air_dashpot_is_viscous_when_slow_and_capped_by_its_air_spring() -> None:
    dt = 0.001
    t = np.arange(int(4.0 / dt)) * dt
    q = {"air_stiffness_ratio": 0.2, "orifice_s": 0.1}
    slow = air_dashpot_lag(np.asarray(5.0 * t, dtype=np.float64), dt, q)
    assert slow[-1] == pytest.approx(0.2 * 0.1 * 5.0, rel=0.01)  # r tau v
    jump = air_dashpot_lag(np.where(t < 1.0, 0.0, 3.0), dt, q)
    assert float(jump.max()) == pytest.approx(3.0 * 0.2 / 1.2, rel=0.02) and abs(jump[-1]) < 1e-3


def test_inerter_rings_after_a_step_and_settles_on_it() -> None:
    dt, peak = 0.002, 4.0
    params = draw_params("fancher_leaf_spring", np.random.default_rng(7), peak)
    u = step_and_hold(peak, dt)
    q = {"inertance_s2": (2.0 * np.pi * 3.0) ** -2, "inerter_zeta": 0.15}
    change = _render("fancher_leaf_spring", params, u, dt, "flywheel_inerter", q)
    change -= _render("fancher_leaf_spring", params, u, dt, "none", q)
    after = change[int(2.0 / dt) : int(4.0 / dt)]
    assert np.max(after) > 0.05 and np.min(after) < -0.05  # overshoots and swings back
    assert np.max(np.abs(change[int(20.0 / dt) : int(29.0 / dt)])) < 0.01  # settled on the same stroke


def test_belleville_stack_is_degressive_and_bowden_sheath_progressive() -> None:
    tension = np.linspace(10.0, 200.0, 400)  # N
    disc = belleville_deflection(tension, {"stack_mm": 2.0, "cone_ratio": 1.0, "flat_over_line": 2.0}, 100.0)
    sheath = sheath_compression(tension, {"gap_mm": 1.0, "gap_over_line": 1.0, "solid_mm_per_n": 0.002}, 100.0)
    assert np.allclose(
        disc, belleville_deflection(tension, {"stack_mm": 2.0, "cone_ratio": 1.0, "flat_over_line": 1.0}, 200.0)
    )
    assert np.all(np.diff(disc) > 0.0) and np.all(np.diff(sheath) > 0.0)
    assert np.all(np.diff(disc, 2) > -1e-9) and np.diff(disc)[-1] > 2.0 * np.diff(disc)[0]  # softer as it flattens
    assert np.all(np.diff(sheath, 2) < 1e-12) and np.diff(sheath)[-1] < 0.5 * np.diff(sheath)[0]  # gaps close first


def test_cord_inverts_and_the_drum_scales_the_whole_extension() -> None:
    dt, peak = 0.02, 4.0
    params = draw_params("crystallising_bladder", np.random.default_rng(9), peak)
    params.update(autozero_mm=0.0, **{k: 0.0 for k in params if k.startswith("sar_w")})  # the rig's errors off
    t = np.arange(int(120.0 / dt)) * dt
    u = np.asarray(peak * (0.1 + 0.8 * 0.5 * (1.0 - np.cos(2.0 * np.pi * t / 20.0))), dtype=np.float64)
    base = BLIND8_CORES["crystallising_bladder"](u, dt, params)
    load, still, warm = np.full_like(u, 2.0), np.full_like(u, 20.0), np.where(t < 10.0, 20.0, 30.0)
    qc = {
        "cord_mm_share": 1.0,
        "cord_prestretch": 0.01,
        "cord_stretch": 0.3,
        "cord_expansion_per_k": 2.2e-4,
        "cord_thermal_tau_s": 5.0,
    }
    change = render(params, u, dt, "thermoelastic_inversion_cord", qc, load, warm, base)
    change -= render(params, u, dt, "thermoelastic_inversion_cord", qc, load, still, base)
    late = t > 60.0
    low, high = late & (base < 0.1 * np.max(base)), late & (base > 0.8 * np.max(base))
    assert np.mean(change[low]) > 0.0 > np.mean(change[high])  # weaker at small stretch, stronger at large
    qd = {"drum_alpha_per_k": 1e-4, "dead_length_mm": 600.0, "drum_tau_s": 10.0}
    change = render(params, u, dt, "drawwire_drum_expansion", qd, load, warm, base)
    change -= render(params, u, dt, "drawwire_drum_expansion", qd, load, still, base)
    expected = -(600.0 + base[late]) * 1e-3 / (1.0 + 1e-3)  # settled 10 K warmer
    assert np.allclose(change[late], expected, atol=0.02)


def test_ivshin_pence_crystallinity_stays_between_its_boundaries() -> None:
    params = draw_params("crystallising_bladder", np.random.default_rng(11), 4.0)
    v = np.concatenate([np.linspace(0.0, 1.0, 500), np.linspace(1.0, 0.4, 300)[1:], np.linspace(0.4, 0.8, 200)[1:]])
    x = ivshin_pence_crystallinity(v, params)
    assert np.all((x >= 0.0) & (x <= 1.0)) and x[0] == 0.0
    assert np.all(np.diff(x[:500]) >= 0.0) and np.all(np.diff(x[499:799]) <= 0.0) and np.all(np.diff(x[798:]) >= 0.0)
    width = params["crystal_width"]
    crystallising = 1.0 / (1.0 + np.exp(-(v - params["crystal_onset"]) / width))
    melting = 1.0 / (1.0 + np.exp(-(v - params["melt_onset"]) / width))
    c0 = crystallising[0]
    assert np.allclose(x[:500], (crystallising[:500] - c0) / (1.0 - c0), atol=1e-9)  # from amorphous
    assert np.allclose(x[499:799], x[499] * melting[499:799] / melting[499], atol=1e-9)  # scaled melting boundary
    xr, cr = x[798], crystallising[798]  # rising again: scaled between the reversal and full crystallinity
    assert np.allclose(x[798:], 1.0 - (1.0 - xr) * (1.0 - crystallising[798:]) / (1.0 - cr), atol=1e-9)


def test_bounding_surface_friction_starts_elastic_and_approaches_its_bound() -> None:
    params = draw_params("bounding_surface_braid", np.random.default_rng(12), 4.0)
    v = np.concatenate([np.linspace(0.0, 1.0, 4001), np.linspace(1.0, 0.0, 4001)[1:]])
    s = dafalias_popov_friction(v, params)
    bound = params["dp_bound"] * (0.15 + 0.85 * v)
    assert np.all(np.abs(s) <= bound + 1e-12)
    assert s[4000] > 0.97 * bound[4000] and s[-1] < -0.9 * bound[-1]  # near the bound after a long travel
    slope = (s[4002] - s[4000]) / (v[4002] - v[4000])
    z_top = s[4000] / bound[4000]
    elastic = params["dp_bound"] * (params["dp_elastic"] + 0.85 * z_top)  # d(bound z)/dv with dz/dv = E
    assert slope == pytest.approx(elastic, rel=0.1)  # elastic just after the reversal


def test_mindlin_elements_follow_the_three_halves_backbone() -> None:
    params = {"slip_force_mm": 1.0, "slip_distance_mm": 2.0, "normal_floor": 0.0}
    x0 = np.linspace(0.0, 2.0, 2001)
    f = mindlin_friction(x0, np.ones_like(x0), params)  # N = 1: F = 1 mm, delta* = 2 mm
    backbone = 1.0 - (1.0 - x0 / 2.0) ** 1.5
    assert np.max(np.abs(f - backbone)) < 0.06 and f[-1] == pytest.approx(1.0, abs=0.002)
    back = np.linspace(2.0, -2.0, 4001)[1:]
    down = mindlin_friction(np.concatenate([x0, back]), np.ones(x0.size + back.size), params)
    half = down[x0.size + 1999]  # 2 mm back: Masing's branch, F_max - 2 F_backbone(1 mm)
    assert half == pytest.approx(1.0 - 2.0 * (1.0 - 0.5**1.5), abs=0.06)
    assert down[-1] == pytest.approx(-1.0, abs=0.002)  # twice the backbone's travel reverses it fully
    halved = mindlin_friction(x0, np.concatenate([np.ones(1000), np.full(1001, 0.25)]), params)
    assert np.max(np.abs(halved[1001:])) <= 0.25 * 1.002  # a lower normal force lets the loaded elements slip


def test_fancher_state_moves_between_its_envelopes_by_path_length() -> None:
    x0 = np.concatenate([np.linspace(0.0, 10.0, 1001), np.linspace(10.0, 9.0, 101)[1:]])
    phi = fancher_envelope_state(x0, 0.5)
    assert phi[1000] == pytest.approx(1.0 - np.exp(-20.0), abs=1e-6)
    assert phi[-1] == pytest.approx(-1.0 + 2.0 * np.exp(-2.0), abs=1e-3)  # 1 mm back: e^(-1 / 0.5)
    fast = fancher_envelope_state(x0[::10], 0.5)
    assert np.allclose(fast, phi[::10], atol=1e-9)  # rate-independent: path length only


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind8_measurement)


@pytest.mark.parametrize("duration_s", [40.0, 300.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind8_cases, blind8_measurement, duration_s)


@pytest.mark.parametrize("core", list(BLIND8_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND8_CORES[core], partial(draw_params, core))


@pytest.mark.parametrize("protocol", list(BLIND8_PROTOCOLS))
def test_protocols_start_vented_shake_down_early_and_then_keep_covering_it(protocol: str) -> None:
    dt, peak = 1.0 / 48.0, 4.0
    for seed in range(3):
        u = with_shakedown(protocol, 60.0, dt, peak, np.random.default_rng(seed))
        assert u.size == 2880 and np.all(np.isfinite(u)) and np.all(u[:24] == 0.0)
        early = int(0.15 * u.size)
        assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:early]) >= 0.96 * peak
        lead = u[: int(7.0 / dt)]
        assert np.count_nonzero(np.diff(np.sign(lead - 0.5 * peak)) > 0) >= 4  # four shakedown cycles
        body = u[early:]
        assert np.ptp(body) > 0.35 * peak
        crossings = np.count_nonzero(np.diff(np.sign(body - 0.5 * peak)) != 0)
        assert crossings >= 2  # the range is covered again, not once
