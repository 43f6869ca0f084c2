"""The rig opened from its spec: buses by URL, one driver per device, and the per-tick
``read`` / ``write`` / ``prepare`` over all of them with every failure recorded in the frame.

Buses: ``i2c://`` (smbus2), ``serial://`` (pyserial), ``gpiochip://`` (libgpiod v2), and
``sim://`` through the ``pmactl.backends`` entry point (the HIL registers ``sim``), so ``edge``
never imports ``hil``. A driver's ``BusError`` or any ``OSError`` (libgpiod raises plain ones)
becomes the errno in ``rd_<device>`` / ``wr_<device>``; the supervisor decides what it means.
"""

from __future__ import annotations

import errno
import math
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any, Protocol

from edge.control.law import TickFrame
from edge.drivers.base import Device, installed_drivers
from edge.errors import ConfigError
from edge.hal.clock import Clock, MonotonicClock
from edge.runtime.config import RigConfig
from edge.runtime.frame import FrameLayout
from edge.runtime.rigspec import ANALOG_IN, LINE_IN, LINE_OUT, BusSpec, RigSpec

BACKENDS_GROUP = "pmactl.backends"


class SimBackend(Protocol):
    """What a ``pmactl.backends`` plug-in returns for its buses."""

    clock: Clock
    lockstep: bool  # True: the clock is simulated, waiting is free and exact

    def handle(self, bus: BusSpec, kind: str) -> Any:
        """The bus object a driver of ``kind`` (``i2c``, ``gpio``, ``serial``) talks to."""

    def close(self) -> None: ...


@dataclass
class Rig:
    """Opened devices in declaration order (see the module docstring)."""

    devices: list[Device]
    clock: Clock
    lockstep: bool
    layout: FrameLayout
    spec: RigSpec
    device: Any = None  # the backend plug-in object (the HIL: tests reach its faults there)
    closers: list[Any] = field(default_factory=list)
    errors: dict[str, str] = field(default_factory=dict)  # latest failure message per device

    def __post_init__(self) -> None:
        channels: dict[str, list[str]] = {d.name: [] for d in self.devices}
        for c in self.spec.channels:
            if c.kind in (ANALOG_IN, LINE_IN):
                channels[c.device].append(c.field)
        status = {dev: (rd, wr) for dev, rd, wr in self.layout.status_fields}
        self._readers = [(d, status[d.name][0], tuple(channels[d.name])) for d in self.devices if channels[d.name]]
        self._writers = [(d, status[d.name][1]) for d in self.devices]
        self._pending_errors: dict[str, int] = {}

    def _record(self, device: Device, exc: OSError) -> int:
        self.errors[device.name] = str(exc)
        return exc.errno or errno.EIO

    def read(self, frame: TickFrame) -> None:
        """Every input device into ``frame``; a failed device's channels become NaN."""
        pending = self._pending_errors
        for device, status, fields in self._readers:
            try:
                device.read(frame)
                code = pending.pop(device.name, 0) if pending else 0
            except OSError as exc:
                code = self._record(device, exc)
                for name in fields:
                    setattr(frame, name, math.nan)
            setattr(frame, status, code)

    def write(self, frame: TickFrame) -> None:
        """Every device's outputs from ``frame``; the result stays in ``wr_<device>``."""
        for device, status in self._writers:
            try:
                device.write(frame)
                setattr(frame, status, 0)
            except OSError as exc:
                setattr(frame, status, self._record(device, exc))

    def prepare(self, frame: TickFrame) -> None:
        """Start the next conversions (pipelining); a failure shows in the next read's status."""
        for device, _, _ in self._readers:
            try:
                device.prepare(frame)
            except OSError as exc:
                self._pending_errors[device.name] = self._record(device, exc)

    def vent(self) -> None:
        """Best effort safe state: line outputs (valve enable) first, then the DACs. Never raises:
        a device that fails to vent is recorded in ``errors`` and the next one is still vented
        (drivers arrive by entry point, so "vent never raises" is not something to trust)."""
        for device in sorted(self.devices, key=lambda d: getattr(type(d), "output_kind", None) != LINE_OUT):
            try:
                device.vent()
            except Exception as exc:  # noqa: BLE001 - every valve must get its vent call
                self.errors[device.name] = f"vent failed: {exc}"

    def close(self) -> None:
        """Vent, then release every device and bus (each tried even if one fails)."""
        self.vent()
        for item in [*self.devices, *self.closers]:
            try:
                item.close()
            except Exception:  # noqa: BLE001 - closing must reach every device and bus
                pass


def _open_bus(bus: BusSpec, config: RigConfig) -> Any:
    scheme = bus.scheme
    if scheme == "i2c":
        from edge.hal.i2c import SMBus2I2C

        return SMBus2I2C(bus.path)
    if scheme == "serial":
        from edge.hal.serial import PySerialLink

        return PySerialLink(bus.path, int(bus.options.get("baud", 921_600)))  # type: ignore[call-overload]
    if scheme == "gpiochip":
        from edge.drivers.lines import GpioChip

        return GpioChip(bus.path)
    raise ConfigError(f"{config.source}: [buses.{bus.name}] scheme {scheme!r} has no opener")


def _open_sim(buses: list[BusSpec], config: RigConfig) -> SimBackend:
    plugins = {ep.name: ep for ep in entry_points(group=BACKENDS_GROUP)}
    if "sim" not in plugins:
        raise ConfigError(
            f"{config.source}: [buses.{buses[0].name}] {buses[0].url!r}: no backend plug-in 'sim' installed "
            f"(have: {sorted(plugins) or 'none'}); install pmactl with its HIL for sim://"
        )
    backend: SimBackend = plugins["sim"].load()(buses, config)
    return backend


def open_rig(config: RigConfig, layout: FrameLayout, clock: Clock | None = None, lockstep: bool = False) -> Rig:
    """Open every bus and device of ``config.rig`` (see the module docstring).

    ``clock`` / ``lockstep``: run a rig without ``sim://`` buses on another clock (a HIL that
    serves a real pty on its simulated clock); by default the sim backend's clock, else the
    wall clock."""
    spec = config.rig
    drivers = installed_drivers()
    sim_buses = [b for b in spec.buses if b.scheme == "sim"]
    opened: list[Any] = []
    devices: list[Device] = []
    try:
        sim = _open_sim(sim_buses, config) if sim_buses else None
        if sim is not None:
            opened.append(sim)
        if clock is None:
            clock = sim.clock if sim is not None else MonotonicClock()
        else:
            lockstep = lockstep or (sim is not None and sim.lockstep)
        handles: dict[str, Any] = {}
        for bus in spec.buses:
            if bus.scheme != "sim":
                handles[bus.name] = _open_bus(bus, config)
                opened.append(handles[bus.name])
        for device in spec.devices:
            cls = drivers[device.driver]
            bus = spec.bus(device.bus)
            handle = sim.handle(bus, cls.bus_kind) if bus.scheme == "sim" and sim is not None else handles[bus.name]
            devices.append(cls(device, spec.channels_of(device.name), handle, clock))
    except BaseException:
        for item in [*devices, *opened]:
            try:
                item.close()
            except Exception:  # noqa: BLE001 - best effort while failing to open
                pass
        raise
    return Rig(devices, clock, lockstep or (sim.lockstep if sim is not None else False), layout, spec, sim, opened)
