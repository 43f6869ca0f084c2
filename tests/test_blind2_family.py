"""Properties of the fourth (blind2) held-out plant family; the diagnosis is never run here.

Short records (40 s) keep the default run to a few CPU seconds. Checked: coverage (new cores,
forms, protocols, rates, every protocol-rate pair), determinism by seed, finite quantised
records, every effect visible (>= 5x noise) yet modest (<= 12 % of span), columns that move in
every record and do nothing unless they are the effect (and do something when they are), the
memory known early (full range in the first 15 %), delays that lag, creep that keeps moving
in a hold, rate forms that grow with speed, and each core's loop (closed, 3-20 % wide).
"""

from __future__ import annotations

from collections import Counter
from functools import cache, partial
from typing import Any

import numpy as np
import pytest

from bench.plants import (
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
from bench.plants.blind2_cores import BLIND2_CORES, draw_params
from bench.plants.blind2_effects import BLIND2_FORMS, draw_effect_params, render
from bench.plants.blind2_family import (
    BLIND2_PLANTS,
    BLIND2_RATES_HZ,
    NONE_PER_PLANT,
    QUANT_MM,
    blind2_cases,
    blind2_measurement,
    measurement_from,
    simulate,
)
from bench.plants.blind2_protocols import BLIND2_PROTOCOLS, with_range_check
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_closed_loop_3_to_20_percent_wide,
    assert_deterministic_by_seed,
    slow_and_fast_triangles,
    step_and_hold,
)
from bench.plants.visibility import EFFECT_MAX_OVER_SPAN, EFFECT_MIN_OVER_NOISE

DURATION_S = 40.0
CASES = blind2_cases(DURATION_S)


@cache
def _simulated(case: family.Case) -> dict[str, Any]:
    return simulate(case)


def test_cases_cover_new_cores_forms_protocols_and_rates() -> None:
    older_plants = {*family.TUNING_PLANTS, *family.SECOND_TUNING_PLANTS, *fresh_family.FRESH_PLANTS}
    older_plants |= set(blind_family.BLIND_PLANTS)
    assert len(BLIND2_PLANTS) == 4 and not set(BLIND2_PLANTS) & older_plants
    older_forms = {
        f
        for table in (effects.FORMS, fresh_effects.FRESH_FORMS, blind_effects.BLIND_FORMS)
        for e, forms in table.items()
        if e != "none"
        for f in forms
    }
    assert BLIND2_FORMS.keys() == effects.FORMS.keys()
    assert all(len(forms) == 2 and not set(forms) & older_forms for e, forms in BLIND2_FORMS.items() if e != "none")
    per = Counter((c.plant, c.effect, c.form) for c in CASES)
    for plant in BLIND2_PLANTS:
        for effect, forms in BLIND2_FORMS.items():
            for form in forms:
                assert per[(plant, effect, form)] == (NONE_PER_PLANT if effect == "none" else 1)
    assert len(CASES) == 60 and len({c.seed for c in CASES}) == 60
    assert min(c.seed for c in CASES) >= 12000
    older_protocols = {*protocols.PROTOCOLS, *fresh_protocols.FRESH_PROTOCOLS, *blind_protocols.BLIND_PROTOCOLS}
    assert {c.protocol for c in CASES} == set(BLIND2_PROTOCOLS) and len(BLIND2_PROTOCOLS) >= 5
    assert not set(BLIND2_PROTOCOLS) & older_protocols
    older_rates = {*family.RATES_HZ, *fresh_family.FRESH_RATES_HZ, *blind_family.BLIND_RATES_HZ}
    rates = {c.rate_hz for c in CASES}
    assert rates == set(BLIND2_RATES_HZ) and all(50.0 <= r <= 500.0 for r in rates) and not rates & older_rates
    assert {70.0, 175.0, 333.0, 480.0} <= rates
    assert len({(c.protocol, c.rate_hz) for c in CASES}) == len(BLIND2_PROTOCOLS) * len(rates)


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
    assert 8.0 <= truth["span"] <= 60.0 and np.min(sim["off"]) > -0.5  # mm; the rest length
    assert np.std(m.y - sim["on"]) == pytest.approx(truth["noise"], rel=0.15)
    size = float(np.sqrt(np.mean((sim["on"] - sim["off"]) ** 2)))
    assert size == pytest.approx(truth["effect_size"])
    if case.effect == "none":
        assert size == 0.0
        return
    assert EFFECT_MIN_OVER_NOISE * truth["noise"] <= size <= EFFECT_MAX_OVER_SPAN * truth["span"]
    assert 0.25 <= truth["intensity_rescale"] <= 4.0


@pytest.mark.parametrize(
    "case", [c for c in CASES if c.effect in ("none", "load_dependence", "temperature_drift")], ids=lambda c: c.name
)
def test_columns_act_only_in_their_own_effects_records(case: family.Case) -> None:
    sim = _simulated(case)
    truth = sim["truth"]
    core, params, q = BLIND2_CORES[case.plant], truth["plant_parameters"], truth["parameters"]
    dt = 1.0 / case.rate_hz
    still_load = np.full_like(sim["load"], float(np.median(sim["load"])))
    still_temp = np.full_like(sim["temperature"], float(sim["temperature"][0]))
    for load, temp, which in ((still_load, sim["temperature"], "load"), (sim["load"], still_temp, "temperature")):
        again = render(core, params, sim["u"], dt, case.form, dict(q), load, temp)
        change = float(np.sqrt(np.mean((again - sim["on"]) ** 2)))
        acts = case.effect == f"{which}_dependence" or case.effect == f"{which}_drift"
        if acts:
            assert change > EFFECT_MIN_OVER_NOISE * truth["noise"] / 2.0, (which, change)
        else:
            assert change == 0.0, (which, change)


@pytest.mark.parametrize("case", CASES[::3], ids=lambda c: c.name)
def test_memory_is_known_early(case: family.Case) -> None:
    sim = _simulated(case)
    early = int(0.15 * sim["u"].size)
    u, off = sim["u"], sim["off"]
    assert u[0] == 0.0 and off[0] == pytest.approx(0.0, abs=1e-9)
    assert np.max(u[:early]) >= 0.97 * np.max(u)
    assert np.ptp(off[:early]) >= 0.85 * np.ptp(off)


def test_delay_forms_lag_the_effect_free_output() -> None:
    for case in (c for c in CASES if c.effect == "transport_delay"):
        sim = _simulated(case)
        on, off = sim["on"], sim["off"]
        lags = np.arange(0, int(0.4 * case.rate_hz))
        misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
        assert lags[int(np.argmin(misfit))] > 0, case.name


@pytest.mark.parametrize("plant", BLIND2_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND2_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28 = int(10.0 / dt), int(28.0 / dt)
    assert abs(base[i28] - base[i10]) < 0.01 * span  # the effect-free rig settles (tails < 4 s)
    still = np.zeros_like(u)
    for form in BLIND2_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        on = render(BLIND2_CORES[plant], params, u, dt, form, q, still, still + 22.0, base)
        assert on[i28] - on[i10] > 0.003 * span, form  # still contracting 8-26 s after the step


@pytest.mark.parametrize("plant", BLIND2_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.005, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND2_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt):
            base = BLIND2_CORES[plant](u, dt, params)
            temps, loads = np.full_like(u, 22.0), np.zeros_like(u)
            on = render(BLIND2_CORES[plant], params, u, dt, form, q, loads, temps, base)
            sizes.append(float(np.sqrt(np.mean((on - base) ** 2))))
        assert sizes[1] > 3.0 * sizes[0], (form, sizes)


def test_measurement_is_deterministic_by_seed() -> None:
    assert_deterministic_by_seed(CASES, blind2_measurement)


@pytest.mark.parametrize("duration_s", [40.0, 300.0])
def test_any_duration_builds(duration_s: float) -> None:
    assert_any_duration_builds(blind2_cases, blind2_measurement, duration_s)


@pytest.mark.parametrize("core", list(BLIND2_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(
        BLIND2_CORES[core], partial(draw_params, core), cycles=3, settled_share=0.01
    )


@pytest.mark.parametrize("protocol", list(BLIND2_PROTOCOLS))
def test_protocols_start_vented_stay_in_range_and_excite(protocol: str) -> None:
    dt, peak = 1.0 / 70.0, 4.0
    u = with_range_check(protocol, 60.0, dt, peak, np.random.default_rng(2))
    assert u.size == 4200 and np.all(np.isfinite(u)) and np.all(u[:70] == 0.0)
    assert u.min() >= 0.0 and u.max() <= peak and np.max(u[:420]) >= 0.97 * peak
    assert np.ptp(u[420:]) > 0.4 * peak
