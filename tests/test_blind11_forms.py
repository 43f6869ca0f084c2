"""Physics of the thirteenth (blind11) plant family's forms, cores and rig; the diagnosis is never run here.

Each core's own physics against a derivation or a limiting case (the extensible braid's balance;
the run-in plays reducing to a Prandtl-Ishlinskii set without wear, narrowing with use and widening
after a vent; the wrapped strap's virgin and reversal yields in closed form and its wiping out;
the contacts' friction vanishing below the first onset and bounded by their Hertz limits; the
Menegotto-Pinto branch leaving a reversal along the elastic stiffness and bending to its
asymptote), its loop (closed, 3-20 % wide, descending above ascending) and rate independence;
each effect form's signature (the Prony solid's instantaneous and relaxed limits, the brake that
leaves slow moves alone, creep that keeps moving in a hold and returns to the plant, reverse
creep from the cover's gap, a delay of whole frames, the jitter buffer's delay never below the
transit, the tackle's sag ``F / K``, the column's amplification, the lift-off shift, the glass
transition growing with the pressure); the rig's regulator, filters, laser sensor and
converters, and the guy wire's decoy. A few CPU seconds in all.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np
import pytest

from bench.plants.blind11_cores import (
    BLIND11_CORES,
    BLIND11_DRIVES,
    RUNIN_PLAYS,
    MenegottoPinto,
    StrapProfile,
    balance_stiffness,
    contact_friction,
    draw_params,
    muscle_strain,
    normalised_pressure,
    pull_coefficients,
    runin_pressure,
    spring_k1,
    static_stroke,
)
from bench.plants.blind11_effects import (
    BLIND11_FORMS,
    INSIDE_FORMS,
    PLAIN_FORMS,
    column_shortening,
    cover_gap_pressure,
    draw_effect_params,
    fibre_compliance,
    governed_stroke,
    jitter_delay_s,
    kelvin_spectrum,
    load_thermal_guy_wire,
    prony_maxwell,
    render,
)
from bench.plants.blind11_rig import (
    boxcar,
    load_reading,
    regulator_pressure,
    second_order,
    stroke_reading,
    thermocouple_reading,
    triangulation_error,
)
from bench.plants.filters import resonance
from bench.plants.properties import assert_closed_loop_3_to_20_percent_wide, step_and_hold, triangles
from bench.plants.visibility import rms

STILL_TEMP_C = 22.0


def _params(plant: str, seed: int = 3, peak: float = 4.0) -> dict[str, float]:
    return draw_params(plant, np.random.default_rng(seed), peak)


def _render(
    plant: str, params: dict[str, float], u: np.ndarray, dt: float, form: str, q: dict[str, float]
) -> np.ndarray:
    """``form`` on ``plant`` for the set pressure ``u`` with still columns."""
    base = BLIND11_CORES[plant](u, dt, params)
    return render(plant, params, u, dt, form, q, np.full_like(u, 2.0), np.full_like(u, STILL_TEMP_C), base)


# ---- rig -------------------------------------------------------------------------------------------------


def test_regulator_stops_in_its_dead_band_and_slews() -> None:
    p = _params("runin_crossings")
    dt = 0.001
    u = np.concatenate([np.zeros(10), np.full(1500, p["peak"]), np.full(1500, p["peak"] - 0.5 * p["deadband_bar"])])
    out = regulator_pressure(u, dt, p)
    assert np.max(np.diff(out)) <= p["slew_bar_s"] * dt * (1.0 + 1e-9)  # the flow saturates
    assert out[1509] == pytest.approx(p["peak"] - p["deadband_bar"], abs=1e-6)  # short of the set pressure
    assert np.all(out[1510:] == out[1509])  # a move inside the band opens no port
    x = np.random.default_rng(1).normal(size=3000).cumsum()
    assert np.allclose(second_order(x, 1.0 / 236.0, 30.0, 0.1), resonance(x, 1.0 / 236.0, 30.0, 0.1), atol=1e-9)


def test_laser_sensor_errors_and_averaging() -> None:
    p = {**_params("wire_rope_return"), "speckle_mm": 0.0}
    ends = np.array([0.0, 0.5, 1.0]) * p["range_mm"] - p["standoff_mm"]
    assert np.allclose(triangulation_error(ends, p), 0.0, atol=1e-12)  # zero at its ends and middle
    extreme = (0.5 - 0.5 / math.sqrt(3.0)) * p["range_mm"] - p["standoff_mm"]
    assert abs(float(triangulation_error(np.array([extreme]), p)[0])) == pytest.approx(abs(p["lin_mm"]))
    p = _params("wire_rope_return")
    x = np.linspace(0.0, 40.0, 40001)
    speckle = triangulation_error(x, p) - triangulation_error(x, {**p, "speckle_mm": 0.0})
    assert rms(speckle) == pytest.approx(p["speckle_mm"], rel=0.5)
    dt, w = 1.0 / 396.0, p["avg_window_s"]
    t = np.arange(2000, dtype=np.float64) * dt
    ramp = 20.0 * t  # mm: a boxcar lags a ramp by half its window
    assert np.allclose(boxcar(ramp, dt, w)[50:], 20.0 * (t[50:] - 0.5 * w), atol=1e-9)


def test_thermocouple_and_load_converters() -> None:
    p = _params("contact_births")
    dt = 1.0 / 142.0
    t = np.arange(int(20.0 / dt), dtype=np.float64) * dt
    temp = thermocouple_reading(22.0 + 0.3 * t, dt, p, np.random.default_rng(2))
    assert np.allclose(temp / 0.25, np.round(temp / 0.25))
    changes = np.flatnonzero(np.diff(temp))
    assert np.min(np.diff(changes)) * dt >= 0.1 - 1.5 * dt  # at most one new value per conversion
    late = t > 10.0  # behind the ramp by the junction's lag (and the held conversion), off by the CJ error
    lag = np.mean(22.0 + 0.3 * t[late] + p["cj_error_k"] - temp[late]) / 0.3
    assert p["junction_tau_s"] < lag < p["junction_tau_s"] + 0.2
    load = load_reading(np.full(t.size, 4.0), dt, p, np.random.default_rng(3))
    assert np.allclose(load / p["load_step_kg"], np.round(load / p["load_step_kg"]))
    assert rms(load - 4.0) < 2.0 * (p["hum_kg"] + p["load_noise_kg"] + p["load_step_kg"])


def test_guy_wire_load_falls_as_the_wire_warms() -> None:
    """The decoy: the same turnbuckle draws, a wire warmed by 5 K, reads ``E A alpha`` (0.24-0.49
    kg/K) less once its lag has passed."""
    dt = 0.1
    t = np.arange(int(400.0 / dt), dtype=np.float64) * dt
    cold = load_thermal_guy_wire(t, np.random.default_rng(4), np.full(t.size, 20.0))
    warm = load_thermal_guy_wire(t, np.random.default_rng(4), np.where(t > 10.0, 25.0, 20.0))
    per_k = (cold[-1] - warm[-1]) / 5.0
    assert 0.24 <= per_k <= 0.5 and np.all(cold - warm >= -1e-12)


# ---- the muscle ------------------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", ["runin_crossings", "contact_births"])
def test_extensible_braid_balance_is_solved(plant: str) -> None:
    p = _params(plant, seed=4)
    v = np.linspace(0.0, 1.1, 300)
    vt, c2, c0 = pull_coefficients(v, p, {})
    hold = p["weight_n"] + 5.0
    e = muscle_strain(c2, c0, spring_k1(p), hold)
    up = e > 0.0
    assert np.allclose(c2[up] * (1.0 - e[up]) ** 2 - c0[up], hold + spring_k1(p) * e[up], rtol=1e-9)
    assert np.all(c2[~up] - c0[~up] <= hold + 1e-9) and np.all(np.diff(e) >= 0.0)  # lifts off, then rises
    assert static_stroke(np.array([1.0]), p, {})[0] == pytest.approx(p["stroke_mm"], rel=1e-9)
    stretchier = static_stroke(v, p, {"fibre": np.full_like(v, 2.0)})
    assert np.all(stretchier <= static_stroke(v, p, {}) + 1e-12)  # longer fibres: less contraction
    x = static_stroke(v, p, {})
    h = 1e-4
    surplus = [
        c2[up] * (1.0 - (x[up] + s) / p["length_mm"]) ** 2 - c0[up] - spring_k1(p) * (x[up] + s) / p["length_mm"]
        for s in (-h, h)
    ]
    assert np.allclose((surplus[0] - surplus[1]) / (2.0 * h), balance_stiffness(v[up], x[up], p), rtol=1e-6)


# ---- cores -----------------------------------------------------------------------------------------------


def _plays(v: np.ndarray, radius: float) -> np.ndarray:
    out, a = np.empty_like(v), float(v[0])
    for i, vi in enumerate(v.tolist()):
        a = min(max(a, vi - radius), vi + radius)
        out[i] = a
    return out


def test_runin_reduces_to_a_prandtl_ishlinskii_set_and_narrows_with_use() -> None:
    p = {**_params("runin_crossings", seed=5), "runin_gain": 0.0}
    v = np.concatenate([np.linspace(0.0, 0.9, 400), np.linspace(0.9, 0.3, 300), np.linspace(0.3, 0.7, 200)])
    expected = v - sum(p[f"play_w{j}"] * (v - _plays(v, p[f"play_r{j}"])) for j in range(RUNIN_PLAYS))
    assert np.allclose(runin_pressure(v, p), expected, atol=1e-12)  # no wear: Prandtl-Ishlinskii
    p = _params("runin_crossings", seed=5)
    cycle = np.concatenate([np.linspace(0.15, 0.95, 400), np.linspace(0.95, 0.15, 400)])
    vent = np.concatenate([np.linspace(0.15, 0.0, 50), np.linspace(0.0, 0.15, 50)])
    v = np.concatenate([cycle, cycle, cycle, vent, cycle])

    def width(k: int) -> float:  # the loop's width in pressure share at mid-range, cycle starting at ``k``
        out = runin_pressure(v, p)[k : k + 800]
        return float(
            np.interp(0.55, v[k + 400 : k + 800][::-1], out[400:][::-1]) - np.interp(0.55, v[k : k + 400], out[:400])
        )

    first, third, after = width(0), width(1600), width(2500)
    assert first > third > 0.0 and after > third  # runs in, re-seats at the vent
    assert np.max(np.abs(runin_pressure(v, p) - v)) <= (1.0 + p["runin_gain"]) * sum(
        p[f"play_w{j}"] * p[f"play_r{j}"] for j in range(RUNIN_PLAYS)
    )


def test_wrapped_strap_yields_as_derived_and_wipes_out() -> None:
    """Virgin: ``u = s T0 (tau - 1 - ln tau) / mu``; unloading from ``Tm``: ``u_m - s (sqrt(Tm) -
    sqrt(T))^2 / mu``; reloading to ``Tm`` comes back to ``u_m`` and goes on along the virgin curve."""
    t0, mu, s = 20.0, 0.35, 0.01
    strap = StrapProfile(t0, mu, s)
    for tension in np.linspace(t0, 5.0 * t0, 40)[1:].tolist():
        strap.move(tension)
    tau = 5.0
    u_max, slope = strap.yield_mm(5.0 * t0)
    assert u_max == pytest.approx(s * t0 * (tau - 1.0 - math.log(tau)) / mu, rel=1e-12)
    assert slope == pytest.approx(s * (1.0 - 1.0 / tau) / mu, rel=1e-9)  # du/dT = s (1 - T0 / T) / mu
    strap.turn()
    assert strap.yield_mm(5.0 * t0)[1] == 0.0  # no give just after a reversal
    for tension in (4.0 * t0, 3.0 * t0, 2.0 * t0):
        strap.move(tension)
        assert strap.yield_mm(tension)[0] == pytest.approx(
            u_max - s * (math.sqrt(5.0 * t0) - math.sqrt(tension)) ** 2 / mu
        )
    strap.turn()
    strap.move(3.5 * t0)
    strap.turn()
    strap.move(2.5 * t0)  # a minor loop inside
    strap.turn()
    strap.move(5.0 * t0)
    assert strap.yield_mm(5.0 * t0)[0] == pytest.approx(u_max, rel=1e-12)  # return-point memory
    strap.move(6.0 * t0)
    assert strap.yield_mm(6.0 * t0)[0] == pytest.approx(s * t0 * (6.0 - 1.0 - math.log(6.0)) / mu, rel=1e-12)


def test_contacts_vanish_below_their_first_onset_and_keep_their_hertz_limits() -> None:
    p = _params("contact_births", seed=6)
    below = np.concatenate([np.linspace(0.0, 0.9 * p["onset0"], 200)] * 3)
    f, x = contact_friction(below, p, {})
    assert np.all(f == 0.0) and np.allclose(x, static_stroke(below, p, {}))
    v = np.concatenate([np.linspace(0.0, 1.0, 600), np.linspace(1.0, 0.3, 400), np.linspace(0.3, 0.8, 300)])
    f, x = contact_friction(v, p, {})
    onsets = np.array([p[f"onset{j}"] for j in range(6)])
    bound = p["contact_limit_n"] * np.sum(np.clip(np.subtract.outer(v, onsets), 0.0, None) ** 1.5, axis=1)
    assert np.all(np.abs(f) <= bound + 1e-9) and np.max(np.abs(f)) > 0.3 * np.max(bound)
    assert np.allclose(x, static_stroke(v, p, {}, f), atol=1e-9)  # the stroke is the balance's with that friction
    back = np.concatenate([v, np.linspace(0.8, 0.0, 300)])  # and fades to nothing as the contacts leave
    assert contact_friction(back, p, {})[0][-1] == 0.0


def test_menegotto_pinto_branches_leave_elastically_and_bend_to_their_asymptote() -> None:
    e0, b, fy = 5.0, 0.4, 30.0
    iso = MenegottoPinto(e0, b, fy, 18.0, 16.0, 0.15)
    h = 1e-6
    assert iso.force(h)[0] / h == pytest.approx(e0, rel=1e-3)  # the virgin branch leaves elastically
    far = 40.0
    assert iso.force(far)[0] == pytest.approx(b * e0 * far + (1.0 - b) * fy, rel=1e-3)  # onto the asymptote
    r_top, _ = iso.force(far)
    iso.reach(far)
    iso.turn(far)
    assert (iso.force(far - h)[0] - r_top) / -h == pytest.approx(e0, rel=1e-3)
    assert iso.rc < 18.0 - 0.5 * 16.0  # a big excursion rounds the next branch (Bauschinger)
    gaps = [iso.force(far - d)[0] - (b * e0 * (far - d) - (1.0 - b) * fy) for d in (10.0, 20.0, 30.0, 60.0)]
    assert np.all(np.diff(gaps) < 0.0) and 0.0 < gaps[2] < 0.1 * 2.0 * (1.0 - b) * fy  # towards the lower asymptote


@pytest.mark.parametrize("core", list(BLIND11_CORES))
def test_core_draws_a_closed_loop_3_to_20_percent_wide_descending_above_ascending(core: str) -> None:
    assert_closed_loop_3_to_20_percent_wide(BLIND11_CORES[core], partial(draw_params, core))


@pytest.mark.parametrize("core", list(BLIND11_DRIVES))
def test_core_is_rate_independent_and_rises_with_the_pressure(core: str) -> None:
    params = _params(core, seed=9)
    v = np.concatenate([np.linspace(0.0, 1.0, 3001), np.linspace(1.0, 0.2, 2401)[1:], np.linspace(0.2, 0.8, 1801)[1:]])
    fine = BLIND11_DRIVES[core](v, 0.001, params, {})
    coarse = BLIND11_DRIVES[core](v[::15], 0.015, params, {})
    assert np.max(np.abs(coarse - fine[::15])) < 0.03 * np.ptp(fine)
    assert rms(coarse - fine[::15]) < 0.01 * np.ptp(fine)
    assert np.all(np.isfinite(fine)) and fine[3000] > fine[1500] > fine[0]
    assert fine[5400] < fine[4000] < fine[3000]


# ---- effects ---------------------------------------------------------------------------------------------


@pytest.mark.parametrize("plant", list(BLIND11_CORES))
def test_forms_are_absent_in_none_and_the_inside_forms_use_the_core(plant: str) -> None:
    params = _params(plant, seed=10)
    dt = 1.0 / 142.0
    u = triangles(params["peak"], dt, 5.0, 4)
    u = np.clip(u + 0.08 * params["peak"] * np.sin(2.0 * np.pi * 1.3 * np.arange(u.size) * dt), 0.0, params["peak"])
    base = BLIND11_CORES[plant](u, dt, params)
    off = _render(plant, params, u, dt, "none", {})
    assert np.array_equal(off, stroke_reading(base, dt, params))
    rng = np.random.default_rng(11)
    for effect, forms in BLIND11_FORMS.items():
        if effect in ("none", "load_dependence", "temperature_drift"):
            continue
        for form in forms:
            change = _render(plant, params, u, dt, form, draw_effect_params(effect, form, rng)) - off
            assert rms(change) > 0.001 * np.ptp(base), form
    assert set(INSIDE_FORMS) <= {f for forms in BLIND11_FORMS.values() for f in forms}
    assert PLAIN_FORMS == tuple(forms[0] for e, forms in BLIND11_FORMS.items() if e != "none")


def test_prony_solid_meets_a_step_with_its_instantaneous_modulus_and_then_relaxes() -> None:
    """A stroke step ``x_e`` is first met by ``1 / (1 + g1 + g2)`` of it, and ends at all of it."""
    q = {"prony_share": 0.3, "tau1_s": 0.02, "tau2_s": 0.2, "second_over_first": 2.0}
    dt = 0.0005
    step = np.concatenate([np.zeros(10), np.full(4000, 1.0)])
    out = prony_maxwell(step, dt, q)
    assert out[10] == pytest.approx(1.0 / 1.3, rel=0.02) and out[-1] == pytest.approx(1.0, abs=1e-3)
    assert np.all(np.diff(out[10:]) >= -1e-12)  # it only catches up
    ramp_slow = np.linspace(0.0, 10.0, 20001)
    assert np.max(np.abs(prony_maxwell(ramp_slow, 0.01, q) - ramp_slow)) < 0.01  # slow: no lag to speak of


def test_centrifugal_brake_leaves_slow_moves_alone_and_holds_fast_ones_back() -> None:
    p = _params("wire_rope_return", seed=12)
    dt = 0.002
    t = np.arange(5000) * dt
    x = 10.0 + 8.0 * np.sin(2.0 * np.pi * 0.5 * t) + 3.0 * np.sin(2.0 * np.pi * 4.0 * t)
    v = np.full_like(x, 0.6)
    q = {"brake_gain": 5e-4, "threshold_pct": 60.0}
    y = governed_stroke(x, v, dt, p, q)
    v_c = float(np.percentile(np.abs(np.gradient(x, dt)), 60.0))
    slow = np.abs(np.diff(x)) / dt <= v_c
    assert np.allclose(y[1:][slow & (np.abs(np.diff(y)) / dt < v_c)], x[1:][slow & (np.abs(np.diff(y)) / dt < v_c)])
    assert rms(y - x) > 0.05 and np.max(np.abs(np.diff(y)) / dt) >= v_c  # fast moves lag but go at least v_c


def test_kelvin_spectrum_creeps_in_a_hold_and_settles_to_the_plant() -> None:
    q = {"kelvin_share": 0.06, "tau_a_s": 1.0, "tau_b_s": 5.0, "tau_c_s": 20.0}
    dt = 0.05
    x = np.concatenate([np.zeros(20), np.full(4000, 10.0)])
    y = kelvin_spectrum(x, dt, q)
    assert y[21] == pytest.approx(10.0 * (1.0 - 0.06), rel=0.01)  # the delayed share is missing at first
    assert y[int(10.0 / dt)] - y[int(3.0 / dt)] > 0.05 and y[-1] == pytest.approx(10.0, abs=1e-3)


def test_cover_gap_takes_pressure_back_slowly_reverse_creep() -> None:
    plant = "contact_births"
    params = _params(plant, seed=13)
    dt, peak = 0.02, params["peak"]
    u = step_and_hold(peak, dt)
    q = {"cover_share": 0.08, "membrane_s": 3.0, "gap_s": 10.0}
    v = normalised_pressure(u, dt, params)
    gap = cover_gap_pressure(v, dt, q)
    assert gap[int(29.0 / dt)] == pytest.approx(0.08 * v[int(29.0 / dt)], rel=0.15)  # settling at its share
    on = _render(plant, params, u, dt, "sealed_cover_permeation", q)
    off = _render(plant, params, u, dt, "none", q)
    i3, i28, i33, i58 = (int(s / dt) for s in (3.0, 28.0, 33.0, 58.0))
    assert on[i28] < on[i3] - 0.002 * np.ptp(off) and abs(off[i28] - off[i3]) < 0.01 * np.ptp(off)  # sinks back
    assert on[i58] > on[i33]  # after the fall it undershoots and creeps back up


def test_fifo_delays_by_whole_frames_and_the_jitter_buffer_by_at_least_the_transit() -> None:
    plant = "runin_crossings"
    params = _params(plant, seed=14)
    dt = 1.0 / 310.0
    u = triangles(params["peak"], dt, 4.0, 3)
    off = _render(plant, params, u, dt, "none", {})
    on = _render(plant, params, u, dt, "fifo_frames", {"fifo_samples": 6.4})
    assert np.array_equal(on[6:], off[:-6])
    q = {"latency_scale": 0.01, "burst_every_s": 3.0, "burst_s": 1.0, "jitter_seed": 7.0}
    delay = jitter_delay_s(u.size, dt, q)
    assert np.all(delay >= 0.01) and np.all(np.diff(delay) >= -0.1 * dt - 1e-15)  # falls slower than time
    assert np.max(delay) > 3.0 * np.min(delay)  # the bursts push it up


def test_tackle_sags_by_the_force_over_the_stiffness() -> None:
    plant = "runin_crossings"
    params = _params(plant, seed=15)
    v = np.concatenate([np.linspace(0.0, 0.8, 400), np.full(200, 0.8)])
    f = np.concatenate([np.zeros(500), np.full(100, 2.0)])  # N, once the pressure holds
    x = BLIND11_DRIVES[plant](v, 0.01, params, {})
    xf = BLIND11_DRIVES[plant](v, 0.01, params, {"f_ext": f})
    k = float(balance_stiffness(v[-1:], x[-1:], params)[0])
    assert x[-1] - xf[-1] == pytest.approx(2.0 / k, rel=0.02) and np.array_equal(x[:500], xf[:500])


def test_column_bow_is_amplified_towards_the_euler_load() -> None:
    q = {"shortening_mm": 0.02, "heaviest_share": 0.8, "frame_kg": 3.0}
    load = np.array([0.0, 1.0, 3.0, 5.0])
    short = column_shortening(load, q)
    ratio = (3.0 + load) / (8.0 / 0.8)
    assert np.allclose(short, 0.02 * ((1.0 - ratio) ** -2 - 1.0))
    assert short[-1] == pytest.approx(0.02 * 24.0) and np.all(np.diff(short) > 0.0)
    assert np.all(np.diff(np.diff(short)) > 0.0)  # ever faster as P nears P_cr


@pytest.mark.parametrize("plant", ["wrapped_tiedown", "wire_rope_return"])
def test_temperature_forms_shift_the_lift_off_and_soften_the_fibres_at_pressure(plant: str) -> None:
    params = _params(plant, seed=16)
    dt = 0.02
    u = triangles(params["peak"], dt, 10.0, 4)
    base = BLIND11_CORES[plant](u, dt, params)
    load = np.full_like(u, 2.0)
    warm = STILL_TEMP_C + np.clip(np.arange(u.size) * dt - 5.0, 0.0, 6.0)  # +6 K from 5 s to 11 s
    off = render(plant, params, u, dt, "none", {}, load, warm, base)
    lift = {"lift_mbar_per_k": 8.0, "bladder_tau_s": 4.0}
    on = render(plant, params, u, dt, "lift_off_tempco", lift, load, warm, base)
    late = np.arange(u.size) * dt > 25.0
    v = normalised_pressure(u, dt, params)
    shifted = BLIND11_DRIVES[plant](v, dt, params, {"lift": np.full_like(v, 0.048 / params["peak"])})
    assert np.all(on[late] <= off[late] + 1e-9)  # warm: it takes more pressure to reach the braid
    assert rms(on[late] - stroke_reading(shifted, dt, params)[late]) < 0.05 * rms(on[late] - off[late])
    q = {"compliance_rise": 2.0, "tg_above_median_k": 0.0, "tg_width_k": 2.0, "braid_tau_s": 1.0}
    comp = fibre_compliance(warm, dt, q)
    assert comp[0] == 1.0 and comp[-1] > 1.5  # glassy at the start, rubbery (compliant) once warm
    glass = render(plant, params, u, dt, "nylon_glass_transition", q, load, warm, base)
    diff = off - glass
    low, high = late & (v < 0.3), late & (v > 0.8)
    assert np.mean(diff[high]) > 3.0 * abs(np.mean(diff[low])) > 0.0  # grows with the pressure
