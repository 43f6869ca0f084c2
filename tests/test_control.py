"""The pure control law, and a closed loop on the HIL through the real drivers (lockstep)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from edge.control.pid import PID, PIDGains
from edge.control.tick import Controller, Limits, Readings
from edge.devices.ads1x15 import ADS1x15
from edge.devices.mcp4725 import MCP4725
from edge.hysteresis.lut import CompiledModel
from hil.rig import ADC_ADDRESS, DAC_ADDRESS, DISPLACEMENT_CHANNEL, HilRig
from host.data import load_measurement
from host.examples import example_path
from host.workflow import make_estimator, rest_state


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
    first = controller.tick(0.0, 0.01, Readings(0.0))
    assert first.pressure_bar == pytest.approx(0.1) and first.saturated  # 10 bar/s for 10 ms
    for k in range(1, 100):
        command = controller.tick(k * 0.01, 0.01, Readings(0.0))
    assert command.pressure_bar == 4.0  # the range limit


def inverse_table() -> CompiledModel:
    train = load_measurement(example_path("train"))
    estimator = make_estimator("preisach").fit(train.u, train.y)
    _, inverse = rest_state(estimator.model_, float(train.u.min()))
    return CompiledModel(inverse.compile())


def track(inverse: CompiledModel | None, seconds: float = 25.0, period_s: float = 0.002) -> np.ndarray:
    """Seed 000 Table 4: y_d = 3 sin(2 pi 0.2 t) + 4 cm; errors [mm] after a 5 s settling time."""
    rig = HilRig(adc_variant="ADS1015")
    adc = ADS1x15(rig.bus, rig.clock, address=ADC_ADDRESS, variant="ADS1015", data_rate_sps=3300)
    dac = MCP4725(rig.bus, address=DAC_ADDRESS)

    def contraction_mm() -> float:
        return adc.read_volts(DISPLACEMENT_CHANNEL) / 3.3 * 160.0 - 10.0

    controller = Controller(lambda t: 30.0 * math.sin(2 * math.pi * 0.2 * t) + 40.0, PIDGains(kp=0.05, ki=0.5), inverse)
    rig.gpio.set("valve_enable", True)
    controller.arm(Readings(contraction_mm()))
    errors = []
    for k in range(int(seconds / period_s)):
        t = k * period_s
        rig.clock.sleep_until(t)
        y = contraction_mm()
        command = controller.tick(t, period_s, Readings(y))
        dac.write_volts(command.pressure_bar / 2.0)  # the rig's valve: 2 bar per volt
        if t >= 5.0:
            errors.append(command.reference_mm - y)
    return np.array(errors)


def test_inverse_hysteresis_feedforward_halves_the_tracking_error_on_the_hil():
    """Seed 000 Table 5 cut RMS error by 48 %; measured here: PID 5.14 mm -> PID + FF 2.45 mm (52 %)."""
    pid_only = track(None)
    with_ff = track(inverse_table())
    rms = lambda e: float(np.sqrt(np.mean(e**2)))  # noqa: E731
    assert rms(with_ff) <= 0.5 * rms(pid_only)
    assert np.abs(with_ff).mean() < np.abs(pid_only).mean()
