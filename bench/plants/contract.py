"""The promises every plant family keeps, written once as checks (scikit-learn's
``estimator_checks`` shape): ``tests/test_plant_contract.py`` runs each check on every family of
the registry, and a new family's author runs them the same way before scoring anything.

A check takes a family's spec (and, for a per-record check, a case and its simulation) and
raises ``AssertionError`` naming what broke. A family switches a check off with a tag of the
check's name in ``FamilySpec.tags`` where the property does not apply to it (the tuning family
keeps no effect-free twin; the first held-out families reuse protocols or rates of the tuning
set), so every skip is written down beside the family, not in a test. A tag ``slow:<check>``
runs that check only under ``-m slow`` (a check a family's own tests never had, where it costs
seconds in the default run).
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable
from functools import partial
from typing import Any

import numpy as np

from bench.plants import engine
from bench.plants.case import Case
from bench.plants.engine import LOAD_TEMP_EFFECTS, FamilySpec, Run
from bench.plants.properties import (
    assert_any_duration_builds,
    assert_closed_loop_3_to_20_percent_wide,
    assert_deterministic_by_seed,
    slow_and_fast_triangles,
    step_and_hold,
)
from bench.plants.visibility import EFFECT_MAX_OVER_SPAN, EFFECT_MIN_OVER_NOISE, MAX_CALIBRATION, rms

SPAN_MM = (8.0, 60.0)  # every family's effect-free stroke: a muscle's, not a sensor's
LOAD_MOVES_KG, TEMPERATURE_MOVES_K = 0.3, 0.5  # the columns move in every record
EARLY_SHARE = 0.2  # the memory is known within the first fifth of a record
NOISE_REL = 0.2  # the recorded output's scatter about the truth is the truth's noise, to 20 %


def _older(spec: FamilySpec, registry: Iterable[FamilySpec]) -> list[FamilySpec]:
    return [other for other in registry if other.seed_base < spec.seed_base]


def check_cases_cover_the_spec(spec: FamilySpec) -> None:
    """Every effect-form on every core once (effect-free ``none_per_plant`` times), distinct
    seeds, every protocol and every rate (40-600 Hz) used, and every protocol-rate pair met."""
    cases = engine.cases(spec, 1.0)
    per = Counter((c.plant, c.effect, c.form) for c in cases)
    for plant in spec.plants:
        for effect, forms in spec.forms.items():
            for form in forms:
                assert per[(plant, effect, form)] == (spec.none_per_plant if effect == "none" else 1), (plant, form)
    assert len({c.seed for c in cases}) == len(cases)
    assert {c.protocol for c in cases} == set(spec.protocols) and {c.rate_hz for c in cases} == set(spec.rates_hz)
    assert all(40.0 <= rate <= 600.0 for rate in spec.rates_hz)  # Hz: a muscle rig's logging rates
    if "pairs" not in spec.tags:
        assert len({(c.protocol, c.rate_hz) for c in cases}) == len(spec.protocols) * len(spec.rates_hz)


def check_unlike_every_older_family(spec: FamilySpec, registry: Iterable[FamilySpec]) -> None:
    """New cores, forms (of a real effect), protocols, rates and seeds: nothing an older family
    (lower seeds) has; tags ``shares_protocols`` / ``shares_rates`` record a family that reuses them."""
    older = _older(spec, registry)
    mine = {c.seed for c in engine.cases(spec, 1.0)}
    for other in older:
        assert not set(spec.plants) & set(other.plants), (other.name, "plants")
        forms = {f for e, fs in spec.forms.items() if e != "none" for f in fs}
        assert not forms & {f for e, fs in other.forms.items() if e != "none" for f in fs}, (other.name, "forms")
        if "shares_protocols" not in spec.tags:
            assert not set(spec.protocols) & set(other.protocols), (other.name, "protocols")
        if "shares_rates" not in spec.tags:
            assert not set(spec.rates_hz) & set(other.rates_hz), (other.name, "rates")
        assert not mine & {c.seed for c in engine.cases(other, 1.0)}, (other.name, "seeds")
        offsets = {s.seed_offset for s in spec.sensors.values()} & {s.seed_offset for s in other.sensors.values()}
        assert not offsets or "shares_seed_offset" in spec.tags, (other.name, "measurement seed offset")


def check_deterministic_by_seed(spec: FamilySpec) -> None:
    """A case recorded twice is the same record (every 20th case, 20 s); the next seed gives another."""
    assert_deterministic_by_seed(engine.cases(spec, 20.0), lambda case: engine.measurement(spec, case), stride=20)


def check_any_duration_builds(spec: FamilySpec) -> None:
    """A record of 30 s and of 200 s has its length, finite samples and a visible, modest effect."""
    for duration_s in (30.0, 200.0):
        assert_any_duration_builds(lambda d: engine.cases(spec, d), lambda c: engine.measurement(spec, c), duration_s)


def check_delay_forms_lag(sims: Iterable[tuple[Case, dict[str, Any]]]) -> None:
    """A transport delay's output lags its effect-free twin (the best shift is not zero)."""
    for case, sim in sims:
        if case.effect == "transport_delay":
            on, off = sim["on"], sim["off"]
            lags = np.arange(0, int(0.4 * case.rate_hz))
            misfit = [float(np.mean((on[k:] - off[: off.size - k]) ** 2)) for k in lags]
            assert lags[int(np.argmin(misfit))] > 0, case.name


def check_sizes_spread_over_the_band(spec: FamilySpec, sims: Iterable[tuple[Case, dict[str, Any]]]) -> None:
    """A calibrated family's effect sizes reach from ~1 % of the span to several %."""
    shares = np.array([s["truth"]["effect_size_over_span"] for c, s in sims if c.effect != "none"])
    assert np.min(shares) < 0.015 and np.max(shares) > 0.06 and 0.015 <= np.median(shares) <= 0.06


def check_protocols_start_vented_and_cover_the_range(spec: FamilySpec) -> None:
    """Each protocol (60 s at the slowest rate, three seeds) starts vented, stays in
    ``[0, peak]`` and keeps covering the range after its first fifth."""
    dt, peak = 1.0 / min(spec.rates_hz), 4.0
    for seed in range(3):
        for protocol in spec.protocols:
            u = spec.excite(protocol, 60.0, dt, peak, np.random.default_rng(seed))
            assert u.size == int(round(60.0 / dt)) and np.all(np.isfinite(u)) and u[0] == 0.0, protocol
            early = int(EARLY_SHARE * u.size)
            assert u.min() >= 0.0 and u.max() <= peak + 1e-9, protocol
            assert np.ptp(u[early:]) > 0.3 * peak, protocol


def check_record(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> None:
    """The recording is finite, on its time grid, its output on the sensor's reading step with
    the truth's noise, its columns move, its span a muscle's; the effect's size is what the
    truth says and lies in the visibility band (zero in an effect-free record)."""
    m, truth = engine.measurement_from(spec, case, sim)
    n = int(round(case.duration_s * case.rate_hz))
    assert len(m) == m.u.size == m.y.size == n and np.all(np.isfinite(m.y)) and np.all(np.isfinite(m.u))
    assert np.allclose(np.diff(m.t), 1.0 / case.rate_hz) and m.source == case.name
    assert (truth["effect"], truth["form"]) == (case.effect, case.form) and set(m.extras) == {"load", "temperature"}
    assert np.ptp(m.extras["load"]) >= LOAD_MOVES_KG and np.ptp(m.extras["temperature"]) >= TEMPERATURE_MOVES_K
    assert SPAN_MM[0] <= truth["span"] <= SPAN_MM[1]
    sensors = spec.sensors.get(case.plant)
    if sensors is not None:  # every channel on its reading step
        for column, step in ((m.y, sensors.quant_mm), (m.extras["load"], sensors.load_read_kg)):
            assert np.allclose(column / step, np.round(column / step), atol=1e-6)
        temperature = m.extras["temperature"] / sensors.temp_read_k
        assert np.allclose(temperature, np.round(temperature), atol=1e-6)
    # the scatter where the output moves slowly (< 5 mm/s: a time-base error adds nothing there),
    # and, where the rig drops frames, not on a frame that repeats the one before
    slow = np.abs(np.gradient(sim["on"], 1.0 / case.rate_hz)) < 5.0
    if truth.get("dropped_frames", 0):
        slow[np.flatnonzero(np.diff(m.y) == 0.0) + 1] = False
    scatter = float(np.std((m.y - sim["on"])[slow]))
    assert abs(scatter - truth["noise"]) <= NOISE_REL * truth["noise"], (scatter, truth["noise"])
    size = rms(sim["on"] - sim["off"])
    assert np.isclose(size, truth["effect_size"], rtol=1e-6, atol=1e-12)
    if case.effect == "none":
        assert size == 0.0
        return
    assert EFFECT_MIN_OVER_NOISE * truth["noise"] <= size <= EFFECT_MAX_OVER_SPAN * truth["span"]
    assert 0.25 <= truth["intensity_rescale"] <= 4.0
    if spec.calibration is not None:
        calibration = truth["parameters"]["calibration"]
        assert 1.0 / MAX_CALIBRATION - 1e-9 <= calibration <= MAX_CALIBRATION + 1e-9


STILL_TEMPERATURE_C = 22.0  # the columns held still in the form checks: no load, room temperature


def _still_run(spec: FamilySpec, plant: str, u: Any, dt: float, params: dict[str, float]) -> Run:
    case = Case(plant, "none", "none", spec.protocols[0], 1.0 / dt, 0, u.size * dt)
    run = Run(case, spec.cores[plant], dt, float(params.get("peak", np.max(u))), u, np.arange(u.size) * dt, params)
    base = spec.base(run) if spec.base is not None else run.core(u, dt, params)
    return Run(case, run.core, dt, run.peak, u, run.t, params, base)


def _with_still_columns(spec: FamilySpec, run: Run, form: str, q: dict[str, float]) -> Any:
    """``form`` rendered over its effect-free twin with no load and a still room temperature."""
    assert spec.render is not None
    load, temperature = np.zeros_like(run.u), np.full_like(run.u, STILL_TEMPERATURE_C)
    off = spec.render(run, "none", dict(q), load, temperature, None)
    return off, spec.render(run, form, q, load, temperature, off)


def check_creep_forms_keep_moving_in_a_hold(spec: FamilySpec) -> None:
    """After a step to 70 % of the peak held 28 s (:func:`bench.plants.properties.step_and_hold`),
    each core settles (< 1 % of its span between 10 s and 28 s) and each creep form still moves
    the output by more than 0.3 % of the span over that time (in the direction
    ``promises["creep_sign"]`` where the family promises one)."""
    assert spec.draw_effect is not None
    for plant in spec.plants:
        rng = np.random.default_rng(5)
        dt, peak = 0.01, 4.0
        params = spec.draw_params(plant, rng, peak)
        run = _still_run(spec, plant, step_and_hold(peak, dt), dt, params)
        off, _ = _with_still_columns(spec, run, "none", {})
        span, i10, i28 = float(np.ptp(off)), int(10.0 / dt), int(28.0 / dt)
        assert abs(off[i28] - off[i10]) < 0.01 * span, (plant, "the effect-free plant settles")
        for form in spec.forms["creep"]:
            off, on = _with_still_columns(spec, run, form, spec.draw_effect("creep", form, rng))
            drift = (on - off)[i28] - (on - off)[i10]
            sign = spec.promises.get("creep_sign", float(np.sign(drift)))  # +1: contracting further
            assert sign * drift > 0.003 * span, (plant, form, drift / span)


def check_rate_forms_grow_with_the_input_speed(spec: FamilySpec) -> None:
    """Each rate form's size (RMS [mm] over its effect-free twin) on 4 s triangles is more than
    ``promises["rate_growth"]`` (default 2) x its size on 40 s triangles."""
    assert spec.draw_effect is not None
    growth = spec.promises.get("rate_growth", 2.0)
    for plant in spec.plants:
        rng = np.random.default_rng(6)
        dt, peak = 0.005, 4.0
        params = spec.draw_params(plant, rng, peak)
        for form in spec.forms["rate_dependence"]:
            q = spec.draw_effect("rate_dependence", form, rng)
            sizes = []
            for u in slow_and_fast_triangles(peak, dt):
                off, on = _with_still_columns(spec, _still_run(spec, plant, u, dt, params), form, q)
                sizes.append(rms(on - off))
            assert sizes[1] > growth * sizes[0], (plant, form, sizes)


def check_core_draws_a_closed_loop(spec: FamilySpec) -> None:
    """Each core, on slow triangles over three parameter draws, draws a closed loop (the last
    cycle within ``promises["loop_settled_share"]``, default 2 %, of the one before; over
    ``promises["loop_cycles"]``, default 4) of a 10-50 mm stroke, 3-20 % of it wide, the
    descending branch above the ascending one."""
    cycles = int(spec.promises.get("loop_cycles", 4))
    settled = spec.promises.get("loop_settled_share", 0.02)
    for plant, core in spec.cores.items():
        assert_closed_loop_3_to_20_percent_wide(core, partial(spec.draw_params, plant), cycles, settled)


def rerun(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Run:
    """The :class:`bench.plants.engine.Run` a simulation was rendered from, rebuilt from it."""
    params = sim["truth"]["plant_parameters"]
    peak = float(params.get("peak", np.max(sim["command"])))
    dt = 1.0 / case.rate_hz
    return Run(case, spec.cores[case.plant], dt, peak, sim["command"], sim["t"], params, sim.get("base"))


def check_columns_act_only_in_their_own_records(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> None:
    """Holding the load (or the temperature) still changes nothing unless the record's effect is
    the load's (the temperature's), and then it changes the output by more than the noise."""
    assert spec.render is not None
    truth, run = sim["truth"], rerun(spec, case, sim)
    q = dict(truth["parameters"])
    still_load = np.full_like(sim["load"], float(sim["load"][0]))
    still_temp = np.full_like(sim["temperature"], float(sim["temperature"][0]))
    for load, temp, which in ((still_load, sim["temperature"], "load"), (sim["load"], still_temp, "temperature")):
        again = spec.render(run, case.form, q, load, temp, sim["off"])
        change = rms(again - sim["on"])
        if case.effect in (f"{which}_dependence", f"{which}_drift"):
            assert change >= 0.5 * EFFECT_MIN_OVER_NOISE * truth["noise"], (which, change)
        else:
            assert change == 0.0, (which, change)


def check_memory_known_early(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> None:
    """The record starts vented and at rest (within 0.3 mm of zero, or of its lowest point where
    a held load stretches the muscle below it), and its first fifth reaches the peak and sweeps
    most of the stroke (the hysteresis memory is known early)."""
    early = int(EARLY_SHARE * sim["command"].size)
    u, off = sim["command"], sim["off"]
    assert u[0] == 0.0 and min(abs(off[0]), abs(off[0] - np.min(off))) < 0.3
    assert np.max(u[:early]) >= 0.96 * np.max(u) and np.ptp(off[:early]) >= 0.85 * np.ptp(off)


FAMILY_CHECKS: tuple[Callable[[FamilySpec], None], ...] = (
    check_cases_cover_the_spec,
    check_deterministic_by_seed,
    check_any_duration_builds,
    check_protocols_start_vented_and_cover_the_range,
    check_creep_forms_keep_moving_in_a_hold,
    check_rate_forms_grow_with_the_input_speed,
    check_core_draws_a_closed_loop,
)
RECORD_CHECKS: tuple[Callable[[FamilySpec, Case, dict[str, Any]], None], ...] = (
    check_record,
    check_memory_known_early,
)


def applies(check: Callable[..., None], spec: FamilySpec) -> bool:
    """Whether ``check`` runs on ``spec``: not if the family is tagged with the check's name, and
    the record checks only on families the engine simulates."""
    name = check.__name__
    if name in spec.tags:
        return False
    simulated = spec.custom_record is None
    return simulated or name in ("check_deterministic_by_seed", "check_cases_cover_the_spec")


def load_or_temperature(case: Case) -> bool:
    return case.effect == "none" or case.effect in LOAD_TEMP_EFFECTS
