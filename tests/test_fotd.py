"""First-order-plus-dead-time identification: harmonics, frequency-response fit, time-response fallback."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hil.linearise import equivalent_fotd
from hil.plant import PlantParams
from hil.record import record
from host.cli import main
from host.data import Measurement
from host.identify.fotd import identify_fotd
from host.identify.harmonics import fourier_fit, harmonics_of

FREQUENCIES_HZ = (0.1, 0.25, 0.6, 1.3, 2.5)


def dead_time_tolerance(true_s: float) -> float:
    """The issue's target: 15 % or 15 ms, whichever is larger."""
    return max(0.15 * true_s, 0.015)


def hammerstein_fotd(
    seed: int, gain: float, tau: float, delay: float, rate_hz: float = 50.0
) -> tuple[Measurement, float]:
    """A plant that is not our emulator: cubic input nonlinearity, then K e^{-sL}/(1+sT), then noise.

    Driven by a stepped sine (its own, with a random phase per segment and segments that are not
    whole periods long); returns the record and the true first-harmonic gain of the nonlinearity
    times ``gain`` (describing function of ``x + c x^3`` at amplitude A: ``1 + 3/4 c A^2``).
    """
    rng = np.random.default_rng(seed)
    dt_fine = 1e-3
    amplitude, cubic = 0.8, 0.3
    pieces = []
    for f in FREQUENCIES_HZ:
        n = int((4.3 / f + rng.uniform(0, 1 / f)) / dt_fine)
        phase = rng.uniform(0, 2 * np.pi)
        pieces.append(amplitude * np.sin(2 * np.pi * f * np.arange(n) * dt_fine + phase))
    u = 3.0 + np.concatenate(pieces)
    t = np.arange(u.size) * dt_fine
    x = (u - 3.0) + cubic * (u - 3.0) ** 3
    delayed = np.interp(t - delay, t, x, left=x[0])
    a = np.exp(-dt_fine / tau)
    y = np.empty_like(delayed)
    state = delayed[0]
    for i, v in enumerate(delayed):
        state = a * state + (1 - a) * v
        y[i] = state
    step = int(round(1 / (rate_hz * dt_fine)))
    y_out = 5.0 + gain * y[::step] + rng.normal(0.0, 0.01 * abs(gain) * amplitude, y[::step].size)
    true_gain = gain * (1 + 0.75 * cubic * amplitude**2)
    return Measurement(t[::step], u[::step], y_out, source=f"foreign Hammerstein FOPDT seed {seed}"), true_gain


def test_fourier_fit_does_not_leak_off_whole_periods():
    """A window of 3.37 periods with an offset, a trend and a 3rd harmonic: amplitude and phase exact."""
    t = np.arange(0, 3.37 / 0.7, 0.002)
    omega = 2 * np.pi * 0.7
    x = 1.5 + 0.1 * t + 2.0 * np.cos(omega * t - 0.8) + 0.4 * np.sin(3 * omega * t)
    amplitude, _, mean, _, _ = fourier_fit(t, x, omega)
    assert abs(amplitude) == pytest.approx(2.0, rel=1e-9)
    assert np.angle(amplitude) == pytest.approx(-0.8, abs=1e-9)
    # the DFT bin nearest 0.7 Hz on the same window is off by more than 5 %
    spectrum = np.fft.rfft(x - x.mean())
    bin_index = int(round(0.7 * t.size * 0.002))
    assert abs(2 * abs(spectrum[bin_index]) / t.size - 2.0) > 0.1


def test_loss_angle_of_a_pure_lag_is_the_lag():
    t = np.arange(0, 40.0, 0.01)
    u = 2.0 + np.sin(2 * np.pi * 0.5 * t)
    y = 1.0 + 3.0 * np.sin(2 * np.pi * 0.5 * t - 0.4)
    (h,) = harmonics_of(t, u, y)
    assert h.loss_angle_rad == pytest.approx(0.4, abs=2e-3)
    assert h.phase_rad == pytest.approx(-0.4, abs=1e-6)
    assert h.gain == pytest.approx(3.0, rel=1e-6)


@pytest.mark.parametrize("seed,gain,tau,delay", [(1, 4.0, 0.08, 0.137), (2, -2.0, 0.3, 0.043), (3, 12.0, 0.02, 0.26)])
def test_recovers_a_foreign_hammerstein_plant(seed, gain, tau, delay):
    measurement, true_gain = hammerstein_fotd(seed, gain, tau, delay)
    fit = identify_fotd([measurement], hysteresis_phase=False)
    assert fit.method == "harmonic"
    assert len(fit.harmonics) == len(FREQUENCIES_HZ)
    assert fit.gain == pytest.approx(true_gain, rel=0.03)
    assert fit.time_constant_s == pytest.approx(tau, rel=0.15, abs=0.005)
    assert abs(fit.dead_time_s - delay) <= dead_time_tolerance(delay)
    assert abs(fit.dead_time_s - delay) <= 4 * fit.dead_time_se_s + 0.002


def test_hysteresis_phase_is_near_zero_on_a_plant_without_hysteresis():
    measurement, _ = hammerstein_fotd(4, 3.0, 0.1, 0.1)
    fit = identify_fotd([measurement])
    assert fit.hysteresis_loss_angle_rad is not None
    assert abs(np.degrees(fit.hysteresis_loss_angle_rad)) < 1.0
    assert abs(fit.dead_time_s - 0.1) <= dead_time_tolerance(0.1)


def test_one_run_per_frequency_is_pooled():
    measurement, true_gain = hammerstein_fotd(5, 2.0, 0.05, 0.07)
    windows = harmonics_of(measurement.t, measurement.u, measurement.y)
    cuts = [0.0] + [(a.stop_s + b.start_s) / 2 for a, b in zip(windows[:-1], windows[1:])] + [measurement.t[-1] + 1]
    runs = [measurement.slice(int(a / measurement.dt), int(b / measurement.dt)) for a, b in zip(cuts[:-1], cuts[1:])]
    assert all(len(harmonics_of(r.t, r.u, r.y)) == 1 for r in runs)
    # one frequency alone cannot identify three parameters
    with pytest.raises(ValueError, match="need at least 2 frequencies|need at least 3"):
        identify_fotd(runs[:1], method="harmonic")
    fit = identify_fotd(runs, method="harmonic", hysteresis_phase=False)
    assert len(fit.harmonics) == len(FREQUENCIES_HZ)
    assert fit.gain == pytest.approx(true_gain, rel=0.03)
    assert abs(fit.dead_time_s - 0.07) <= dead_time_tolerance(0.07)


def _hil_check(seed: int, effect: str) -> None:
    rec = record("stepped-sine", seed, 210.0, effect, 100.0)
    fit = identify_fotd([Measurement(rec.t, rec.u, rec.y)])
    params = PlantParams()
    if effect == "transport_delay":
        params = replace(params, dead_time_s=rec.truth["parameters"]["dead_time_s"])
    truth = equivalent_fotd(params, amplitude_bar=fit.harmonics[0].input_amplitude)
    assert abs(fit.dead_time_s - truth.dead_time_s) <= dead_time_tolerance(truth.dead_time_s)
    assert fit.time_constant_s == pytest.approx(truth.time_constant_s, rel=0.3)
    assert fit.gain == pytest.approx(truth.gain_mm_per_bar, rel=0.2)


def test_hil_transport_delay_is_recovered():
    _hil_check(1, "transport_delay")


@pytest.mark.slow
@pytest.mark.parametrize(
    "seed,effect", [(2, "transport_delay"), (3, "transport_delay"), (4, "transport_delay"), (0, "none")]
)
def test_hil_dead_time_over_seeds(seed, effect):
    _hil_check(seed, effect)


def test_time_response_fallback_on_a_ramp_and_hold():
    """An inflation-like record (ramp up, hold, ramp down), irregular steps resampled: K, T, L back."""
    rng = np.random.default_rng(7)
    t = np.arange(0, 12.0, 0.001)
    u = np.interp(t, [0, 1, 1.4, 6, 6.3, 12], [0.3, 0.3, 5.0, 5.0, 0.5, 0.5])
    gain, tau, delay = 3.2, 0.25, 0.11
    delayed = np.interp(t - delay, t, u, left=u[0])
    a = np.exp(-0.001 / tau)
    y = np.empty_like(u)
    state = u[0]
    for i, v in enumerate(delayed):
        state = a * state + (1 - a) * v
        y[i] = 2.0 + gain * (state - u[0])
    keep = np.sort(rng.choice(t.size, size=400, replace=False))
    m = Measurement(t[keep][::1], u[keep], y[keep] + rng.normal(0, 0.02, keep.size))
    grid = np.arange(m.t[0], m.t[-1], 0.03)
    uniform = Measurement(grid, np.interp(grid, m.t, m.u), np.interp(grid, m.t, m.y))
    fit = identify_fotd([uniform])
    assert fit.method == "time"
    assert fit.gain == pytest.approx(gain, rel=0.03)
    assert fit.time_constant_s == pytest.approx(tau, rel=0.15)
    assert abs(fit.dead_time_s - delay) <= dead_time_tolerance(delay)


def test_cli_fotd_json_and_a_one_frequency_error(tmp_path, capsys):
    measurement, _ = hammerstein_fotd(6, 2.0, 0.05, 0.1)
    path = tmp_path / "run.csv"
    np.savetxt(
        path, np.column_stack([measurement.t, measurement.u, measurement.y]), delimiter=",", header="t,u,y", comments=""
    )
    assert main(["identify", "fotd", str(path), "--json"]) == 0
    import json

    out = json.loads(capsys.readouterr().out)
    for key in ("gain", "time_constant_s", "dead_time_s", "gain_se", "time_constant_se_s", "dead_time_se_s"):
        assert np.isfinite(out[key])
    assert len(out["harmonics"]) == len(FREQUENCIES_HZ)
    assert {"amplitude_ratio", "phase_rad", "loss_angle_rad", "frequency_hz"} <= set(out["harmonics"][0])
    one = tmp_path / "one.csv"
    t = np.arange(0, 30, 0.01)
    np.savetxt(one, np.column_stack([t, np.sin(t), np.sin(t - 0.2)]), delimiter=",", header="t,u,y", comments="")
    assert main(["identify", "fotd", str(one), "--method", "harmonic"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "need at least 3 frequencies" in err[0]


def test_real_inflation_runs_fall_back_to_the_time_fit(shared_data):
    """18-03 campaign: one inflate/deflate per file, not sinusoidal; the fit must explain it."""
    folder = shared_data / "pam_muscle_sensory" / "18-03-2026_Length_Characterisation"
    files = sorted(folder.glob("S0*P001.csv"))[::6]
    if not files:
        pytest.skip("18-03 campaign not present")
    from host.data import load_measurement

    records = [load_measurement(f) for f in files]
    fit = identify_fotd(records)
    assert fit.method == "time"
    assert fit.gain > 0
    spread = max(float(np.ptp(r.y)) for r in records)
    assert fit.rms_error < 0.1 * spread
    assert fit.dead_time_s < 0.1 and fit.time_constant_s < 0.3


@pytest.mark.slow
@pytest.mark.parametrize("valve_s,dead_s", [(0.08, 0.1), (0.015, 0.22)])
def test_hil_dead_time_with_other_valve_lags(valve_s, dead_s):
    """Dead time stays within target when the valve lag changes. T does not: with a slow valve the
    contraction amplitude falls at high frequency, and the presliding hysteresis is stiffer at small
    amplitude, so |G| falls faster than the valve alone would make it (T +50 % at 0.08 s)."""
    params = replace(PlantParams(), valve_time_constant_s=valve_s, dead_time_s=dead_s)
    rec = record("stepped-sine", 5, 210.0, params=params)
    fit = identify_fotd([Measurement(rec.t, rec.u, rec.y)])
    truth = equivalent_fotd(params, amplitude_bar=fit.harmonics[0].input_amplitude)
    assert abs(fit.dead_time_s - truth.dead_time_s) <= dead_time_tolerance(truth.dead_time_s)
    assert fit.time_constant_s >= 0.9 * truth.time_constant_s


def test_two_runs_at_one_frequency_are_one_frequency_and_refused(tmp_path, capsys):
    t = np.arange(0, 40, 0.01)
    paths = []
    for k, shift in enumerate((0.0, 0.3)):  # the same 0.5 Hz twice, estimated a hair apart
        path = tmp_path / f"run{k}.csv"
        u = 2 + np.sin(2 * np.pi * 0.5 * (t + shift))
        y = 10 + 5 * np.sin(2 * np.pi * 0.5 * (t + shift) - 0.4)
        np.savetxt(path, np.column_stack([t, u, y]), delimiter=",", header="t,u,y", comments="")
        paths.append(str(path))
    assert main(["identify", "fotd", *paths, "--method", "harmonic"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "1 distinct frequency" in err[0] and "count once" in err[0]


def test_two_frequencies_do_not_carry_the_loss_angle_too(tmp_path):
    measurement, _ = hammerstein_fotd(5, 2.0, 0.05, 0.07)
    windows = harmonics_of(measurement.t, measurement.u, measurement.y)
    two = measurement.slice(0, int((windows[1].stop_s + windows[2].start_s) / 2 / measurement.dt))
    with pytest.raises(ValueError, match="need at least 3 .*--no-hysteresis-phase"):
        identify_fotd([two], method="harmonic")
    fit = identify_fotd([two])  # auto: without the loss angle, said in a note
    assert fit.hysteresis_loss_angle_rad is None and "without the hysteresis loss angle" in fit.notes[0]
