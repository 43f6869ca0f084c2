"""The serial DAQ (``docs/serial-daq.md``) as a runtime device (``pmactl.drivers``:
``serial-daq``): input 0 is the pressure converter, input 1 the displacement converter,
``estop`` the status bit; ``valve`` and ``valve_enable`` go out in one COMMAND frame."""

from __future__ import annotations

import math
from typing import ClassVar

from edge.control.law import TickFrame
from edge.devices.daq_client import DaqClient
from edge.devices.daq_protocol import COMMAND_FORMAT, SAMPLE_FORMAT
from edge.drivers.base import option
from edge.errors import ConfigError
from edge.hal.clock import Clock
from edge.hal.serial import SerialLink
from edge.runtime.rigspec import ANALOG_IN, ANALOG_OUT, LINE_IN, BusSpec, ChannelSpec, DeviceSpec
from edge.runtime.wire import WireTime

UART_BITS_PER_BYTE = 10  # start + 8 data + stop
FRAME_OVERHEAD_BYTES = 8  # sync 2, len 1, seq 2, type 1, crc 2


class SerialDaqDevice:
    """One DAQ on a ``serial://`` bus (options ``sample_rate_hz``, ``timeout_s``, ``vdd_v``)."""

    input_kind: ClassVar[str | None] = ANALOG_IN
    output_kind: ClassVar[str | None] = ANALOG_OUT
    option_keys: ClassVar[frozenset[str]] = frozenset({"sample_rate_hz", "timeout_s", "vdd_v"})
    bus_schemes: ClassVar[frozenset[str]] = frozenset({"serial"})
    bus_kind: ClassVar[str] = "serial"

    @classmethod
    def check(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec, source: str) -> None:
        rate = option(spec, "sample_rate_hz", 1000, int, source)
        timeout = option(spec, "timeout_s", 0.002, float, source)
        vdd = option(spec, "vdd_v", 5.0, float, source)
        baud = bus.options.get("baud", 921_600)
        if isinstance(baud, bool) or not isinstance(baud, int) or not 9600 <= baud <= 12_000_000:
            raise ConfigError(f"{source}: [buses.{bus.name}] baud = {baud!r} must be an integer in 9600..12000000")
        if not 1 <= rate <= 65535 or not 0 < timeout <= 1.0 or not 0 < vdd <= 24:
            raise ConfigError(
                f"{source}: [devices.{spec.name}] sample_rate_hz 1..65535, timeout_s in (0, 1] and vdd_v in (0, 24] "
                f"(got {rate}, {timeout}, {vdd})"
            )
        for c in channels:
            if c.kind == ANALOG_IN and c.input not in (0, 1):
                raise ConfigError(f"{source}: [channels.{c.name}] the DAQ has inputs 0 (pressure) and 1 (displacement)")

    @classmethod
    def wire_time(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec) -> WireTime:
        baud = int(bus.options.get("baud", 921_600))  # type: ignore[call-overload]
        rate = int(spec.options.get("sample_rate_hz", 1000))  # type: ignore[call-overload]
        wire_bytes = SAMPLE_FORMAT.size + COMMAND_FORMAT.size + 2 * FRAME_OVERHEAD_BYTES
        wire_s = wire_bytes * UART_BITS_PER_BYTE / baud
        return WireTime(
            wire_s,
            1.0 / rate,
            f"{spec.name} (serial DAQ): one sample every {1e3 / rate:.3f} ms; {wire_bytes} bytes on the wire per "
            f"tick take {wire_s * 1e3:.3f} ms at {baud} baud",
        )

    def __init__(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: SerialLink, clock: Clock) -> None:
        opts = spec.options
        self.name = spec.name
        self.link = bus
        self.client = DaqClient(bus, clock, int(opts.get("sample_rate_hz", 1000)), float(opts.get("timeout_s", 0.002)))  # type: ignore[call-overload, arg-type]
        self._vdd = float(opts.get("vdd_v", 5.0))  # type: ignore[arg-type]
        self._analog = [(c.input, c.field, c.scale, c.zero) for c in channels if c.kind == ANALOG_IN]
        self._lines = [c.field for c in channels if c.kind == LINE_IN]
        out = [c for c in channels if c.kind == ANALOG_OUT]
        self._valve = (out[0].field, out[0].scale) if out else None
        enable = [c.field for c in channels if c.name == "valve_enable"]
        self._enable = enable[0] if enable else None

    def read(self, frame: TickFrame) -> None:
        sample = self.client.read()
        for index, field, scale, zero in self._analog:
            volts = sample.pressure_volts if index == 0 else sample.displacement_volts
            setattr(frame, field, (volts - zero) * scale)
        for field in self._lines:
            setattr(frame, field, 1.0 if sample.estop else 0.0)

    def prepare(self, frame: TickFrame) -> None:
        """The DAQ converts on its own clock."""

    def write(self, frame: TickFrame) -> None:
        enabled = self._enable is not None and getattr(frame, self._enable) == 1.0
        volts = 0.0
        if self._valve is not None and enabled:
            value = getattr(frame, self._valve[0])
            volts = value / self._valve[1] if math.isfinite(value) else 0.0
        self.client.command(round(volts / self._vdd * 4096), enabled)

    def vent(self) -> None:
        try:
            self.client.command(0, False)
        except Exception:  # noqa: BLE001 - best effort; the DAQ vents on its own command timeout
            pass

    def close(self) -> None:
        self.vent()
