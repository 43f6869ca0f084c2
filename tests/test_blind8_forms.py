"""Physics of the tenth (blind8) plant family's forms, cores and rig; the diagnosis is never run here.

Each effect form's signature (the Bessel demodulator's group delay and the UART's held frames,
creep that keeps moving in a hold and recovers, the crimp re-crimping slower than it
straightened, rate forms that grow with speed, the dashpot viscous when slow and capped by its
air spring, the inerter ringing after a step, the Belleville stack degressive and the Bowden
sheath progressive, the cord's thermoelastic inversion, the drum scaling the whole extension),
each core's own physics (Ivshin-Pence boundaries, the bounding surface, Mindlin's backbone,
Fancher's envelopes) and loop (closed, 3-20 % wide, descending above ascending), and the rig's
converter and filters. A few CPU seconds in all.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from bench.plants.blind8_cores import (
    BLIND8_CORES,
    dafalias_popov_friction,
    draw_params,
    fancher_envelope_state,
    ivshin_pence_crystallinity,
    mindlin_friction,
)
from bench.plants.blind8_effects import (
    BLIND8_FORMS,
    air_dashpot_lag,
    belleville_deflection,
    bessel_demodulated,
    crimp_state,
    draw_effect_params,
    render,
    sheath_compression,
    uart_stream,
)
from bench.plants.blind8_family import BLIND8_PLANTS, BLIND8_RATES_HZ
from bench.plants.blind8_rig import anti_alias, sar_bit_error
from bench.plants.properties import (
    assert_closed_loop_3_to_20_percent_wide,
    slow_and_fast_triangles,
    step_and_hold,
)
from bench.plants.visibility import rms

STILL_TEMP_C = 22.0


def _render(
    plant: str, params: dict[str, float], u: np.ndarray, dt: float, form: str, q: dict[str, float]
) -> np.ndarray:
    """``form`` on ``plant`` for the set pressure ``u`` with still columns."""
    base = BLIND8_CORES[plant](u, dt, params)
    return render(params, u, dt, form, q, np.full_like(u, 2.0), np.full_like(u, STILL_TEMP_C), base)


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


@pytest.mark.parametrize("core", list(BLIND8_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND8_CORES[core], partial(draw_params, core))
