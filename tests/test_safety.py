"""Safety: every injected fault ends in the latched safe state within 3 ticks, valve vented."""

from __future__ import annotations

import math

import pytest

from edge.control.pid import PIDGains
from edge.control.tick import Controller, Readings
from edge.devices.ads1x15 import ADS1x15
from edge.devices.mcp4725 import MCP4725
from edge.errors import BusError
from edge.runtime.safety import Health, State, Supervisor
from hil.rig import ADC_ADDRESS, DAC_ADDRESS, DISPLACEMENT_CHANNEL, PRESSURE_CHANNEL, HilRig

PERIOD_S = 0.002
FAULT_AT_S = 4.0


def loop(inject, seconds=6.0):
    """A minimal runtime around the supervisor: read, decide, write; returns (supervisor, ticks, rig)."""
    rig = HilRig(adc_variant="ADS1015")
    adc = ADS1x15(rig.bus, rig.clock, address=ADC_ADDRESS, variant="ADS1015", data_rate_sps=3300)
    dac = MCP4725(rig.bus, address=DAC_ADDRESS)
    controller = Controller(lambda t: 10.0 * math.sin(2 * math.pi * 0.2 * t) + 40.0, PIDGains(kp=0.05, ki=0.5))
    supervisor = Supervisor(controller)

    def read() -> Readings:
        contraction = adc.read_volts(DISPLACEMENT_CHANNEL) / 3.3 * 160.0 - 10.0
        pressure = (adc.read_volts(PRESSURE_CHANNEL) - 0.5) / 0.4
        return Readings(contraction, pressure)

    supervisor.arm(read())
    log = []
    for k in range(int(seconds / PERIOD_S)):
        t = k * PERIOD_S
        rig.clock.sleep_until(t)
        if abs(t - FAULT_AT_S) < PERIOD_S / 2:
            inject(rig)
        try:
            readings, bus_error = read(), False
        except BusError:
            readings, bus_error = None, True
        outcome = supervisor.tick(t, PERIOD_S, readings, Health(bus_error=bus_error, estop=rig.gpio.get("estop")))
        rig.gpio.set("valve_enable", outcome.valve_enabled)
        if outcome.valve_enabled:
            dac.write_volts(outcome.pressure_bar / 2.0)
        else:
            dac.power_down()
        log.append((t, outcome))
    return supervisor, log, rig


FAULTS = {
    "sensor disconnected": (lambda rig: rig.fail_sensor(DISPLACEMENT_CHANNEL, "disconnected"), "outside"),
    "sensor saturated": (lambda rig: rig.fail_sensor(DISPLACEMENT_CHANNEL, "saturated"), "outside"),
    "I2C NACK burst": (lambda rig: rig.bus.faults.nack_burst(10, address=ADC_ADDRESS), "consecutive bus errors"),
    "e-stop": (lambda rig: rig.press_estop(), "e-stop"),
    "pressure sensor reads high": (lambda rig: rig.fail_sensor(PRESSURE_CHANNEL, "disconnected"), "overpressure"),
}


def test_healthy_run_stays_running():
    supervisor, log, _ = loop(lambda rig: None)
    assert supervisor.state is State.RUNNING and supervisor.fault is None


@pytest.mark.parametrize("name", FAULTS)
def test_each_fault_ends_in_the_safe_state_within_three_ticks(name):
    inject, reason = FAULTS[name]
    supervisor, log, rig = loop(inject)
    after = [(t, o) for t, o in log if t >= FAULT_AT_S - 1e-9]
    safe_at = next(i for i, (_, o) in enumerate(after) if o.state is State.SAFE)
    assert safe_at < 3, name
    assert reason in supervisor.fault
    assert all(o.state is State.SAFE and not o.valve_enabled for _, o in after[safe_at:])  # latched
    assert rig.dac.output_volts == 0.0 and not rig.gpio.get("valve_enable")


def test_safe_is_left_only_by_an_explicit_reset():
    supervisor, _, _ = loop(FAULTS["e-stop"][0])
    assert supervisor.tick(10.0, PERIOD_S, Readings(40.0, 1.0)).state is State.SAFE
    supervisor.reset()
    assert supervisor.state is State.CONFIGURED
    supervisor.arm(Readings(40.0))
    assert supervisor.state is State.ARMED
    with pytest.raises(RuntimeError, match="cannot arm from armed"):
        supervisor.arm(Readings(40.0))
