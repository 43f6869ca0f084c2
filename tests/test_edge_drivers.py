"""The edge's chip drivers, unchanged, against the HIL's emulated chips (lockstep clock)."""

from __future__ import annotations

import errno

import pytest

from edge.devices.ads1x15 import ADS1x15
from edge.devices.mcp4725 import MCP4725
from edge.errors import BusError
from hil.rig import ADC_ADDRESS, DAC_ADDRESS, DISPLACEMENT_CHANNEL, PRESSURE_CHANNEL, HilRig, pressure_volts


def drivers(variant="ADS1115", rate=860):
    rig = HilRig(adc_variant=variant)
    adc = ADS1x15(rig.bus, rig.clock, address=ADC_ADDRESS, variant=variant, data_rate_sps=rate)
    dac = MCP4725(rig.bus, address=DAC_ADDRESS)
    return rig, adc, dac


def test_the_drivers_close_the_pneumatic_loop_on_the_emulated_rig():
    rig, adc, dac = drivers()
    rig.gpio.set("valve_enable", True)
    dac.write_volts(1.5)  # 2 bar/V: a 3 bar command
    assert dac.read_code() == round(1.5 / 5.0 * 4096)
    rig.clock.advance(1.0)
    pressure = (adc.read_volts(PRESSURE_CHANNEL) - 0.5) / 0.4
    assert pressure == pytest.approx(3.0, abs=0.05)
    assert adc.read_volts(DISPLACEMENT_CHANNEL) > 1.0  # the muscle contracted


def test_a_single_shot_read_takes_one_conversion_period_of_simulated_time():
    rig, adc, _ = drivers("ADS1015", 3300)
    before = rig.clock.now()
    adc.read_volts(PRESSURE_CHANNEL)
    assert rig.clock.now() - before == pytest.approx(1 / 3300, rel=0.01)


def test_a_stuck_adc_times_out_instead_of_stalling_the_loop():
    rig, adc, _ = drivers()
    rig.adc.stuck_busy = True
    before = rig.clock.now()
    with pytest.raises(BusError) as info:
        adc.read_volts(PRESSURE_CHANNEL)
    assert info.value.errno == errno.ETIMEDOUT
    assert rig.clock.now() - before == pytest.approx(3 / 860, rel=0.01)


def test_continuous_mode_and_power_down():
    rig, adc, dac = drivers()
    adc.start_continuous(PRESSURE_CHANNEL)
    rig.clock.advance(0.01)
    assert adc.latest_volts() == pytest.approx(pressure_volts(0.0), abs=0.01)
    dac.write_code(4095)
    dac.power_down()
    assert rig.dac.output_volts == 0.0


def test_bus_faults_reach_the_driver_as_bus_errors():
    rig, adc, _ = drivers()
    rig.bus.faults.nack_burst(1, address=ADC_ADDRESS)
    with pytest.raises(BusError):
        adc.read_volts(PRESSURE_CHANNEL)
    assert adc.read_volts(PRESSURE_CHANNEL) == pytest.approx(0.5, abs=0.02)


def test_driver_arguments_are_checked():
    rig = HilRig()
    with pytest.raises(ValueError, match="no 3300 SPS"):
        ADS1x15(rig.bus, rig.clock, data_rate_sps=3300)
    with pytest.raises(ValueError, match="outside 0..4095"):
        MCP4725(rig.bus).write_code(5000)
