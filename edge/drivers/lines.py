"""GPIO lines as a runtime device (``pmactl.drivers``: ``gpio``): ``estop`` and other inputs
read as 1.0 (active) / 0.0, ``valve_enable`` and other outputs driven from the frame.

The bus handle offers ``request(outputs, inputs, active_low) -> GpioLines``: libgpiod v2 for
``gpiochip://`` (:class:`GpioChip`), the emulated lines for ``sim://``.
"""

from __future__ import annotations

from typing import Any, ClassVar

from edge.control.law import TickFrame
from edge.drivers.base import check_inputs
from edge.hal.clock import Clock
from edge.hal.gpio import GpioLines
from edge.runtime.rigspec import LINE_IN, LINE_OUT, BusSpec, ChannelSpec, DeviceSpec
from edge.runtime.wire import WireTime

MAX_LINE_OFFSET = 1023  # gpiochips of SBCs have up to a few hundred lines


class GpioChip:
    """A ``gpiochip://`` bus: lines are requested by the device that uses them."""

    def __init__(self, path: str) -> None:
        self.path = path

    def request(self, outputs: dict[str, int], inputs: dict[str, int], active_low: frozenset[str]) -> GpioLines:
        from edge.hal.gpio import GpiodLines

        return GpiodLines(self.path, outputs=outputs, inputs=inputs, active_low=active_low)

    def close(self) -> None:
        """Lines are released by their device."""


class GpioDevice:
    """Named lines on one chip (``input`` = the line offset)."""

    input_kind: ClassVar[str | None] = LINE_IN
    output_kind: ClassVar[str | None] = LINE_OUT
    option_keys: ClassVar[frozenset[str]] = frozenset()
    bus_schemes: ClassVar[frozenset[str]] = frozenset({"gpiochip", "sim"})
    bus_kind: ClassVar[str] = "gpio"

    @classmethod
    def check(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec, source: str) -> None:
        check_inputs(channels, 0, MAX_LINE_OFFSET, "a GPIO line offset", source)

    @classmethod
    def wire_time(cls, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec) -> WireTime:
        return WireTime(0.0, 0.0, f"{spec.name} (GPIO): memory-mapped, no wire time")

    def __init__(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: Any, clock: Clock) -> None:
        self.name = spec.name
        outputs = {c.name: c.input or 0 for c in channels if c.kind == LINE_OUT}
        inputs = {c.name: c.input or 0 for c in channels if c.kind == LINE_IN}
        low = frozenset(c.name for c in channels if c.active_low)
        self.lines: GpioLines = bus.request(outputs, inputs, low)
        self._inputs = [(c.name, c.field) for c in channels if c.kind == LINE_IN]
        self._outputs = [(c.name, c.field) for c in channels if c.kind == LINE_OUT]

    def read(self, frame: TickFrame) -> None:
        get = self.lines.get
        for name, field in self._inputs:
            setattr(frame, field, 1.0 if get(name) else 0.0)

    def prepare(self, frame: TickFrame) -> None:
        """Nothing to start."""

    def write(self, frame: TickFrame) -> None:
        for name, field in self._outputs:
            self.lines.set(name, getattr(frame, field) == 1.0)

    def vent(self) -> None:
        for name, _ in self._outputs:
            try:
                self.lines.set(name, False)
            except Exception:  # noqa: BLE001 - venting tries every line
                pass

    def close(self) -> None:
        self.vent()
        self.lines.close()
