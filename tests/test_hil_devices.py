"""Chip emulators against datasheet behaviour, and every rig fault visible at the wire."""

from __future__ import annotations

import errno

import pytest

from edge.errors import BusError
from edge.hal.i2c import I2CMessage
from hil.clock import SimClock
from hil.devices.ads1x15 import ADS1x15Emulator
from hil.devices.bus import EmulatedI2CBus
from hil.devices.mcp4725 import EEPROM_WRITE_S, MCP4725Emulator
from hil.rig import ADC_ADDRESS, DAC_ADDRESS, DISPLACEMENT_CHANNEL, PRESSURE_CHANNEL, HilRig


def adc_bus(volts=(1.0, 0.25, 0.0, 0.0), variant="ADS1115"):
    clock = SimClock()
    adc = ADS1x15Emulator(clock.now, lambda ch: volts[ch], variant)
    bus = EmulatedI2CBus(advance=clock.advance)
    bus.attach(0x48, adc)
    return clock, adc, bus


def write_register(bus, pointer, value, address=0x48):
    bus.transfer(address, [I2CMessage.write([pointer, value >> 8, value & 0xFF])])


def read_register(bus, pointer, address=0x48):
    out = I2CMessage.read_bytes(2)
    bus.transfer(address, [I2CMessage.write([pointer]), out])
    return (out.data[0] << 8) | out.data[1]


def config(mux=4, pga=1, single=True, rate=4, start=True):
    return (0x8000 if start else 0) | (mux << 12) | (pga << 9) | (0x100 if single else 0) | (rate << 5) | 0x3


def test_ads1115_reset_values_and_threshold_round_trip():
    _, _, bus = adc_bus()
    assert read_register(bus, 1) == 0x8583
    assert read_register(bus, 2) == 0x8000 and read_register(bus, 3) == 0x7FFF
    write_register(bus, 2, 0x1234)
    write_register(bus, 3, 0xABCD)
    assert read_register(bus, 2) == 0x1234 and read_register(bus, 3) == 0xABCD


def test_single_shot_conversion_takes_one_data_rate_period():
    clock, adc, bus = adc_bus()
    write_register(bus, 1, config(rate=4))  # 128 SPS, AIN0, +-4.096 V
    assert read_register(bus, 1) & 0x8000 == 0  # converting
    clock.advance(1 / 128 - 1e-5)
    assert read_register(bus, 1) & 0x8000 == 0
    clock.advance(2e-5)
    assert read_register(bus, 1) & 0x8000  # done
    assert read_register(bus, 0) == round(1.0 / 4.096 * 32768)


def test_continuous_mode_refreshes_at_the_data_rate():
    volts = [1.0, 0.0, 0.0, 0.0]
    clock, adc, bus = adc_bus(volts)
    write_register(bus, 1, config(single=False, rate=7, start=False))  # 860 SPS continuous
    clock.advance(1.5 / 860)
    first = read_register(bus, 0)
    volts[0] = 2.0
    clock.advance(1 / 860)
    assert read_register(bus, 0) == 2 * first
    assert read_register(bus, 1) & 0x8000 == 0  # always converting


def test_saturation_codes_and_differential_inputs():
    clock, _, bus = adc_bus((3.0, 0.5, 0.0, 0.0))
    write_register(bus, 1, config(mux=4, pga=2))  # AIN0 3.0 V on a +-2.048 V range
    clock.advance(0.01)
    assert read_register(bus, 0) == 0x7FFF
    write_register(bus, 1, config(mux=0, pga=5))  # AIN0 - AIN1 = +2.5 V on +-0.256 V
    clock.advance(0.01)
    assert read_register(bus, 0) == 0x7FFF
    clock2, _, bus2 = adc_bus((0.0, 2.0, 0.0, 0.0))
    write_register(bus2, 1, config(mux=0, pga=2))  # AIN0 - AIN1 = -2.0 V on +-2.048 V
    clock2.advance(0.01)
    assert read_register(bus2, 0) == (-round(2.0 / 2.048 * 32768)) & 0xFFFF
    write_register(bus2, 1, config(mux=0, pga=3))
    clock2.advance(0.01)
    assert read_register(bus2, 0) == 0x8000


def test_ads1015_is_twelve_bit_left_aligned_and_faster():
    clock, adc, bus = adc_bus((1.0, 0, 0, 0), variant="ADS1015")
    write_register(bus, 1, config(rate=6))  # 3300 SPS
    assert adc.conversion_time() == pytest.approx(1 / 3300)
    clock.advance(1 / 3300 + 1e-6)
    assert read_register(bus, 0) == round(1.0 / 4.096 * 2048) << 4


def dac():
    clock = SimClock()
    chip = MCP4725Emulator(clock.now, vdd=5.0)
    bus = EmulatedI2CBus(advance=clock.advance)
    bus.attach(0x60, chip)
    return clock, chip, bus


def test_mcp4725_fast_write_and_readback():
    _, chip, bus = dac()
    bus.transfer(0x60, [I2CMessage.write([0x0A, 0xBC])])
    assert chip.code == 0xABC and chip.output_volts == pytest.approx(5.0 * 0xABC / 4096)
    back = I2CMessage.read_bytes(5)
    bus.transfer(0x60, [back])
    assert back.data[0] & 0x80 and back.data[1] == 0xAB and back.data[2] == 0xC0


def test_mcp4725_write_dac_and_eeprom_is_busy_for_the_eeprom_time():
    clock, chip, bus = dac()
    bus.transfer(0x60, [I2CMessage.write([0x60, 0x80, 0x00])])  # write DAC + EEPROM, code 0x800
    assert chip.code == 0x800 and chip.eeprom_code == 0x800
    status = I2CMessage.read_bytes(1)
    bus.transfer(0x60, [status])
    assert status.data[0] & 0x80 == 0  # not ready
    bus.transfer(0x60, [I2CMessage.write([0x01, 0x00])])  # ignored while busy
    assert chip.code == 0x800
    clock.advance(EEPROM_WRITE_S)
    bus.transfer(0x60, [status])
    assert status.data[0] & 0x80


def test_mcp4725_power_down_turns_the_output_off():
    _, chip, bus = dac()
    bus.transfer(0x60, [I2CMessage.write([0x40 | (0b01 << 1), 0xFF, 0xF0])])  # write DAC, PD = 1k
    assert chip.code == 0xFFF and chip.output_volts == 0.0


def test_unknown_address_is_not_acknowledged():
    _, _, bus = adc_bus()
    with pytest.raises(BusError) as info:
        bus.transfer(0x49, [I2CMessage.write([0])])
    assert info.value.errno == errno.ENXIO


def test_nack_and_eio_bursts_then_recovery_and_latency():
    clock, _, bus = adc_bus()
    bus.faults.nack_burst(2, address=0x48)
    for _ in range(2):
        with pytest.raises(BusError) as info:
            read_register(bus, 1)
        assert info.value.errno == errno.EREMOTEIO
    assert read_register(bus, 1) == 0x8583
    bus.faults.eio_burst(1)
    with pytest.raises(BusError) as info:
        read_register(bus, 1)
    assert info.value.errno == errno.EIO
    assert bus.faults.log == ["nack 0x48", "nack 0x48", "eio 0x48"]
    bus.faults.latency_s = 0.002
    before = clock.now()
    read_register(bus, 1)
    assert clock.now() - before == pytest.approx(0.002)


# ---- the rig: chips wired to the plant ------------------------------------------------------


def sample(rig, channel, pga=1):
    write_register(rig.bus, 1, config(mux=4 + channel, pga=pga, rate=7), ADC_ADDRESS)
    rig.clock.advance(1.2 / 860)
    return read_register(rig.bus, 0, ADC_ADDRESS)


def command(rig, bar):
    code = round(bar / 2.0 / 5.0 * 4096)
    rig.bus.transfer(DAC_ADDRESS, [I2CMessage.write([code >> 8, code & 0xFF])])


def pressure_from_code(code):
    return ((code if code < 0x8000 else code - 0x10000) / 32768 * 4.096 - 0.5) / 0.4


def test_valve_command_through_the_dac_raises_the_measured_pressure():
    rig = HilRig()
    command(rig, 3.0)
    rig.clock.advance(0.5)
    assert pressure_from_code(sample(rig, PRESSURE_CHANNEL)) < 0.05  # valve disabled: vented
    rig.gpio.set("valve_enable", True)
    rig.clock.advance(1.0)
    assert pressure_from_code(sample(rig, PRESSURE_CHANNEL)) == pytest.approx(3.0, abs=0.05)
    assert rig.steps >= 1500  # the plant ran in lockstep, 1 kHz


@pytest.mark.parametrize(
    "mode, expected",
    [("disconnected", round(3.3 / 4.096 * 32768)), ("saturated", 0x7FFF)],
)
def test_sensor_faults_show_in_the_codes(mode, expected):
    rig = HilRig()
    rig.fail_sensor(DISPLACEMENT_CHANNEL, mode)
    pga = 2 if mode == "saturated" else 1
    code = sample(rig, DISPLACEMENT_CHANNEL, pga)
    assert code == (0x7FFF if mode == "saturated" else expected)


def test_stuck_sensor_repeats_its_code_while_the_muscle_moves():
    rig = HilRig()
    rig.gpio.set("valve_enable", True)
    rig.fail_sensor(DISPLACEMENT_CHANNEL, "stuck")
    first = sample(rig, DISPLACEMENT_CHANNEL)
    command(rig, 3.0)
    rig.clock.advance(1.0)
    assert sample(rig, DISPLACEMENT_CHANNEL) == first
    assert rig.outputs().contraction_mm > 20.0


def test_stuck_valve_and_supply_drop():
    rig = HilRig()
    rig.gpio.set("valve_enable", True)
    command(rig, 2.0)
    rig.clock.advance(1.0)
    rig.stick_valve()
    command(rig, 4.0)
    rig.clock.advance(1.0)
    assert rig.outputs().pressure_bar == pytest.approx(2.0, abs=0.02)
    rig.stick_valve(False)
    rig.drop_supply(1.5)
    rig.clock.advance(1.0)
    assert rig.outputs().pressure_bar == pytest.approx(1.5, abs=0.02)


def test_estop_input_line():
    rig = HilRig()
    assert rig.gpio.get("estop") is False
    rig.press_estop()
    assert rig.gpio.get("estop") is True
    with pytest.raises(BusError):
        rig.gpio.set("estop", False)
