"""What a ``pmactl.drivers`` entry point provides, and the registry that loads them.

A driver class is built with ``(spec, channels, bus, clock)``: its :class:`DeviceSpec`, its
channels from the rig config, the opened bus handle and the clock port. Per tick the runtime
calls ``read(frame)`` (fill the input channels' fields), later ``write(frame)`` (drive the
outputs from the command fields) and ``prepare(frame)`` (start the next conversion, so the next
``read`` finds it done). Failures raise :class:`~edge.errors.BusError`; the runtime records the
errno in the frame (``rd_<device>`` / ``wr_<device>``) and the supervisor sees it.

``wire_time(spec, channels, bus)`` is a classmethod: the time one tick spends on this device's
wires and conversions [s] with a one-line breakdown, so the fastest loop period is a sum over
devices, known before any hardware is opened.
"""

from __future__ import annotations

from importlib.metadata import entry_points
from typing import Any, ClassVar, Protocol

from edge.control.law import TickFrame
from edge.errors import ConfigError
from edge.runtime.rigspec import BusSpec, ChannelSpec, DeviceSpec
from edge.runtime.wire import WireTime

ENTRY_POINT_GROUP = "pmactl.drivers"


class Device(Protocol):
    """An opened device (see the module docstring)."""

    name: str

    def read(self, frame: TickFrame) -> None: ...

    def write(self, frame: TickFrame) -> None: ...

    def prepare(self, frame: TickFrame) -> None: ...

    def vent(self) -> None:
        """Best effort safe output (valve closed / disabled); never raises."""

    def close(self) -> None: ...


class DriverClass(Protocol):
    """The class an entry point names."""

    input_kind: ClassVar[str | None]
    output_kind: ClassVar[str | None]
    option_keys: ClassVar[frozenset[str]]
    bus_schemes: ClassVar[frozenset[str]]
    bus_kind: ClassVar[str]  # the bus handle it needs: "i2c", "gpio" or "serial"

    def __call__(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: Any, clock: Any) -> Device: ...

    def wire_time(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec) -> WireTime: ...

    def check(self, spec: DeviceSpec, channels: tuple[ChannelSpec, ...], bus: BusSpec, source: str) -> None: ...


def installed_drivers() -> dict[str, DriverClass]:
    """Every ``pmactl.drivers`` entry point, loaded (name -> driver class)."""
    drivers: dict[str, DriverClass] = {}
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        try:
            drivers[ep.name] = ep.load()
        except Exception as exc:  # noqa: BLE001 - a broken third-party driver must not hide the others
            raise ConfigError(f"driver plug-in {ep.name!r} ({ep.value}) cannot be loaded: {exc}") from exc
    return drivers


def channel_kinds(drivers: dict[str, DriverClass]) -> dict[str, dict[str, str]]:
    """driver -> {"input": kind, "output": kind} for :func:`edge.runtime.rigspec.parse_rig`."""
    kinds: dict[str, dict[str, str]] = {}
    for name, cls in drivers.items():
        kinds[name] = {}
        if cls.input_kind:
            kinds[name]["input"] = cls.input_kind
        if cls.output_kind:
            kinds[name]["output"] = cls.output_kind
    return kinds


def option(spec: DeviceSpec, key: str, default: Any, kind: type, source: str) -> Any:
    """A driver option with its type checked (numbers finite)."""
    value = spec.options.get(key, default)
    ok = isinstance(value, kind) and not (kind is not bool and isinstance(value, bool))
    if kind is float:
        ok = (
            isinstance(value, int | float)
            and not isinstance(value, bool)
            and value == value
            and abs(value) != float("inf")
        )
    if not ok:
        raise ConfigError(f"{source}: [devices.{spec.name}] {key} = {value!r} must be {kind.__name__}")
    return float(value) if kind is float else value  # type: ignore[arg-type]


def check_inputs(channels: tuple[ChannelSpec, ...], low: int, high: int, what: str, source: str) -> None:
    """Every channel's ``input`` an integer in ``low..high`` and no two the same; one line
    naming the channel key otherwise (``what`` says what an input is on this device)."""
    seen: dict[int, str] = {}
    for c in channels:
        if c.input is None:
            raise ConfigError(f"{source}: [channels.{c.name}] input missing; give {what} ({low}..{high})")
        if not low <= c.input <= high:
            raise ConfigError(f"{source}: [channels.{c.name}] input = {c.input} must be {what} in {low}..{high}")
        if c.input in seen:
            raise ConfigError(
                f"{source}: [channels.{c.name}] input = {c.input} is already [channels.{seen[c.input]}]'s; "
                "give each channel its own"
            )
        seen[c.input] = c.name


def check_address(spec: DeviceSpec, allowed: range, chip: str, source: str) -> None:
    """The device's I2C ``address`` one its chip can answer at (when given)."""
    if spec.address is not None and spec.address not in allowed:
        raise ConfigError(
            f"{source}: [devices.{spec.name}] address = {spec.address:#04x} is not an {chip} address; "
            f"use {allowed[0]:#04x}..{allowed[-1]:#04x} (its address pins)"
        )
