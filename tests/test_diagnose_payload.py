"""A payload on the muscle's pressure-dependent stiffness (host.diagnose.payload): the element
against the damped oscillator's closed form, its scaling with stiffness, and the diagnosis of a
pulse-driven muscle carrying a payload whose ringing speeds up with the pressure (a rate
dependence) or does not (linear mechanics: the output_lag yardstick, never named).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from bench.plants.pulses import muscle_stroke, pulse_pressure, pulse_record
from host.data import Measurement
from host.diagnose import run
from host.diagnose.payload import payload_follow, stiffness_ratio


def _damped_step(t: np.ndarray, w: float, zeta: float) -> np.ndarray:
    """Unit step response of ``y'' + 2 zeta w y' + w^2 y = w^2`` from rest (underdamped)."""
    wd = w * np.sqrt(1.0 - zeta**2)
    return 1.0 - np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd * np.sin(wd * t))


@pytest.mark.parametrize(("rate_hz", "f_hz", "zeta"), [(1000.0, 5.0, 0.1), (200.0, 2.0, 0.5)])
def test_the_element_rings_like_a_damped_oscillator(rate_hz, f_hz, zeta):
    """The input is held at the mean of each sample's ends, so a step between two samples acts
    half a sample after the first."""
    dt = 1.0 / rate_hz
    t = np.arange(int(2.0 / dt)) * dt
    step = np.r_[0.0, np.ones(t.size - 1)]
    w = 2.0 * np.pi * f_hz
    y = payload_follow(step, dt, np.ones(t.size), w, zeta)
    exact = np.where(t > 0, _damped_step(np.maximum(t - 0.5 * dt, 0.0), w, zeta), 0.0)
    assert np.max(np.abs(y - exact)) < 1e-3


def test_a_payload_near_the_sample_rate_is_within_five_percent_of_a_step():
    """8 Hz sampled at 60 Hz (w dt = 0.84): the mean hold against the input joined linearly
    (the element run 100 times finer) differs by at most 5 % of a step."""
    dt, n, finer = 1.0 / 60.0, 120, 100
    t = np.arange(n) * dt
    step = np.r_[0.0, np.ones(n - 1)]
    w = 2.0 * np.pi * 8.0
    fine_t = np.arange((n - 1) * finer + 1) * dt / finer
    reference = payload_follow(np.interp(fine_t, t, step), dt / finer, np.ones(fine_t.size), w, 0.2)[::finer]
    assert np.max(np.abs(payload_follow(step, dt, np.ones(n), w, 0.2) - reference)) < 0.05


def test_a_stiffer_muscle_rings_faster_by_the_square_root_of_its_stiffness():
    dt = 1e-3
    t = np.arange(4000) * dt
    step = np.r_[0.0, np.ones(t.size - 1)]

    def first_peak(stiffness: float) -> float:
        y = payload_follow(step, dt, np.full(t.size, stiffness), 2.0 * np.pi * 3.0, 0.05)
        return float(t[int(np.argmax(y[: int(0.5 / dt)]))])

    assert first_peak(1.0) / first_peak(0.25) == pytest.approx(0.5, rel=0.03)


def test_columns_and_trials_are_filtered_as_one_at_a_time():
    rng = np.random.default_rng(2)
    dt = 0.005
    x = np.cumsum(rng.normal(size=(800, 3)), axis=0)
    p = np.abs(np.cumsum(rng.normal(size=800)))
    s = stiffness_ratio(p, 0.3)
    together = payload_follow(x, dt, s, 20.0, 0.2)
    for j in range(3):
        assert np.allclose(together[:, j], payload_follow(x[:, j], dt, s, 20.0, 0.2))
    trials = payload_follow(
        x[:, 0], dt, np.column_stack([s, np.ones(800)]), np.array([20.0, 30.0]), np.array([0.2, 0.4])
    )
    assert np.allclose(trials[:, 1], payload_follow(x[:, 0], dt, np.ones(800), 30.0, 0.4))


def test_the_stiffness_ratio_runs_from_its_floor_share_to_one():
    p = np.array([0.5, 1.0, 4.5])
    assert stiffness_ratio(p, 0.25) == pytest.approx([0.2, 0.2 + 0.8 * 0.125, 1.0])
    assert np.all(stiffness_ratio(p, None) == 1.0)


def _payload_record(floor: float | None, seed: int = 11) -> Measurement:
    """The pulse-driven muscle at 200 Hz carrying a payload that rings at 4 Hz at the top
    (damping ratio 0.12), on a stiffness with ``floor`` (None: fixed)."""
    dt, pressure = pulse_pressure(200.0, 60.0)
    stroke = payload_follow(muscle_stroke(pressure), dt, stiffness_ratio(pressure, floor), 2.0 * np.pi * 4.0, 0.12)
    return pulse_record(dt, pressure, stroke, f"payload {floor}", seed)


def _diagnosed(m: Measurement) -> run.Diagnosis:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return run.diagnose(m, progress=False)


def test_a_payload_whose_ringing_speeds_up_with_pressure_is_named_rate_dependence():
    d = _diagnosed(_payload_record(0.3))
    assert d.cause == "rate_dependence"
    model = d.extended_model
    assert model.get("form") == 2.0
    assert model["payload_frequency_at_top_hz"] == pytest.approx(4.0, rel=0.25)


def test_a_payload_on_a_fixed_stiffness_is_mechanics_not_rate_dependence():
    """The same payload on a stiffness that does not change with pressure is linear mechanics,
    which the output_lag yardstick explains as well: never named."""
    d = _diagnosed(_payload_record(None))
    assert d.cause != "rate_dependence"
    assert d.scores["output_lag"] > 0.25
