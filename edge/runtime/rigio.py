"""The rig seen by the runtime: calibrated readings in, a valve command out.

Two implementations over the ports: ADS1x15 + MCP4725 on I2C with GPIO lines, and the serial
DAQ. Calibration (volts -> mm, volts -> bar, bar -> DAC volts) comes from the rig config.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from edge.devices.ads1x15 import ADS1x15
from edge.devices.daq_client import DaqClient
from edge.devices.mcp4725 import MCP4725
from edge.hal.clock import Clock
from edge.hal.gpio import GpioLines
from edge.hal.i2c import I2CBus
from edge.hal.serial import SerialLink
from edge.runtime.config import RigConfig


@dataclass(slots=True)  # built every tick: slots, not frozen (a frozen init costs ~0.15 us per field)
class RigReading:
    """One tick's sensors: contraction [mm], pressure [bar] (NaN without a transducer), e-stop."""

    contraction_mm: float
    pressure_bar: float
    estop: bool


class RigIO(Protocol):
    def read(self) -> RigReading:
        """Sample the sensors; raises :class:`~edge.errors.BusError` on a failed transfer."""

    def write(self, pressure_bar: float, valve_enabled: bool) -> None:
        """Command the valve; ``valve_enabled=False`` vents."""

    def vent(self) -> None:
        """Best effort safe state (valve disabled, zero command); never raises."""

    def close(self) -> None: ...


class Calibration:
    """Volts <-> engineering units of one rig config."""

    def __init__(self, config: RigConfig) -> None:
        c, p = config.sensors.contraction, config.sensors.pressure
        self._y = (c.mm_per_volt, c.volts_at_zero_mm)
        self._p = (p.bar_per_volt, p.volts_at_zero_bar) if p else None
        self.valve_bar_per_volt = config.valve.bar_per_volt

    def contraction_mm(self, volts: float) -> float:
        scale, zero = self._y
        return (volts - zero) * scale

    def pressure_bar(self, volts: float) -> float:
        if self._p is None:
            return math.nan
        scale, zero = self._p
        return (volts - zero) * scale


class I2CRigIO:
    """ADC and DAC drivers on an I2C bus, valve enable and e-stop on GPIO lines."""

    def __init__(self, bus: I2CBus, clock: Clock, gpio: GpioLines, config: RigConfig) -> None:
        a, d = config.adc, config.dac
        self.adc = ADS1x15(
            bus, clock, address=a.address, variant=a.chip, full_scale_v=a.full_scale_v, data_rate_sps=a.data_rate_sps
        )
        self.dac = MCP4725(bus, address=d.address, vdd=d.vdd_v)
        self.bus, self.gpio = bus, gpio
        self.calibration = Calibration(config)
        self._y_channel = config.sensors.contraction.channel
        self._p_channel = config.sensors.pressure.channel if config.sensors.pressure else None

    def read(self) -> RigReading:
        cal = self.calibration
        y = cal.contraction_mm(self.adc.read_volts(self._y_channel))
        p = cal.pressure_bar(self.adc.read_volts(self._p_channel)) if self._p_channel is not None else math.nan
        return RigReading(y, p, self.gpio.get("estop"))

    def write(self, pressure_bar: float, valve_enabled: bool) -> None:
        self.dac.write_volts(pressure_bar / self.calibration.valve_bar_per_volt if valve_enabled else 0.0)
        self.gpio.set("valve_enable", valve_enabled)

    def vent(self) -> None:
        for action in (lambda: self.gpio.set("valve_enable", False), lambda: self.dac.write_code(0)):
            try:
                action()
            except Exception:  # noqa: BLE001 - venting must try every path even if one fails
                pass

    def close(self) -> None:
        self.vent()
        self.gpio.close()
        self.bus.close()


class SerialRigIO:
    """The serial DAQ: both sensors and the e-stop in each sample, enable in each command."""

    def __init__(self, link: SerialLink, clock: Clock, config: RigConfig) -> None:
        serial = config.serial
        self.link = link
        self.client = DaqClient(link, clock, serial.sample_rate_hz, serial.timeout_s)
        self.calibration = Calibration(config)
        self._vdd = config.dac.vdd_v

    def read(self) -> RigReading:
        sample = self.client.read()
        cal = self.calibration
        return RigReading(
            cal.contraction_mm(sample.displacement_volts), cal.pressure_bar(sample.pressure_volts), sample.estop
        )

    def write(self, pressure_bar: float, valve_enabled: bool) -> None:
        volts = pressure_bar / self.calibration.valve_bar_per_volt if valve_enabled else 0.0
        self.client.command(round(volts / self._vdd * 4096), valve_enabled)

    def vent(self) -> None:
        try:
            self.client.command(0, False)
        except Exception:  # noqa: BLE001 - best effort; the DAQ vents on its own command timeout
            pass

    def close(self) -> None:
        self.vent()
        self.link.close()
