"""The emulated rig: plant physics wired to chip emulators, GPIO lines and faults.

Wiring (the defaults of ``docs/examples/hil-rig.toml`` in the edge issue):

* ADS1115 (or ADS1015) at 0x48. AIN0: pressure transducer, 0.5-4.5 V for 0-10 bar. AIN1:
  displacement potentiometer, 0-3.3 V for -10..150 mm of contraction.
* MCP4725 at 0x60 drives the proportional valve: 0-5 V for 0-10 bar, limited by the supply.
* GPIO: ``valve_enable`` (edge output; off vents the muscle), ``estop`` (edge input).

The physics is brought up to date lazily: before every bus transfer and analog read the plant
is integrated from its last time to the clock's now at its fixed step, with the valve command
that held over that interval. With a :class:`~hil.clock.SimClock` that is lockstep (no sleeping,
deterministic); with the wall clock it is real time.

Faults: sensors stuck (voltage frozen), saturated (driven past full scale), disconnected (pulled
to the supply rail), detached (off the muscle: the value where it came off, plus noise); a leak
(the muscle holds a share of the measured pressure); valve stuck (ignores new commands); supply
pressure drop; plus the bus's wire faults (:class:`~hil.devices.bus.WireFaults`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from edge.hal.clock import Clock
from hil.clock import SimClock
from hil.devices.ads1x15 import ADS1x15Emulator
from hil.devices.bus import EmulatedI2CBus
from hil.devices.gpio import EmulatedGpio
from hil.devices.mcp4725 import MCP4725Emulator
from hil.plant import Outputs, PlantParams, initial_state, output, update

ADC_ADDRESS = 0x48
DAC_ADDRESS = 0x60
PRESSURE_CHANNEL = 0
DISPLACEMENT_CHANNEL = 1
ADC_VDD = 3.3
NOISE = {"pressure_bar": 0.004, "contraction_mm": 0.03, "load_kg": 0.01, "temperature_c": 0.05, "pressure_b_bar": 0.004}


@dataclass(frozen=True)
class Sensor:
    """One emulated sensor on an ADC input: ``volts = quantity / scale + zero`` (the inverse of
    the edge's channel calibration ``value = (volts - zero) * scale``)."""

    quantity: str  # a field of hil.plant.Outputs
    scale: float
    zero: float

    def volts(self, value: float) -> float:
        return value / self.scale + self.zero


@dataclass(frozen=True)
class Wiring:
    """Which sensor sits on which ADC input, and the valve's bar per volt of DAC command.
    The plug-in builds it from the rig config's channel table; the defaults are
    ``docs/examples/hil-rig.toml``'s."""

    sensors: dict[int, Sensor] = field(
        default_factory=lambda: {
            PRESSURE_CHANNEL: Sensor("pressure_bar", 2.5, 0.5),  # 0.5-4.5 V for 0-10 bar
            DISPLACEMENT_CHANNEL: Sensor(
                "contraction_mm", 160.0 / ADC_VDD, ADC_VDD * 10.0 / 160.0
            ),  # 0-3.3 V: -10..150 mm
        }
    )
    valve_bar_per_volt: float = 2.0  # proportional valve: 0-5 V -> 0-10 bar
    valve_b_bar_per_volt: float = 2.0  # the joint's second valve (hil.joint_rig)


DEFAULT_WIRING = Wiring()


def pressure_volts(pressure_bar: float) -> float:
    """Transducer of the default wiring: 0.5 V at 0 bar, 4.5 V at 10 bar."""
    return DEFAULT_WIRING.sensors[PRESSURE_CHANNEL].volts(pressure_bar)


def displacement_volts(contraction_mm: float) -> float:
    """Potentiometer of the default wiring: 0 V at -10 mm, 3.3 V at 150 mm."""
    return DEFAULT_WIRING.sensors[DISPLACEMENT_CHANNEL].volts(contraction_mm)


def valve_command_bar(dac_volts: float, bar_per_volt: float = DEFAULT_WIRING.valve_bar_per_volt) -> float:
    """Proportional valve: ``bar_per_volt`` bar per volt of command."""
    return bar_per_volt * dac_volts


@dataclass
class RigFaults:
    """Faults at the sensors and the valve. Sensor modes: None, stuck, saturated, disconnected,
    detached (``detached_at`` keeps the value where it came off)."""

    sensors: dict[int, str | None] = field(default_factory=lambda: {PRESSURE_CHANNEL: None, DISPLACEMENT_CHANNEL: None})
    stuck_volts: dict[int, float] = field(default_factory=dict)
    detached_at: dict[int, float] = field(default_factory=dict)
    valve_stuck_bar: float | None = None


class HilRig:
    """The emulated rig (see module docstring).

    Args:
        params: plant parameters (effects already applied).
        clock: defaults to a new :class:`SimClock` (lockstep).
        seed: sensor noise.
        adc_variant: ``ADS1115`` or ``ADS1015``.
        bus_hz: I2C clock; when given, lockstep runs pay each transfer's wire time.
    """

    def __init__(
        self,
        params: PlantParams | None = None,
        clock: Clock | None = None,
        seed: int = 0,
        adc_variant: str = "ADS1115",
        bus_hz: float | None = None,
        wiring: Wiring | None = None,
    ) -> None:
        self.params = params or PlantParams()
        self.wiring = wiring or DEFAULT_WIRING
        self.hooks: list[Callable[[float], None]] = []  # called with the time before each sync (fault schedules)
        self.clock = clock or SimClock()
        self._rng = np.random.default_rng(seed)
        self.state = initial_state(self.params)
        self._plant_time = self.clock.now()
        self.faults = RigFaults()
        advance = self.clock.advance if isinstance(self.clock, SimClock) else None
        self.bus = EmulatedI2CBus(advance=advance, before_transfer=self.sync, bus_hz=bus_hz)
        self.adc = ADS1x15Emulator(self.clock.now, self.analog_volts, adc_variant, vdd=ADC_VDD)
        self.dac = MCP4725Emulator(self.clock.now)
        self.bus.attach(ADC_ADDRESS, self.adc)
        self.bus.attach(DAC_ADDRESS, self.dac)
        self.gpio = EmulatedGpio({"valve_enable": False, "estop": False}, outputs={"valve_enable"})
        self.steps = 0

    @property
    def command_bar(self) -> float:
        """What the valve is asked for now [bar]."""
        if self.faults.valve_stuck_bar is not None:
            return self.faults.valve_stuck_bar
        if not self.gpio.level("valve_enable"):
            return 0.0  # vented
        return valve_command_bar(self.dac.output_volts, self.wiring.valve_bar_per_volt)

    def sync(self) -> None:
        """Integrate the plant up to the clock's now."""
        dt = self.params.dt_s
        now = self.clock.now()
        for hook in self.hooks:
            hook(now)
        command = self.command_bar
        while self._plant_time + dt <= now + 1e-12:
            self.state = update(self._plant_time, self.state, command, self.params)
            self._plant_time += dt
            self.steps += 1

    def outputs(self) -> Outputs:
        """True (noise-free) plant outputs now."""
        self.sync()
        return output(self._plant_time, self.state, self.params)

    def analog_volts(self, channel: int) -> float:
        """What the ADC input pin of ``channel`` sees now [V], sensor faults included."""
        mode = self.faults.sensors.get(channel)
        if mode == "stuck":
            return self.faults.stuck_volts.setdefault(channel, self._sensor_volts(channel))
        if mode == "saturated":
            return ADC_VDD + 0.3
        if mode == "disconnected":
            return ADC_VDD  # pulled up to the rail
        if mode == "detached":
            sensor = self.wiring.sensors[channel]
            value = self.faults.detached_at.setdefault(channel, getattr(self.outputs(), sensor.quantity))
            return sensor.volts(value + self._rng.normal(0.0, NOISE.get(sensor.quantity, 0.0)))
        return self._sensor_volts(channel)

    def _sensor_volts(self, channel: int) -> float:
        sensor = self.wiring.sensors.get(channel)
        if sensor is None:
            return 0.0  # nothing wired: the input sits at ground
        value = getattr(self.outputs(), sensor.quantity)
        return sensor.volts(value + self._rng.normal(0.0, NOISE.get(sensor.quantity, 0.0)))

    # fault switches -------------------------------------------------------------------------
    def fail_sensor(self, channel: int, mode: str | None) -> None:
        """``mode``: None (healthy), ``stuck``, ``saturated``, ``disconnected``, ``detached``."""
        if mode not in (None, "stuck", "saturated", "disconnected", "detached"):
            raise ValueError(f"sensor fault {mode!r} unknown")
        if mode == "detached" and channel not in self.wiring.sensors:
            raise ValueError(f"no sensor is wired on ADC input {channel}")
        self.faults.sensors[channel] = mode
        self.faults.stuck_volts.pop(channel, None)
        self.faults.detached_at.pop(channel, None)

    def stick_valve(self, stuck: bool = True) -> None:
        """The valve keeps its present command until released."""
        self.sync()
        self.faults.valve_stuck_bar = self.command_bar if stuck else None

    def drop_supply(self, supply_bar: float) -> None:
        self.sync()
        self.params = replace(self.params, supply_bar=supply_bar)

    def leak(self, pressure_gain: float) -> None:
        """From now the muscle holds ``pressure_gain`` of the pressure the transducer reads."""
        self.sync()
        self.params = replace(self.params, muscle_pressure_gain=pressure_gain)

    def press_estop(self, pressed: bool = True) -> None:
        self.gpio.drive_input("estop", pressed)
