"""The rig as data: buses, devices and named channels, read from the rig config.

* ``[buses.NAME]``: ``url`` (``i2c:///dev/i2c-1``, ``serial:///dev/ttyACM0``,
  ``gpiochip:///dev/gpiochip0`` or ``sim://rig?...``) and bus options (``hz`` for I2C,
  ``baud`` for serial, ``faults`` for ``sim://``).
* ``[devices.NAME]``: ``driver`` (a ``pmactl.drivers`` entry point: ``ads1115``, ``ads1015``,
  ``mcp4725``, ``gpio``, ``serial-daq`` or a lab's own), ``bus``, ``address`` and the driver's
  own options.
* ``[channels.NAME]``: ``device``, ``input`` (ADC input, GPIO offset), ``unit``, ``scale`` and
  ``zero`` (``value = (volts - zero) * scale``), optional ``min`` / ``max`` (the supervisor
  trips outside them) and ``active_low`` for lines. The controller uses ``contraction`` [mm],
  ``pressure`` [bar] (optional), ``valve`` [bar per volt of command], ``valve_enable`` and
  ``estop``; any other channel (a load cell, a temperature, a second muscle's sensors) is read,
  range-checked and logged each tick.
* An antagonistic joint (two muscles on a pulley) has ``angle`` [deg] instead of
  ``contraction``, a second valve ``valve_b`` [bar per volt] and optionally ``pressure_b``
  [bar]: the same loop with a joint control law (:mod:`edge.control.joint`).

The same table is the HIL's wiring: the emulated sensors produce ``value / scale + zero`` volts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from urllib.parse import urlsplit

from edge.errors import ConfigError

ANALOG_IN = "analog_in"
ANALOG_OUT = "analog_out"
LINE_IN = "line_in"
LINE_OUT = "line_out"
REQUIRED_CHANNELS = {"contraction": "mm", "valve": "bar", "estop": None, "valve_enable": None}
JOINT_REQUIRED_CHANNELS = {"angle": "deg", "valve": "bar", "valve_b": "bar", "estop": None, "valve_enable": None}
FIXED_UNITS = {"pressure": "bar", "pressure_b": "bar", "angle": "deg", "valve_b": "bar"}
OUTPUT_CHANNELS = ("valve", "valve_b", "valve_enable")
BUS_SCHEMES = ("i2c", "serial", "gpiochip", "sim")
SCALE_RANGE = (1e-6, 1e6)  # |units per volt| a real sensor or valve can have
ZERO_LIMIT_V = 100.0  # the reading at value 0 [V]; no converter here reads beyond this
NAME_CHARS = set("abcdefghijklmnopqrstuvwxyz0123456789_")


@dataclass(frozen=True)
class BusSpec:
    """One bus: its URL and options (``hz`` [Hz] for I2C, ``baud`` for serial)."""

    name: str
    url: str
    options: dict[str, object] = field(default_factory=dict)

    @property
    def scheme(self) -> str:
        return urlsplit(self.url).scheme

    @property
    def path(self) -> str:
        parts = urlsplit(self.url)
        return parts.path if parts.path else parts.netloc


@dataclass(frozen=True)
class DeviceSpec:
    """One chip or instrument on a bus; ``options`` are the driver's own keys."""

    name: str
    driver: str
    bus: str
    address: int | None = None
    options: dict[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class ChannelSpec:
    """A named signal of a device. ``value = (volts - zero) * scale`` for analog inputs;
    ``volts = value / scale`` for analog outputs; lines are 0/1 (``active_low`` inverts)."""

    name: str
    device: str
    input: int | None = None
    unit: str = ""
    scale: float = 1.0
    zero: float = 0.0
    minimum: float = -math.inf
    maximum: float = math.inf
    active_low: bool = False
    kind: str = ANALOG_IN

    @property
    def field(self) -> str:
        """The frame / telemetry column of this channel (``contraction_mm``, ``estop``)."""
        if self.kind == ANALOG_OUT:
            return "u_bar" if self.name == "valve" else f"{self.name}_{self.unit}"
        return f"{self.name}_{self.unit}" if self.kind == ANALOG_IN and self.unit else self.name


@dataclass(frozen=True)
class RigSpec:
    """The whole rig: buses, devices and channels in declaration order."""

    buses: tuple[BusSpec, ...]
    devices: tuple[DeviceSpec, ...]
    channels: tuple[ChannelSpec, ...]

    def bus(self, name: str) -> BusSpec:
        return next(b for b in self.buses if b.name == name)

    def device(self, name: str) -> DeviceSpec:
        return next(d for d in self.devices if d.name == name)

    def channel(self, name: str) -> ChannelSpec | None:
        return next((c for c in self.channels if c.name == name), None)

    def channels_of(self, device: str) -> tuple[ChannelSpec, ...]:
        return tuple(c for c in self.channels if c.device == device)

    @property
    def is_joint(self) -> bool:
        """An antagonistic joint: the controlled output is ``angle`` [deg], two valves."""
        return self.channel("angle") is not None

    @property
    def output_unit(self) -> str:
        """The unit of the controlled output: ``deg`` for a joint, else ``mm``."""
        return "deg" if self.is_joint else "mm"

    @property
    def output_field(self) -> str:
        """The frame field of the controlled output (``angle_deg`` or ``contraction_mm``)."""
        return "angle_deg" if self.is_joint else "contraction_mm"


def _table(raw: object, where: str, source: str) -> dict[str, object]:
    if not isinstance(raw, dict) or not raw:
        raise ConfigError(
            f"{source}: [{where}] must be a table with at least one entry; see docs/examples/hil-rig.toml"
        )
    return raw


def _name(name: str, where: str, source: str) -> str:
    if not name or not set(name) <= NAME_CHARS or name[0].isdigit():
        raise ConfigError(f"{source}: [{where}.{name}] names use a-z, 0-9 and _ and start with a letter")
    return name


def _number(table: dict[str, object], key: str, where: str, source: str, default: float | None = None) -> float:
    value = table.get(key, default)
    if value is None:
        raise ConfigError(f"{source}: [{where}] missing required key {key!r}")
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ConfigError(f"{source}: [{where}] {key} = {value!r} must be a finite number")
    return float(value)


def _pop_int(table: dict[str, object], key: str, where: str, source: str) -> int | None:
    value = table.pop(key, None)
    if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
        raise ConfigError(f"{source}: [{where}] {key} = {value!r} must be an integer")
    return value


def parse_rig(raw: dict[str, object], source: str, driver_kinds: dict[str, dict[str, str]]) -> RigSpec:
    """Build the :class:`RigSpec` of ``raw`` (the parsed TOML document).

    Args:
        driver_kinds: for each driver name, ``{channel field: kind}`` is not known before the
            driver is loaded, so the caller passes ``driver -> {"input": kind, "output": kind}``
            of every installed driver (see :func:`edge.drivers.registry.channel_kinds`).
    """
    buses = []
    for name, table in _table(raw.get("buses"), "buses", source).items():
        where = f"buses.{_name(name, 'buses', source)}"
        table = dict(_table(table, where, source))
        url = table.pop("url", None)
        if not isinstance(url, str) or urlsplit(url).scheme not in BUS_SCHEMES or not BusSpec(name, url).path:
            raise ConfigError(
                f"{source}: [{where}] url = {url!r} is not a known bus; use i2c:///dev/i2c-N, serial:///dev/ttyXXX, "
                "gpiochip:///dev/gpiochipN or sim://rig"
            )
        buses.append(BusSpec(name, url, table))
    bus_names = {b.name for b in buses}
    devices = []
    for name, table in _table(raw.get("devices"), "devices", source).items():
        where = f"devices.{_name(name, 'devices', source)}"
        table = dict(_table(table, where, source))
        driver, bus = table.pop("driver", None), table.pop("bus", None)
        if driver not in driver_kinds:
            raise ConfigError(
                f"{source}: [{where}] driver = {driver!r} is not installed; have {sorted(driver_kinds)} "
                "(pmactl.drivers entry points)"
            )
        if bus not in bus_names:
            raise ConfigError(f"{source}: [{where}] bus = {bus!r} is not a declared bus; have {sorted(bus_names)}")
        address = _pop_int(table, "address", where, source)
        devices.append(DeviceSpec(name, str(driver), str(bus), address, table))
    device_driver = {d.name: d.driver for d in devices}
    channels = []
    for name, table in _table(raw.get("channels"), "channels", source).items():
        where = f"channels.{_name(name, 'channels', source)}"
        table = dict(_table(table, where, source))
        known = {"device", "input", "unit", "scale", "zero", "min", "max", "active_low"}
        unknown = set(table) - known
        if unknown:
            raise ConfigError(f"{source}: [{where}] unknown key(s) {sorted(unknown)}; known: {sorted(known)}")
        device = table.get("device")
        if device not in device_driver:
            raise ConfigError(
                f"{source}: [{where}] device = {device!r} is not a declared device; have {sorted(device_driver)}"
            )
        role = "output" if name in OUTPUT_CHANNELS else "input"
        kind = driver_kinds[device_driver[str(device)]].get(role)
        if kind is None:
            raise ConfigError(
                f"{source}: [{where}] device {device!r} ({device_driver[str(device)]}) has no {role} channels"
            )
        if name in ("estop", "valve_enable"):
            kind = LINE_IN if role == "input" else LINE_OUT
        unit = table.get("unit", REQUIRED_CHANNELS.get(name) or FIXED_UNITS.get(name) or "")
        if not isinstance(unit, str) or not set(unit) <= NAME_CHARS | set("ABCDEFGHIJKLMNOPQRSTUVWXYZ"):
            raise ConfigError(f"{source}: [{where}] unit = {unit!r} must be a plain word (mm, bar, N, degC)")
        expected_unit = REQUIRED_CHANNELS.get(name) or FIXED_UNITS.get(name)
        if expected_unit and unit != expected_unit:
            raise ConfigError(f"{source}: [{where}] unit {unit!r}: the controller works in {expected_unit}")
        scale = _number(table, "scale", where, source, 1.0)
        if scale == 0 or (kind == ANALOG_OUT and scale < 0):
            raise ConfigError(
                f"{source}: [{where}] scale = {scale} must map volts to a range (non-zero; positive for outputs)"
            )
        if not SCALE_RANGE[0] <= abs(scale) <= SCALE_RANGE[1]:
            raise ConfigError(
                f"{source}: [{where}] scale = {scale:g} is outside +-{SCALE_RANGE[0]:g}..{SCALE_RANGE[1]:g} "
                f"{unit or 'units'} per volt; check the sensor's data sheet (value = (volts - zero) * scale)"
            )
        zero = _number(table, "zero", where, source, 0.0)
        if not -ZERO_LIMIT_V <= zero <= ZERO_LIMIT_V:
            raise ConfigError(f"{source}: [{where}] zero = {zero:g} must be a voltage within +-{ZERO_LIMIT_V:g} V")
        minimum = _number(table, "min", where, source, -1e300)
        maximum = _number(table, "max", where, source, 1e300)
        if not minimum < maximum:
            raise ConfigError(f"{source}: [{where}] min {minimum} >= max {maximum}; limits inverted")
        active_low = table.get("active_low", False)
        if not isinstance(active_low, bool):
            raise ConfigError(f"{source}: [{where}] active_low = {active_low!r} must be true or false")
        index = _pop_int(dict(table), "input", where, source)
        channels.append(
            ChannelSpec(
                name,
                str(device),
                index,
                unit,
                scale,
                zero,
                -math.inf if minimum == -1e300 else minimum,
                math.inf if maximum == 1e300 else maximum,
                active_low,
                kind,
            )
        )
    names = {c.name for c in channels}
    if "angle" in names and "contraction" in names:
        raise ConfigError(
            f"{source}: [channels] has both contraction and angle; a muscle controls contraction, a joint angle"
        )
    required = JOINT_REQUIRED_CHANNELS if "angle" in names else REQUIRED_CHANNELS
    missing = [n for n in required if n not in names]
    if missing:
        what = "the joint loop" if "angle" in names else "the loop"
        raise ConfigError(f"{source}: [channels] {', '.join(missing)} missing; {what} needs {', '.join(required)}")
    fields = [c.field for c in channels]
    if len(set(fields)) != len(fields):
        raise ConfigError(f"{source}: [channels] two channels share a telemetry column: {sorted(fields)}")
    return RigSpec(tuple(buses), tuple(devices), tuple(channels))
