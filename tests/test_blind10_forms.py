"""Physics of the twelfth (blind10) plant family's forms, cores and rig; the diagnosis is never run here.

Each core's own physics (the muscle's force balance and the Gent bladder, the bristles' snaps and
re-bonds, the crossings' avalanches, the check valves' asymmetric play, the latch's snap), its loop
(closed, 3-20 % wide, descending above ascending) and rate independence; each effect form's
signature (the dashpot's lag of ``c / K``, self-heating that builds with fast cycling, creep that
keeps moving in a hold and ageing that slows it, the dead time, the PLC's scans lengthening with
its workload, the linear sag, the knots bedding in fast and recovering slowly, the gain's
temperature coefficient, the NiTi spring's thermal hysteresis); the rig's booster, transmitter,
bridge converter and NTC. A few CPU seconds in all.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from bench.plants.blind10_cores import (
    BLIND10_CORES,
    BLIND10_DRIVES,
    bladder_n,
    check_valve_pressure,
    draw_params,
    ofc_force,
    overcentre_push_n,
    residual_n,
    solve_strain,
    static_stroke,
    stiffness_n_mm,
)
from bench.plants.blind10_effects import (
    BLIND10_FORMS,
    INSIDE_FORMS,
    PLAIN_FORMS,
    ageing_lag,
    bedding_sag,
    draw_effect_params,
    martensite_share,
    plc_reading,
    render,
)
from bench.plants.blind10_family import BLIND10_PLANTS
from bench.plants.blind10_rig import booster, held, hx711_load, ntc_celsius, ntc_counts, stroke_reading
from bench.plants.filters import lowpass
from bench.plants.properties import (
    assert_closed_loop_3_to_20_percent_wide,
    step_and_hold,
    triangles,
)
from bench.plants.visibility import rms

STILL_TEMP_C = 22.0


def _params(plant: str, seed: int = 3, peak: float = 4.0) -> dict[str, float]:
    return draw_params(plant, np.random.default_rng(seed), peak)


def _render(
    plant: str, params: dict[str, float], u: np.ndarray, dt: float, form: str, q: dict[str, float]
) -> np.ndarray:
    """``form`` on ``plant`` for the set pressure ``u`` with still columns."""
    base = BLIND10_CORES[plant](u, dt, params)
    return render(plant, params, u, dt, form, q, np.full_like(u, 2.0), np.full_like(u, STILL_TEMP_C), base)


# ---- rig ---------------------------------------------------------------------------------------------


def test_booster_exhausts_faster_than_it_fills_and_the_transmitter_holds() -> None:
    p = _params("check_valve_twin")
    dt = 0.001
    up = booster(np.concatenate([np.zeros(10), np.ones(400)]), dt, p)
    down = booster(np.concatenate([np.ones(10), np.zeros(400)]), dt, p)
    k63 = int(np.argmax(up >= 1.0 - np.exp(-1.0)))
    assert k63 * dt == pytest.approx(10 * dt + p["fill_tau_s"], abs=2 * dt)
    assert int(np.argmax(down <= np.exp(-1.0))) * dt == pytest.approx(
        10 * dt + p["exhaust_share"] * p["fill_tau_s"], abs=2 * dt
    )
    x = np.linspace(0.0, 1.0, 1000)
    h = held(x, dt, 0.012, 0.3)
    assert np.all(h <= x + 1e-12) and np.count_nonzero(np.diff(h)) <= 1.0 / 0.012 + 1


def test_ntc_round_trip_and_bridge_converter_stairs() -> None:
    p = _params("bristle_bladder")
    temps = np.linspace(10.0, 40.0, 61)
    assert np.allclose(ntc_celsius(ntc_counts(temps, p), p), temps, atol=1e-9)
    steps = np.diff(ntc_celsius(np.arange(300.0, 700.0), p))
    assert np.all(steps < 0.0) and np.ptp(steps) > 0.1 * abs(float(np.mean(steps)))  # an uneven step
    dt = 1.0 / 264.0
    t = np.arange(int(5.0 / dt)) * dt
    load = hx711_load(2.0 + np.sin(t), dt, p, np.random.default_rng(1))
    assert np.count_nonzero(np.diff(load)) <= 5.0 * p["hx711_sps"] + 1
    assert rms(load - (2.0 + np.sin(t - 1.0 / p["hx711_sps"]))) < 0.15  # one conversion late at most


def test_stroke_reading_adds_only_small_static_and_speed_errors() -> None:
    p = _params("overcentre_latch")
    dt = 0.005
    x = np.linspace(0.0, p["stroke_mm"], 2000)
    err = stroke_reading(x, dt, p) - x
    assert np.max(np.abs(err)) < 0.08 and rms(err) > 0.001


# ---- cores ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", BLIND10_PLANTS)
def test_force_balance_is_solved_and_monotone(plant: str) -> None:
    p = _params(plant, seed=4)
    v = np.linspace(0.0, 1.2, 400)
    e = solve_strain(v, p, {})
    ones, zero = np.ones_like(v), np.zeros_like(v)
    moving = e > 0.0
    assert np.all(np.abs(residual_n(e[moving], v[moving], p, ones[moving], ones[moving], zero[moving])) < 0.01)
    assert np.all(np.diff(e) >= 0.0) and e[0] == 0.0  # lifts off above a pressure, then rises
    one = np.array([1.0])
    twin = one - p["fill_crack_share"] if plant == "check_valve_twin" else None  # the second muscle at the peak
    assert solve_strain(one, p, {}, v2=twin)[0] * p["length_mm"] == pytest.approx(p["stroke_mm"], rel=1e-4)
    assert static_stroke(one, p, {})[0] <= p["stroke_mm"] + 1e-6
    grid = np.linspace(0.0, p["top_strain"], 50)
    assert np.all(np.diff(bladder_n(grid, p)) > 0.0) and bladder_n(np.array([p["top_strain"]]), p)[0] == pytest.approx(
        p["bladder_top_n"], rel=1e-3
    )
    assert np.all(stiffness_n_mm(v, e * p["length_mm"], p) > 0.0)


def test_bristles_snap_and_rebond_so_loops_never_repeat_exactly() -> None:
    p = _params("bristle_bladder", seed=5)
    dt = 0.01
    u = triangles(p["peak"], dt, 20.0, 4)
    y = BLIND10_CORES["bristle_bladder"](u, dt, p)
    per = int(20.0 / dt)
    last, before = y[-per:], y[-2 * per : -per]
    assert 0.0 < np.max(np.abs(last - before)) < 0.05 * np.ptp(last)  # close, not identical
    jumps = np.abs(np.diff(y[-per:]))
    assert np.max(jumps) > 5.0 * np.median(jumps)  # saw-teeth where bonds snap


def test_crossings_slip_in_avalanches_of_many_sizes() -> None:
    p = _params("avalanche_crossings", seed=6)
    x0 = np.linspace(0.0, 3.0 * p["stroke_mm"], 30000)
    f = ofc_force(x0, np.full_like(x0, 1e9), p)  # a stiff muscle: the ring driven at a set stroke
    drops = -np.diff(f)
    drops = drops[drops > 0.0]
    n = int(p["crossings"])
    assert drops.size > 20 and np.max(drops) > 3.0 * np.median(drops)  # small and large avalanches
    assert np.max(np.abs(f)) <= n * p["crossing_n"] * (1.0 + p["threshold_spread"]) + 1e-6


def test_check_valves_make_an_asymmetric_play_that_traps_pressure() -> None:
    p = _params("check_valve_twin", seed=7)
    v = np.concatenate([np.linspace(0.0, 1.0, 500), np.linspace(1.0, 0.0, 500), np.zeros(50)])
    q = check_valve_pressure(v, p)
    assert np.all(q >= v - p["fill_crack_share"] - 1e-12) and np.all(q <= v + p["vent_crack_share"] + 1e-12)
    assert q[499] == pytest.approx(1.0 - p["fill_crack_share"]) and q[-1] == pytest.approx(p["vent_crack_share"])
    top = int(np.argmax(v))
    held_until = top + int(np.argmax(q[top:] < q[top]))
    assert v[top] - v[held_until] == pytest.approx(p["fill_crack_share"] + p["vent_crack_share"], abs=0.005)


def test_latch_snaps_up_and_down_at_different_pressures() -> None:
    p = _params("overcentre_latch", seed=8)
    v = np.concatenate([np.linspace(0.0, 1.0, 4001), np.linspace(1.0, 0.0, 4001)[1:]])
    y = BLIND10_DRIVES["overcentre_latch"](v, 0.01, p, {})
    jumps = np.diff(y)
    up, down = int(np.argmax(jumps)), int(np.argmin(jumps))
    assert jumps[up] > 0.03 * p["stroke_mm"] and -jumps[down] > 0.03 * p["stroke_mm"]  # one snap each way
    assert v[up] > v[down] and up < 4000 < down
    assert overcentre_push_n(p["latch_x_mm"] + 1.0, p) > 0.0 > overcentre_push_n(p["latch_x_mm"] - 1.0, p)
    assert overcentre_push_n(p["latch_x_mm"] + 2.0 * p["latch_l0_mm"], p) == 0.0  # the strut lets go


@pytest.mark.parametrize("core", list(BLIND10_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    settled = 0.04 if core in ("bristle_bladder", "avalanche_crossings") else 0.02  # random snaps
    assert_closed_loop_3_to_20_percent_wide(BLIND10_CORES[core], partial(draw_params, core), settled_share=settled)


@pytest.mark.parametrize("core", list(BLIND10_DRIVES))
def test_core_is_rate_independent_and_rises_with_the_pressure(core: str) -> None:
    params = _params(core, seed=9)
    v = np.concatenate([np.linspace(0.0, 1.0, 3001), np.linspace(1.0, 0.2, 2401)[1:], np.linspace(0.2, 0.8, 1801)[1:]])
    fine = BLIND10_DRIVES[core](v, 0.001, params, {})
    coarse = BLIND10_DRIVES[core](v[::15], 0.015, params, {})
    assert np.max(np.abs(coarse - fine[::15])) < 0.03 * np.ptp(fine)
    assert rms(coarse - fine[::15]) < 0.01 * np.ptp(fine)
    assert np.all(np.isfinite(fine)) and fine[3000] > fine[1500] > fine[0]
    assert fine[5400] < fine[4000] < fine[3000]


# ---- effects ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", BLIND10_PLANTS)
def test_forms_are_absent_in_none_and_the_inside_forms_use_the_core(plant: str) -> None:
    params = _params(plant, seed=10)
    dt = 1.0 / 128.0
    u = triangles(params["peak"], dt, 5.0, 6)
    base = BLIND10_CORES[plant](u, dt, params)
    off = _render(plant, params, u, dt, "none", {})
    assert np.array_equal(off, stroke_reading(base, dt, params))
    rng = np.random.default_rng(11)
    for effect, forms in BLIND10_FORMS.items():
        if effect in ("none", "load_dependence", "temperature_drift"):
            continue
        for form in forms:
            change = _render(plant, params, u, dt, form, draw_effect_params(effect, form, rng)) - off
            assert rms(change) > 0.001 * np.ptp(base), form
    assert set(INSIDE_FORMS) <= {f for forms in BLIND10_FORMS.values() for f in forms}
    assert PLAIN_FORMS == tuple(forms[0] for e, forms in BLIND10_FORMS.items() if e != "none")


@pytest.mark.parametrize("plant", ["check_valve_twin", "overcentre_latch"])
def test_creep_forms_keep_moving_in_a_hold(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.02, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND10_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i3, i6, i28 = (int(s / dt) for s in (3.0, 6.0, 28.0))
    assert abs(base[i28] - base[i6]) < 0.01 * span  # the core alone settles
    off = _render(plant, params, u, dt, "none", {})
    for form in BLIND10_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        on = _render(plant, params, u, dt, form, q)
        assert on[i6] - on[i3] > 0.005 * span and on[i28] - on[i6] > 0.002 * span, form  # still rising
        assert abs(on[i28] - off[i28]) < abs(on[i3] - off[i3]), form  # towards where the core went at once


def test_ageing_slows_the_creep_as_the_sleeve_ages() -> None:
    dt = 0.01
    q = {"tau0_s": 1.0, "ageing_s": 3.0, "ageing_mu": 1.0, "rejuvenate_share": 0.4}
    v = np.concatenate([np.zeros(10), np.ones(6000)])
    c = ageing_lag(v, dt, q)
    plain = lowpass(v, dt, 1.0)
    late = int(20.0 / dt)
    assert 1.0 - c[late] > 5.0 * (1.0 - plain[late])  # far slower than a fixed time constant
    small = np.concatenate([np.zeros(10), np.full(6000, 0.2)])
    assert ageing_lag(small, dt, q)[late] / 0.2 < c[late]  # a small change does not rejuvenate: slower still


@pytest.mark.parametrize("plant", ["bristle_bladder", "check_valve_twin"])
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND10_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in (triangles(peak, dt, 40.0, 2), triangles(peak, dt, 4.0, 20)):  # as long, ten times as fast
            sizes.append(rms(_render(plant, params, u, dt, form, q) - _render(plant, params, u, dt, "none", q)))
        assert sizes[1] > 2.0 * sizes[0], (form, sizes)


def test_dashpot_lags_by_its_time_constant_and_longer_when_soft() -> None:
    plant = "check_valve_twin"
    params = _params(plant, seed=12)
    dt = 0.001
    u = np.concatenate([np.zeros(100), np.full(1500, params["peak"])])
    q = {"tau_top_s": 0.02}
    on = _render(plant, params, u, dt, "linear_dashpot", q)
    off = _render(plant, params, u, dt, "none", q)
    gap = off - on
    assert np.max(gap) > 0.1 * np.ptp(off) and abs(gap[-1]) < 1e-3  # lags a step, then arrives
    top = float(stiffness_n_mm(np.array([1.0]), np.array([params["stroke_mm"]]), params)[0])
    low = float(stiffness_n_mm(np.array([0.3]), np.array([0.3 * params["stroke_mm"]]), params)[0])
    assert low < top  # the vented muscle is softer, so the lag is longer there


def test_dead_time_and_plc_scans() -> None:
    plant = "bristle_bladder"
    params = _params(plant, seed=13)
    dt = 1.0 / 352.0
    u = triangles(params["peak"], dt, 4.0, 3)
    off = _render(plant, params, u, dt, "none", {})
    k = 14
    on = _render(plant, params, u, dt, "supply_dead_time", {"dead_time_s": k * dt})
    assert rms(on[k + 200 :] - off[200:-k]) < 0.05 * rms(on - off)  # the same, 40 ms later (cable noise aside)
    t = np.arange(int(20.0 / dt), dtype=np.float64) * dt
    x = t.copy()
    q = {"scan_s": 0.01, "workload_growth": 2.0, "input_filter_s": 0.004, "busy_speed_share_s": 1.0}
    still = plc_reading(x, np.zeros_like(t), dt, 4.0, q)
    busy = plc_reading(x, 4.0 * t, dt, 4.0, q)  # the set pressure moving at a full range per second
    assert 0.014 < float(np.mean(x - still)) < 0.025 and float(np.mean(x - busy)) > 2.0 * float(np.mean(x - still))


def test_load_forms_sag_linearly_and_bed_in_fast_but_recover_slowly() -> None:
    dt = 0.01
    load = np.concatenate([np.full(100, 2.0), np.full(500, 4.0), np.full(6000, 2.0)])
    q = {"bedding_mm_per_kg": 0.5, "bed_tau_s": 0.5, "recover_tau_s": 30.0}
    sag = bedding_sag(load, dt, q)
    assert sag[590] == pytest.approx(1.0, rel=0.01)  # beds in within a few time constants
    assert sag[600 + 1000] > 0.6  # 10 s after the load came off, most of it is still there
    assert np.all(sag >= 0.0) and sag[-1] < 0.2
    plant = "overcentre_latch"
    params = _params(plant, seed=14)
    u = triangles(params["peak"], dt, 10.0, 1)
    base = BLIND10_CORES[plant](u, dt, params)
    load_col = np.linspace(1.0, 3.0, u.size)
    temp = np.full_like(u, STILL_TEMP_C)
    lin = render(plant, params, u, dt, "linear_compliance", {"sag_mm_per_kg": 0.4}, load_col, temp, base)
    off = render(plant, params, u, dt, "none", {}, load_col, temp, base)
    assert np.allclose(off - lin, 0.4 * (load_col - 1.0), atol=0.02)  # the reading's small errors aside


def test_temperature_forms_gain_and_nitinol_hysteresis() -> None:
    q = {"a_s_k": 0.3, "a_f_k": 3.0, "m_s_k": -0.3, "m_f_k": -3.0, "martensite0": 0.5}
    up_down = np.concatenate([np.linspace(0.0, 2.0, 200), np.linspace(2.0, -2.0, 400), np.linspace(-2.0, 0.0, 200)])
    xi = martensite_share(up_down, q)
    assert xi[0] == 0.5 and xi[199] < 0.5  # heating past A_s transforms to austenite
    assert xi[300] == pytest.approx(xi[199])  # cooling back inside the hysteresis changes nothing
    assert xi[599] > 0.5 and xi[-1] == pytest.approx(xi[599])  # past M_s it goes back, and stays on reheating
    plant = "bristle_bladder"
    params = _params(plant, seed=15)
    dt = 0.02
    u = triangles(params["peak"], dt, 10.0, 3)
    base = BLIND10_CORES[plant](u, dt, params)
    warm = STILL_TEMP_C + np.clip(np.arange(u.size) * dt - 5.0, 0.0, 5.0)
    load = np.full_like(u, 2.0)
    off = render(plant, params, u, dt, "none", {}, load, warm, base)
    gain = render(plant, params, u, dt, "linear_gain_tempco", {"gain_per_k": 0.01, "wall_tau_s": 5.0}, load, warm, base)
    late = slice(int(25.0 / dt), None)
    ratio = (gain[late] - off[late]) / np.clip(base[late], 1.0, None)
    assert np.median(ratio) == pytest.approx(0.05, rel=0.15)  # 1 %/K x 5 K, once the wall has warmed
    qn = draw_effect_params("temperature_drift", "nitinol_bias_spring", np.random.default_rng(2))
    spring = render(plant, params, u, dt, "nitinol_bias_spring", qn, load, warm, base)
    assert np.mean(spring[late] - off[late]) < -0.002 * np.ptp(base)  # the warm spring is stiffer: less stroke
