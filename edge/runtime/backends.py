"""Open the rig a config names: the plug-in point between the runtime and the hardware.

``i2c://`` and ``serial://`` open Linux devices. ``sim://`` and any other scheme are looked up
in the ``pmactl.backends`` entry-point group (the HIL registers ``sim``), so ``edge`` never
imports ``hil`` and a lab can plug in its own rig the same way.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import Protocol
from urllib.parse import urlsplit

from edge.errors import ConfigError
from edge.hal.clock import Clock, MonotonicClock
from edge.hal.gpio import GpioLines
from edge.hal.i2c import I2CBus
from edge.runtime.config import RigConfig
from edge.runtime.rigio import I2CRigIO, RigIO, SerialRigIO

ENTRY_POINT_GROUP = "pmactl.backends"


class PluginRig(Protocol):
    """What a ``pmactl.backends`` plug-in returns: an I2C bus, GPIO lines and the clock to run on."""

    bus: I2CBus
    gpio: GpioLines
    clock: Clock
    lockstep: bool  # True: the clock is simulated, waiting is free and exact


@dataclass
class OpenedRig:
    """The rig ready to run: its I/O, its clock, and the plug-in object (tests reach faults there)."""

    io: RigIO
    clock: Clock
    lockstep: bool
    device: object = None


def _device_path(url: str) -> str:
    parts = urlsplit(url)
    return parts.path if parts.path else parts.netloc


def open_rig(config: RigConfig) -> OpenedRig:
    """Open the backends of ``config.rig`` (see the module docstring)."""
    scheme = config.io_scheme
    if scheme == "serial":
        from edge.hal.serial import PySerialLink

        clock = MonotonicClock()
        link = PySerialLink(_device_path(config.rig.io), config.serial.baud)
        return OpenedRig(SerialRigIO(link, clock, config), clock, lockstep=False)
    if scheme == "i2c":
        from edge.hal.gpio import GpiodLines
        from edge.hal.i2c import SMBus2I2C

        clock = MonotonicClock()
        bus = SMBus2I2C(_device_path(config.rig.io))
        lines = config.gpio_lines
        gpio = GpiodLines(
            _device_path(config.rig.gpio),
            outputs={"valve_enable": lines.valve_enable},
            inputs={"estop": lines.estop},
            active_low=frozenset(lines.active_low),
        )
        return OpenedRig(I2CRigIO(bus, clock, gpio, config), clock, lockstep=False)
    plugins = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    if scheme not in plugins:
        raise ConfigError(
            f"{config.source}: [rig] io = {config.rig.io!r}: no backend plug-in {scheme!r} installed "
            f"(have: {sorted(plugins) or 'none'}); install pmactl with its HIL for sim://"
        )
    rig: PluginRig = plugins[scheme].load()(config.rig.io, config)
    return OpenedRig(I2CRigIO(rig.bus, rig.clock, rig.gpio, config), rig.clock, rig.lockstep, rig)
