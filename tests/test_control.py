"""The pure control law (the closed loop on the HIL is in test_edge_runtime.py)."""

from __future__ import annotations

import pytest

from edge.control.pid import PID, PIDGains
from edge.control.tick import Controller, Limits, Readings, ScratchFrame


def test_derivative_acts_on_the_measurement_so_a_setpoint_step_gives_no_kick():
    pid = PID(PIDGains(kp=0.0, ki=0.0, kd=1.0, tau_d_s=0.0))
    pid.reset(measurement=5.0)
    assert pid.step(setpoint=100.0, measurement=5.0, dt=0.01) == 0.0
    assert pid.step(setpoint=100.0, measurement=6.0, dt=0.01) == pytest.approx(-100.0)


def test_integrator_does_not_wind_up_against_a_saturated_output():
    pid = PID(PIDGains(kp=1.0, ki=10.0, out_min=0.0, out_max=1.0))
    pid.reset(0.0)
    for _ in range(1000):
        assert pid.step(10.0, 0.0, 0.01) == 1.0
    assert pid.integral < 1.0  # stopped integrating at the limit
    assert pid.step(0.0, 0.5, 0.01) < 1.0  # recovers at once when the error reverses


def test_bumpless_start_continues_from_the_given_output():
    pid = PID(PIDGains(kp=2.0, ki=1.0))
    pid.reset(measurement=3.0, output=0.7)
    assert pid.step(setpoint=3.0, measurement=3.0, dt=0.01) == pytest.approx(0.7)


def test_tick_is_pure_and_applies_slew_and_range_limits():
    controller = Controller(lambda t: 50.0, PIDGains(kp=1.0), limits=Limits(0.0, 4.0, slew_bar_per_s=10.0))
    controller.arm(Readings(0.0), pressure_bar=0.0)
    first = ScratchFrame(0.0, 0.0)
    controller.fill(first, 0.01)
    saturated = first.u_bar != first.u_ff_bar + first.u_nn_bar + first.u_fb_bar
    assert first.u_bar == pytest.approx(0.1) and saturated  # 10 bar/s for 10 ms
    for k in range(1, 100):
        frame = ScratchFrame(k * 0.01, 0.0)
        controller.fill(frame, 0.01)
    assert frame.u_bar == 4.0  # the range limit
