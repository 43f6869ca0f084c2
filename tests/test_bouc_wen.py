"""The Bouc-Wen benchmark generator (bench/bouc_wen_data.py): excitation, integration, physics."""

from __future__ import annotations

import numpy as np

from bench.bouc_wen_data import (
    BAND_HZ,
    FS_HZ,
    PARAMETERS,
    PERIOD_SAMPLES,
    RMS_N,
    UPSAMPLE,
    integrate_rk4,
    multisine_half,
)

H = 1.0 / (FS_HZ * UPSAMPLE)


def test_the_multisine_has_the_published_level_and_band():
    u, u_half = multisine_half(np.random.default_rng(0), 1)
    assert u.size == PERIOD_SAMPLES
    assert abs(np.std(u) - RMS_N) < 0.5  # the fine grid is scaled to 50 N; 750 Hz samples of it keep it
    spectrum = np.abs(np.fft.rfft(u)) ** 2
    freq = np.fft.rfftfreq(u.size, 1.0 / FS_HZ)
    inside = (freq >= BAND_HZ[0] - FS_HZ / PERIOD_SAMPLES) & (freq <= BAND_HZ[1] + FS_HZ / PERIOD_SAMPLES)
    assert spectrum[~inside].sum() < 1e-20 * spectrum.sum()
    assert np.count_nonzero(spectrum[inside] > 1e-6 * spectrum.max()) > 0.95 * np.count_nonzero(inside)


def test_the_integration_has_converged_at_the_published_step():
    t = np.arange(2 * 6000 + 1) * H / 2
    u_half = 50.0 * np.sin(2 * np.pi * 30.0 * t) + 20.0 * np.sin(2 * np.pi * 97.0 * t)
    coarse = integrate_rk4(u_half, H)
    t_fine = np.arange(4 * 6000 + 1) * H / 4
    fine = integrate_rk4(50.0 * np.sin(2 * np.pi * 30.0 * t_fine) + 20.0 * np.sin(2 * np.pi * 97.0 * t_fine), H / 2)
    assert np.max(np.abs(coarse - fine[::2])) < 1e-3 * np.max(np.abs(fine))


def test_a_slow_small_force_sees_the_initial_stiffness():
    """For small, slow motion z ~ alpha y: the static stiffness is k_L + alpha (1e5 N/m)."""
    t = np.arange(2 * int(2.0 / H) + 1) * H / 2
    u_half = 1.0 * np.sin(2 * np.pi * 1.0 * t)
    y = integrate_rk4(u_half, H)
    stiffness = 1.0 / np.max(np.abs(y[y.size // 2 :]))
    assert abs(stiffness - (PARAMETERS.k_l + PARAMETERS.alpha)) < 0.03 * (PARAMETERS.k_l + PARAMETERS.alpha)


def test_a_large_force_shows_a_hysteresis_loop_that_dissipates_energy():
    t = np.arange(2 * int(1.0 / H) + 1) * H / 2
    u_half = 100.0 * np.sin(2 * np.pi * 5.0 * t)
    y = integrate_rk4(u_half, H)
    last = slice(y.size - int(0.2 / H), y.size)  # the last period at 5 Hz
    u = u_half[::2][last]
    work = float(np.sum(u[:-1] * np.diff(y[last])))  # loop area: energy the force puts in per cycle [J]
    assert work > 1e-4


def test_a_periodic_force_reaches_a_periodic_response():
    u, u_half = multisine_half(np.random.default_rng(1), 3)
    y = integrate_rk4(u_half, H)
    n = PERIOD_SAMPLES * UPSAMPLE
    last, before = y[2 * n : 3 * n], y[n : 2 * n]
    assert np.sqrt(np.mean((last - before) ** 2)) < 1e-3 * np.std(last)


def test_the_arx_baseline_recovers_a_linear_system_it_did_not_see_the_orders_of():
    from scipy.signal import lfilter

    from bench.bouc_wen import fit_arx

    u = np.random.default_rng(3).normal(0, 1, 4000)
    y = lfilter([0.0, 0.3, 0.1], [1.0, -1.2, 0.5], u)
    simulate, orders = fit_arx(u, y, 3200)
    assert orders[0] >= 2 and orders[1] >= 2
    u_new = np.random.default_rng(4).normal(0, 1, 1000)
    truth = lfilter([0.0, 0.3, 0.1], [1.0, -1.2, 0.5], u_new)
    assert np.max(np.abs(simulate(u_new, "rest") - truth)) < 1e-6 * np.ptp(truth)
