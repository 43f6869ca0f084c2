"""ADS1115 / ADS1015 ADC and MCP4725 DAC as runtime devices (``pmactl.drivers``: ``ads1115``,
``ads1015``, ``mcp4725``), on the chip drivers of :mod:`edge.devices`.

Pipelining (``pipeline = true``, the default): at the end of each tick the ADC starts the
conversion of its first declared channel, so the next tick's read collects it without waiting.
Further channels of the same chip share its single converter and are converted in the read
(one conversion period each); the fastest-period sum says so. Declare the channel whose age
matters least (pressure) first; give a second time-critical sensor its own converter.
"""

from __future__ import annotations

import math
from typing import ClassVar

from edge.control.law import TickFrame
from edge.devices.ads1x15 import DATA_RATES, FULL_SCALE_V, ADS1x15
from edge.devices.mcp4725 import MCP4725
from edge.drivers.base import check_address, check_inputs, option
from edge.errors import ConfigError
from edge.hal.clock import Clock
from edge.hal.i2c import I2CBus
from edge.runtime.rigspec import ANALOG_IN, ANALOG_OUT, BusSpec, ChannelSpec, DeviceSpec
from edge.runtime.wire import WireTime

ADS1X15_ADDRESSES = range(0x48, 0x4C)  # ADDR pin to GND, VDD, SDA, SCL
MCP4725_ADDRESSES = range(0x60, 0x68)  # A0 (and the factory-set A1, A2)


def _bus_hz(bus: BusSpec, source: str) -> float:
    hz = bus.options.get("hz", 400_000)
    if isinstance(hz, bool) or not isinstance(hz, int | float) or not 10_000 <= hz <= 5_000_000:
        raise ConfigError(f"{source}: [buses.{bus.name}] hz = {hz!r} must be an I2C clock in 10000..5000000 Hz")
    return float(hz)


class ADS1x15Device:
    """One ADS1x15 and its analog input channels (``input`` = AIN0..AIN3 against GND)."""

    input_kind: ClassVar[str | None] = ANALOG_IN
    output_kind: ClassVar[str | None] = None
    option_keys: ClassVar[frozenset[str]] = frozenset({"data_rate_sps", "full_scale_v", "pipeline"})
    bus_schemes: ClassVar[frozenset[str]] = frozenset({"i2c", "sim"})
    bus_kind: ClassVar[str] = "i2c"
    variant: ClassVar[str] = "ADS1115"

    @classmethod
    def check(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec, source: str) -> None:
        rates = DATA_RATES[cls.variant]
        rate = option(spec, "data_rate_sps", max(rates), int, source)
        if rate not in rates:
            raise ConfigError(f"{source}: [devices.{spec.name}] {cls.variant} has no {rate} SPS; use one of {rates}")
        fsr = option(spec, "full_scale_v", 4.096, float, source)
        if fsr not in FULL_SCALE_V:
            raise ConfigError(
                f"{source}: [devices.{spec.name}] full_scale_v {fsr} is not one of {sorted(FULL_SCALE_V)}"
            )
        option(spec, "pipeline", True, bool, source)
        check_address(spec, ADS1X15_ADDRESSES, cls.variant, source)
        check_inputs(channels, 0, 3, f"the {cls.variant}'s AIN input", source)
        for c in channels:  # volts = value / scale + zero must be a voltage the chip can read
            if not -fsr <= c.zero <= fsr:
                raise ConfigError(
                    f"{source}: [channels.{c.name}] zero = {c.zero:g} V is outside the {cls.variant}'s "
                    f"+-{fsr:g} V (full_scale_v); zero is the reading in volts at value 0"
                )
        _bus_hz(bus, source)

    @classmethod
    def wire_time(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec) -> WireTime:
        rate = int(spec.options.get("data_rate_sps", max(DATA_RATES[cls.variant])))  # type: ignore[call-overload]
        pipelined = bool(spec.options.get("pipeline", True))
        conversion_s = 1.0 / rate
        hz = float(bus.options.get("hz", 400_000))  # type: ignore[arg-type]
        waits = max(0, len(channels) - 1) if pipelined else len(channels)
        bus_s = len(channels) * ADS1x15.read_bus_bits() / hz
        text = (
            f"{spec.name} ({cls.variant} at {rate} SPS): {waits} conversion wait(s) of {conversion_s * 1e3:.3f} ms"
            f"{' (first channel pipelined)' if pipelined else ''}, {bus_s * 1e3:.3f} ms of I2C at {hz / 1e3:g} kHz"
        )
        return WireTime(waits * conversion_s + bus_s, conversion_s if pipelined else 0.0, text)

    def __init__(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: I2CBus, clock: Clock) -> None:
        opts = spec.options
        self.name = spec.name
        self.adc = ADS1x15(
            bus,
            clock,
            address=spec.address if spec.address is not None else 0x48,
            variant=self.variant,
            full_scale_v=float(opts.get("full_scale_v", 4.096)),  # type: ignore[arg-type]
            data_rate_sps=int(opts.get("data_rate_sps", max(DATA_RATES[self.variant]))),  # type: ignore[call-overload]
        )
        self.pipeline = bool(opts.get("pipeline", True))
        self._channels = [(c.input, c.field, c.scale, c.zero) for c in channels]
        self._pending = False

    def read(self, frame: TickFrame) -> None:
        adc = self.adc
        for i, (channel, field, scale, zero) in enumerate(self._channels):
            if i == 0 and self._pending:
                self._pending = False
                volts = adc.finish_volts()
            else:
                volts = adc.read_volts(channel)  # type: ignore[arg-type]
            setattr(frame, field, (volts - zero) * scale)

    def prepare(self, frame: TickFrame) -> None:
        if self.pipeline and self._channels:
            self._pending = False
            self.adc.start_single(self._channels[0][0])  # type: ignore[arg-type]
            self._pending = True

    def write(self, frame: TickFrame) -> None:
        """No outputs."""

    def vent(self) -> None:
        """No outputs."""

    def close(self) -> None:
        """The bus is closed by the runtime."""


class ADS1115Device(ADS1x15Device):
    variant: ClassVar[str] = "ADS1115"


class ADS1015Device(ADS1x15Device):
    variant: ClassVar[str] = "ADS1015"


class MCP4725Device:
    """The valve command DAC: ``volts = u_bar / scale`` of its ``valve`` channel (0 when vented)."""

    input_kind: ClassVar[str | None] = None
    output_kind: ClassVar[str | None] = ANALOG_OUT
    option_keys: ClassVar[frozenset[str]] = frozenset({"vdd_v"})
    bus_schemes: ClassVar[frozenset[str]] = frozenset({"i2c", "sim"})
    bus_kind: ClassVar[str] = "i2c"

    @classmethod
    def check(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec, source: str) -> None:
        vdd = option(spec, "vdd_v", 5.0, float, source)
        if not 2.7 <= vdd <= 5.5:
            raise ConfigError(f"{source}: [devices.{spec.name}] vdd_v = {vdd} outside the MCP4725's 2.7..5.5 V")
        if len(channels) != 1:
            raise ConfigError(f"{source}: [devices.{spec.name}] an MCP4725 drives one channel, not {len(channels)}")
        check_address(spec, MCP4725_ADDRESSES, "MCP4725", source)
        (channel,) = channels
        if channel.input is not None:
            raise ConfigError(
                f"{source}: [channels.{channel.name}] input = {channel.input}: an MCP4725 has one output; drop input"
            )
        _bus_hz(bus, source)

    @classmethod
    def wire_time(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec) -> WireTime:
        hz = float(bus.options.get("hz", 400_000))  # type: ignore[arg-type]
        wire_s = MCP4725.write_bus_bits() / hz
        return WireTime(wire_s, 0.0, f"{spec.name} (MCP4725): {wire_s * 1e3:.3f} ms of I2C")

    def __init__(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: I2CBus, clock: Clock) -> None:
        self.name = spec.name
        self.dac = MCP4725(
            bus,
            address=spec.address if spec.address is not None else 0x60,
            vdd=float(spec.options.get("vdd_v", 5.0)),  # type: ignore[arg-type]
        )
        (channel,) = channels
        self._field, self._bar_per_volt = channel.field, channel.scale

    def read(self, frame: TickFrame) -> None:
        """No inputs."""

    def prepare(self, frame: TickFrame) -> None:
        """Nothing to start."""

    def write(self, frame: TickFrame) -> None:
        value = getattr(frame, self._field)
        self.dac.write_volts(value / self._bar_per_volt if math.isfinite(value) else 0.0)

    def vent(self) -> None:
        try:
            self.dac.write_code(0)
        except Exception:  # noqa: BLE001 - venting tries every path even if one fails
            pass

    def close(self) -> None:
        self.vent()
