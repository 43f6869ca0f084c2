"""Physics of the eleventh (blind9) plant family's forms, cores and rig; the diagnosis is never run here.

Each effect form's signature (creep that keeps moving in a hold and recovers, the reptation and
Mittag-Leffler kernels, rate forms that grow with speed, the Bergstrom-Boyce network relaxing
in a hold, the payload ringing faster at high pressure, the line's acoustic dead time and its
volume-dependent lag, the One-Euro filter lagging less when fast, the force-length map, the
vented elongation only below the braid's engagement, softening and elongation with warmth),
each core's own physics (the muscle's force balance, the Graesser-Cozzarelli flag, the jamming
sleeve's confinement and critical state, Ogden-Roxburgh's max-memory, the breakaway bump), its
loop (closed, 3-20 % wide, descending above ascending) and rate independence, and the rig's
valves, filters and pot. A few CPU seconds in all.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest
from scipy.special import erfcx

from bench.plants.blind9_cores import (
    BLIND9_CORES,
    BLIND9_DRIVES,
    breakaway_force,
    draw_params,
    graesser_cozzarelli,
    jamming_force,
    ogden_roxburgh_eta,
    static_stroke,
    stiffness_n_mm,
)
from bench.plants.blind9_effects import (
    BLIND9_FORMS,
    INSIDE_FORMS,
    bergstrom_boyce_force,
    braid_gate,
    doi_edwards_relaxation,
    draw_effect_params,
    line_pressure,
    mittag_leffler_decay,
    one_euro,
    render,
    stiffened_payload,
)
from bench.plants.blind9_family import BLIND9_PLANTS
from bench.plants.blind9_rig import (
    carrier_ripple,
    duty,
    manifold_pressure,
    muscle_pressure,
    rc_filter,
    slew_limited,
    stroke_reading,
    wire_wound,
)
from bench.plants.properties import (
    assert_closed_loop_3_to_20_percent_wide,
    slow_and_fast_triangles,
    step_and_hold,
)
from bench.plants.visibility import rms

STILL_TEMP_C = 22.0


def _params(plant: str, seed: int = 3, peak: float = 4.0) -> dict[str, float]:
    return draw_params(plant, np.random.default_rng(seed), peak)


def _render(
    plant: str, params: dict[str, float], u: np.ndarray, dt: float, form: str, q: dict[str, float]
) -> np.ndarray:
    """``form`` on ``plant`` for the set pressure ``u`` with still columns."""
    base = BLIND9_CORES[plant](u, dt, params)
    return render(plant, params, u, dt, form, q, np.full_like(u, 2.0), np.full_like(u, STILL_TEMP_C), base)


# ---- rig ----------------------------------------------------------------------------------------


def test_valves_quantise_the_duty_and_the_ripple_stays_at_the_manifold() -> None:
    params = _params("jamming_sleeve")
    dt = 1.0 / 416.0
    t = np.arange(int(20.0 / dt)) * dt
    u = np.asarray(params["peak"] * t / 20.0, dtype=np.float64)
    d = duty(u, params)
    levels = 2.0 ** params["pwm_bits"]
    assert np.allclose(d * levels, np.round(d * levels)) and len(np.unique(d)) > 0.5 * levels
    ripple = carrier_ripple(d, dt, params)
    assert np.max(np.abs(ripple)) <= params["ripple_share"] * params["peak"] * (1.0 + 1e-9)
    assert np.all(ripple[(d == 0.0) | (d == 1.0)] == 0.0)
    mid = np.abs(d - 0.5) < 0.1
    assert np.max(np.abs(ripple[mid])) > 0.8 * params["ripple_share"] * params["peak"]  # largest at half duty
    assert np.allclose(manifold_pressure(u, dt, params) - muscle_pressure(u, dt, params), ripple, atol=1e-12)
    assert np.all(np.diff(muscle_pressure(u, dt, params)) >= -1e-12)  # the muscle's own pressure is smooth


def test_rc_filter_lags_a_ramp_by_its_time_constant_and_the_amplifier_slews() -> None:
    dt = 0.001
    t = np.asarray(np.arange(int(5.0 / dt)) * dt, dtype=np.float64)
    late = (t - rc_filter(t, dt, 4.0))[-10:]
    assert np.allclose(late, 1.0 / (2.0 * np.pi * 4.0), rtol=0.03)
    step = np.where(t < 1.0, 0.0, 2.0)
    slewed = slew_limited(step, dt, 10.0)
    assert np.max(np.abs(np.diff(slewed))) <= 10.0 * dt + 1e-12 and slewed[int(1.3 / dt)] == 2.0


def test_wire_wound_pot_steps_from_turn_to_turn() -> None:
    params = _params("mullins_bladder")
    pitch = params["pot_pitch_mm"]
    x = np.linspace(0.0, 200.0 * pitch, 20001)
    read = wire_wound(x, params)
    jumps = np.flatnonzero(np.diff(read) != 0.0)
    assert 195 <= jumps.size <= 201  # one step per turn
    assert np.max(np.abs(read - x)) <= (0.5 + params["pot_irregularity"]) * pitch + 1e-12
    assert np.allclose(np.diff(read)[jumps], pitch, atol=2.0 * params["pot_irregularity"] * pitch + 1e-12)


# ---- the muscle ---------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_force_balance_is_solved_and_monotone_where_physical(plant: str) -> None:
    params = _params(plant)
    v = np.linspace(0.0, 1.1, 1101)
    x = static_stroke(v, params)
    assert np.all(np.diff(x) >= -1e-12) and np.all(x[v <= params["contact_share"]] == 0.0)
    assert x[1000] == pytest.approx(params["stroke_mm"], rel=1e-6)  # the drawn stroke at the peak
    heavier = static_stroke(v, params, f_ext=np.full_like(v, 20.0))
    softer = static_stroke(v, params, rubber=np.full_like(v, 0.8))
    assert np.all(heavier <= x + 1e-12) and np.all(softer >= x - 1e-12) and np.any(softer > x)
    ok = (x > 1.0) & (x < 0.99 * (1.0 - math.sqrt(params["braid_b"] / params["braid_a"])) * params["length_mm"])
    push = 1.0  # N: the slope of the force balance predicts the stroke's answer to a small force
    moved = x - static_stroke(v, params, f_ext=np.full_like(v, push))
    assert np.allclose(moved[ok], push / stiffness_n_mm(v[ok], x[ok], params), rtol=0.02)


def test_graesser_cozzarelli_draws_a_superelastic_flag_rate_independently() -> None:
    params = _params("nitinol_flag_return", seed=5)
    up = np.linspace(params["wire_prestrain"], params["wire_prestrain"] + params["wire_span"], 2001)
    strain = np.concatenate([up, up[::-1][1:], up[1:], up[::-1][1:], up[1:], up[::-1][1:]])
    s = graesser_cozzarelli(strain, params)
    n = up.size
    load, unload = s[2 * n - 2 : 3 * n - 2], s[3 * n - 3 : 4 * n - 3][::-1]
    mid = (up > up[0] + 0.4 * params["wire_span"]) & (up < up[0] + 0.8 * params["wire_span"])
    assert np.all(load[mid] > unload[mid] + 0.3)  # the flag: a loading plateau above the unloading one
    assert abs(unload[0]) < 0.5 < load[-1]  # back to little stress at the start strain: superelastic
    assert np.all(np.diff(load) > -1e-9) and np.all(np.diff(unload) > -1e-9)
    third = s[4 * n - 4 : 5 * n - 4]
    assert np.max(np.abs(third - load)) < 1e-6 * np.ptp(load) + 1e-9  # the same flag every cycle
    coarse = graesser_cozzarelli(strain[::20], params)
    assert np.max(np.abs(coarse - s[::20])) < 0.02 * np.ptp(s)  # rate-independent: path, not time
    # its rate depends on its own output: the same strain step from two stresses moves them differently
    ds_low = graesser_cozzarelli(np.array([1.0, 1.05]), params)
    ds_high = graesser_cozzarelli(np.concatenate([np.linspace(0.3, 3.0, 300), [3.05]]), params)
    assert (ds_high[-1] - ds_high[-2]) < 0.5 * (ds_low[-1] - ds_low[-2])


def test_jamming_sleeve_yields_with_its_confinement_and_relaxes_to_its_critical_state() -> None:
    params = _params("jamming_sleeve", seed=6)
    x0 = np.linspace(0.0, params["stroke_mm"], 4001)
    n0, fj, mu_c = params["jam_floor"], params["jam_force_n"], params["jam_mu_c"]
    high = jamming_force(x0, np.ones_like(x0), params)
    low = jamming_force(x0, np.full_like(x0, 0.3), params)
    assert high[-1] == pytest.approx(mu_c * (n0 + 1.0) * fj, rel=0.02)  # critical state at N = n0 + 1
    assert low[-1] == pytest.approx(mu_c * (n0 + 0.3) * fj, rel=0.02)  # Mohr-Coulomb: ~ N
    first = jamming_force(x0[:200], np.ones(200), params)  # still elastic: stiffness ~ N^(1/3)
    softer = jamming_force(x0[:200], np.full(200, 0.3), params)
    ratio = ((n0 + 1.0) / (n0 + 0.3)) ** (1.0 / 3.0)
    assert first[5] / softer[5] == pytest.approx(ratio, rel=1e-6)
    # minor loops are not congruent: the same stroke cycle at two confinements
    cycle = np.concatenate([x0[:2001], x0[:2001][::-1], x0[:2001]])
    loop_high = jamming_force(cycle, np.ones_like(cycle), params)
    loop_low = jamming_force(cycle, np.full_like(cycle, 0.3), params)
    assert np.ptp(loop_high[2001:]) > 1.5 * np.ptp(loop_low[2001:])


def test_ogden_roxburgh_softens_below_the_maximum_only() -> None:
    params = _params("mullins_bladder", seed=7)
    w = np.concatenate([np.linspace(0.0, 0.6, 301), np.linspace(0.6, 0.1, 251)[1:], np.linspace(0.1, 1.0, 451)[1:]])
    eta = ogden_roxburgh_eta(w, params)
    assert np.all(eta[:301] == 1.0)  # virgin loading: no softening
    assert np.all(eta[301:550] < 1.0) and eta[549] >= 1.0 - 1.0 / params["or_r"]
    reload = eta[550:800]
    back = np.interp(w[550:800], w[300:550][::-1], eta[300:550][::-1])
    assert np.allclose(reload[w[550:800] <= 0.6], back[w[550:800] <= 0.6], atol=1e-4)  # reloads on the unloading curve
    assert np.all(eta[w.size - 100 :] == 1.0)  # beyond the old maximum: virgin again


def test_breakaway_crossings_bump_after_each_reversal_rate_independently() -> None:
    params = _params("breakaway_crossings", seed=8)
    s = params["stroke_mm"]
    x0 = np.concatenate([np.linspace(0.0, s, 3001), np.linspace(s, 0.0, 3001)[1:]])
    f = breakaway_force(x0, params)
    down = f[3000:]
    assert np.min(down) < down[-1] - 0.05 * params["breakaway_n"]  # past its breakaway the force eases off
    assert down[-1] == pytest.approx(-params["kinetic_ratio"] * params["breakaway_n"], rel=1e-6)  # all sliding
    assert np.max(np.abs(f)) <= params["breakaway_n"] * (1.0 + 1e-9)
    coarse = breakaway_force(x0[::10], params)
    assert np.max(np.abs(coarse - f[::10])) < 0.05 * params["breakaway_n"]  # path, not time


@pytest.mark.parametrize("core", list(BLIND9_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND9_CORES[core], partial(draw_params, core))


@pytest.mark.parametrize("core", list(BLIND9_DRIVES))
def test_core_is_rate_independent_and_rises_with_the_pressure(core: str) -> None:
    params = _params(core, seed=9)
    v = np.concatenate([np.linspace(0.0, 1.0, 3001), np.linspace(1.0, 0.2, 2401)[1:], np.linspace(0.2, 0.8, 1801)[1:]])
    fine = BLIND9_DRIVES[core](v, 0.001, params, {})
    coarse = BLIND9_DRIVES[core](v[::15], 0.015, params, {})
    assert np.max(np.abs(coarse - fine[::15])) < 0.01 * np.ptp(fine)
    assert np.all(np.diff(fine[:3001]) > -0.002 * np.ptp(fine)) and np.all(np.isfinite(fine))
    assert np.all(np.diff(fine[3000:5400]) < 0.002 * np.ptp(fine))


# ---- effects ------------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_forms_are_absent_in_none_and_the_inside_forms_use_the_core(plant: str) -> None:
    params = _params(plant, seed=10)
    dt = 1.0 / 112.0
    u = step_and_hold(params["peak"], dt)
    base = BLIND9_CORES[plant](u, dt, params)
    off = _render(plant, params, u, dt, "none", {})
    assert np.array_equal(off, stroke_reading(base, u, dt, params))
    rng = np.random.default_rng(11)
    for effect, forms in BLIND9_FORMS.items():
        if effect in ("none", "load_dependence", "temperature_drift"):
            continue
        for form in forms:
            change = _render(plant, params, u, dt, form, draw_effect_params(effect, form, rng)) - off
            assert rms(change) > 0.001 * np.ptp(base), form
    assert set(INSIDE_FORMS) <= {f for forms in BLIND9_FORMS.values() for f in forms}


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_creep_forms_keep_moving_in_a_hold_and_the_core_alone_settles(plant: str) -> None:
    rng = np.random.default_rng(5)
    dt, peak = 0.02, 4.0
    params = draw_params(plant, rng, peak)
    u = step_and_hold(peak, dt)
    base = BLIND9_CORES[plant](u, dt, params)
    span = float(np.ptp(base))
    i10, i28, i40, i58 = (int(s / dt) for s in (10.0, 28.0, 40.0, 58.0))
    assert abs(base[i28] - base[i10]) < 0.01 * span and abs(base[i58] - base[i40]) < 0.01 * span  # it settles
    off = _render(plant, params, u, dt, "none", {})
    for form in BLIND9_FORMS["creep"]:
        q = draw_effect_params("creep", form, rng)
        change = _render(plant, params, u, dt, form, q) - off
        assert change[i28] > change[i10] + 0.002 * span > 0.002 * span, form  # still growing 8-26 s after the step
        assert change[i58] < change[i40] and min(change[i40], change[i58]) < change[i28], form  # recovering


def test_reptation_and_mittag_leffler_kernels() -> None:
    t = np.linspace(0.0, 100.0, 2001)
    g = doi_edwards_relaxation(t, 10.0)
    assert g[0] == pytest.approx(1.0) and np.all(np.diff(g) < 0.0)
    late = t > 15.0  # the slowest mode alone: 8 / pi^2 exp(-t / tau_d)
    modes = np.sum(1.0 / (2.0 * np.arange(25) + 1.0) ** 2)  # G(0) before scaling, over 8 / pi^2
    assert np.allclose(g[late], np.exp(-t[late] / 10.0) / modes, rtol=1e-6)
    s = np.logspace(-4.0, 3.0, 50)  # E_1/2(-sqrt s) = exp(s) erfc(sqrt s)
    assert np.allclose(mittag_leffler_decay(s, 0.5), erfcx(np.sqrt(s)), rtol=2e-3)
    ml = mittag_leffler_decay(np.linspace(0.0, 50.0, 500), 0.4)
    assert ml[0] == 1.0 and np.all(np.diff(ml) < 0.0) and ml[-1] > 0.05  # a power-law tail: slow


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_rate_forms_grow_with_the_input_speed(plant: str) -> None:
    rng = np.random.default_rng(6)
    dt, peak = 0.01, 4.0
    params = draw_params(plant, rng, peak)
    for form in BLIND9_FORMS["rate_dependence"]:
        q = draw_effect_params("rate_dependence", form, rng)
        sizes = []
        for u in slow_and_fast_triangles(peak, dt, (40.0, 4.0)):
            sizes.append(rms(_render(plant, params, u, dt, form, q) - _render(plant, params, u, dt, "none", q)))
        assert sizes[1] > 2.0 * sizes[0], (form, sizes)


def test_bergstrom_boyce_network_relaxes_in_a_hold_faster_when_loaded_harder() -> None:
    dt = 0.002
    t = np.arange(int(10.0 / dt)) * dt
    q = {"bb_tau_s": 0.3, "bb_power": 1.6, "bb_xi": 0.3}
    e = np.clip(t / 0.2, 0.0, 1.0)  # a fast stretch, then held
    phi = bergstrom_boyce_force(e, dt, q)
    assert 0.0 < phi[int(0.2 / dt)] < 1.0 and phi[-1] < 0.05 * phi[int(0.2 / dt)]  # flows away in a hold
    slow = bergstrom_boyce_force(np.clip(t / 5.0, 0.0, 1.0), dt, q)
    assert np.max(slow) < 0.5 * np.max(phi)  # a slower stretch leaves less in the network


def test_payload_rings_faster_at_high_pressure() -> None:
    dt = 0.001
    t = np.arange(int(3.0 / dt)) * dt
    x = np.where(t < 0.5, 0.0, 1.0)
    q = {"mass_s2": (2.0 * np.pi * 4.0) ** -2, "stiffness_floor": 0.25, "payload_zeta": 0.05}

    def first_peak(v: float) -> float:
        y = stiffened_payload(x, np.full_like(t, v), dt, q)
        return float(t[int(np.argmax(y))] - 0.5)

    assert first_peak(1.0) == pytest.approx(1.0 / (2.0 * 4.0), rel=0.05)  # half a period at 4 Hz
    assert first_peak(0.1) > 1.8 * first_peak(1.0)  # softer muscle, lower frequency


def test_line_delays_by_its_acoustic_time_and_lags_more_when_full() -> None:
    dt = 0.0005
    t = np.arange(int(2.0 / dt)) * dt
    q = {"line_m": 6.86, "tau_per_m_s": 0.004, "volume_growth": 1.0}  # 20 ms of dead time
    for level in (0.2, 1.0):
        v = np.where(t < 0.5, 0.0, level)
        p = line_pressure(v, dt, q)
        assert np.all(p[t < 0.5 + 0.02 - dt] == 0.0) and p[int(0.53 / dt)] > 0.0
    rise = []
    for level in (0.2, 1.0):
        p = line_pressure(np.where(t < 0.5, 0.0, level), dt, q) / level
        rise.append(float(t[np.argmax(p > 0.63)]))
    assert rise[1] > rise[0] + 0.005  # a fuller muscle fills slower


def test_one_euro_lags_a_slow_ramp_longer_than_a_fast_one_and_settles() -> None:
    dt = 0.004
    t = np.arange(int(20.0 / dt)) * dt
    q = {"min_tau_s": 0.06, "speed_half_mm_s": 10.0, "d_cutoff_hz": 1.0}
    lags = []
    for speed in (1.0, 40.0):
        x = np.asarray(np.minimum(speed * t, 400.0), dtype=np.float64)
        y = one_euro(x, dt, q)
        lags.append(float(np.mean((x - y)[(t > 2.0) & (speed * t < 380.0)])) / speed)
    assert lags[0] > 2.0 * lags[1] > 0.0 and lags[0] == pytest.approx(0.06 / 1.1, rel=0.1)
    held = one_euro(np.where(t < 5.0, 0.0, 3.0), dt, q)
    assert held[-1] == pytest.approx(3.0, abs=1e-6)


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_load_forms_lower_the_stroke_where_they_should(plant: str) -> None:
    params = _params(plant, seed=12)
    params.update(rail_dip=0.0)
    dt = 0.02
    t = np.arange(int(60.0 / dt)) * dt
    u = np.asarray(params["peak"] * 0.5 * (1.0 - np.cos(2.0 * np.pi * t / 20.0)), dtype=np.float64)
    base = BLIND9_CORES[plant](u, dt, params)
    heavy, still, temp = np.where(t < 5.0, 2.0, 3.0), np.full_like(t, 2.0), np.full_like(t, STILL_TEMP_C)
    q = {"lever_ratio": 4.0}
    change = render(plant, params, u, dt, "force_length_map", q, heavy, temp, base)
    change -= render(plant, params, u, dt, "force_length_map", q, still, temp, base)
    late = t > 25.0
    assert np.mean(change[late]) < -0.05  # a heavier payload: less contraction
    qv = {"elong_mm": 1.5, "elong_soft_kg": 1.0, "engage_share": 0.3}
    change = render(plant, params, u, dt, "vented_elongation", qv, heavy, temp, base)
    change -= render(plant, params, u, dt, "vented_elongation", qv, still, temp, base)
    v = muscle_pressure(u, dt, params) / params["peak"]
    engaged = late & (v > 0.35)
    assert np.max(np.abs(change[engaged])) < 0.02  # mm: the braid carries it (the filters' tail)
    vented = late & (v < 0.02)
    expected = -1.5 * (np.log1p(3.0) - np.log1p(2.0)) * braid_gate(v[vented], qv)  # a stiffening stretch
    assert np.allclose(change[vented], expected, atol=0.03 * abs(expected).max() + 2.0 * params["pot_pitch_mm"])


@pytest.mark.parametrize("plant", BLIND9_PLANTS)
def test_warmth_softens_the_bladder_and_lengthens_the_muscle(plant: str) -> None:
    params = _params(plant, seed=13)
    params.update(rail_dip=0.0)
    dt = 0.02
    t = np.arange(int(120.0 / dt)) * dt
    u = np.asarray(params["peak"] * (0.1 + 0.8 * 0.5 * (1.0 - np.cos(2.0 * np.pi * t / 20.0))), dtype=np.float64)
    base = BLIND9_CORES[plant](u, dt, params)
    load, still, warm = np.full_like(t, 2.0), np.full_like(t, 20.0), np.where(t < 10.0, 20.0, 25.0)
    qs = {"softening_per_k": 0.02, "bladder_tau_s": 5.0}
    change = render(plant, params, u, dt, "bladder_modulus_softening", qs, load, warm, base)
    change -= render(plant, params, u, dt, "bladder_modulus_softening", qs, load, still, base)
    late = t > 60.0
    assert np.mean(change[late]) > 0.05  # softer rubber: more contraction
    qe = {"expansion_per_k": 5e-4, "thermal_tau_s": 10.0, "braid_share": 0.5}
    change = render(plant, params, u, dt, "thermal_elongation", qe, load, warm, base)
    change -= render(plant, params, u, dt, "thermal_elongation", qe, load, still, base)
    v = muscle_pressure(u, dt, params) / params["peak"]
    low, high = late & (v < 0.2), late & (v > 0.8)
    full = 5e-4 * params["length_mm"] * 5.0
    assert np.mean(change[low]) < -0.75 * full and np.mean(change[low]) < np.mean(change[high]) < 0.0
