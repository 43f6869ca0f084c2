"""Rig configs in the first format (``[rig] io = URL``, ``[adc]``, ``[dac]``, ``[serial]``,
``[sensors.*]``, ``[valve]``, ``[gpio_lines]``), translated to buses, devices and channels so
that existing files keep working. New configs use the tables of :mod:`edge.runtime.rigspec`."""

from __future__ import annotations

import difflib
from urllib.parse import urlsplit

from edge.errors import ConfigError

LEGACY_SECTIONS = {
    "rig": {"io", "gpio", "i2c_bus_hz"},
    "adc": {"chip", "address", "data_rate_sps", "full_scale_v"},
    "dac": {"chip", "address", "vdd_v"},
    "serial": {"baud", "sample_rate_hz", "timeout_s"},
    "sensors": {"contraction", "pressure"},
    "valve": {"bar_per_volt"},
    "gpio_lines": {"valve_enable", "estop", "active_low"},
}
SENSOR_KEYS = {
    "contraction": ("mm_per_volt", "volts_at_zero_mm", "mm"),
    "pressure": ("bar_per_volt", "volts_at_zero_bar", "bar"),
}


def is_legacy(raw: dict[str, object]) -> bool:
    return "rig" in raw or "sensors" in raw


def _section(raw: dict[str, object], name: str, source: str) -> dict[str, object]:
    table = raw.pop(name, {})
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: [{name}] must be a table")
    for key in table:
        if key not in LEGACY_SECTIONS[name]:
            close = difflib.get_close_matches(key, LEGACY_SECTIONS[name], n=1)
            hint = (
                f"; did you mean {close[0]!r}?"
                if close
                else f"; known keys: {', '.join(sorted(LEGACY_SECTIONS[name]))}"
            )
            raise ConfigError(f"{source}: [{name}] unknown key {key!r}{hint}")
    return dict(table)


def _sensor(table: object, name: str, device: str, source: str) -> dict[str, object]:
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: [sensors.{name}] must be a table")
    scale_key, zero_key, unit = SENSOR_KEYS[name]
    expected = {"channel", scale_key, zero_key}
    for key in table:
        if key not in expected:
            raise ConfigError(
                f"{source}: [sensors.{name}] unknown key {key!r}; known keys: {', '.join(sorted(expected))}"
            )
    missing = expected - set(table)
    if missing:
        raise ConfigError(f"{source}: [sensors.{name}] missing required key {sorted(missing)[0]!r}")
    return {
        "device": device,
        "input": table["channel"],
        "unit": unit,
        "scale": table[scale_key],
        "zero": table[zero_key],
    }


def translate_legacy(raw: dict[str, object], source: str) -> dict[str, object]:
    """The same rig in the buses / devices / channels tables (other sections unchanged)."""
    raw = dict(raw)
    if any(k in raw for k in ("buses", "devices", "channels")):
        raise ConfigError(f"{source}: mixes [rig]/[sensors] with [buses]/[devices]/[channels]; use one format")
    for section in ("rig", "valve", "sensors"):
        if section not in raw:
            raise ConfigError(f"{source}: section [{section}] missing; see docs/examples/hil-rig.toml")
    rig, adc, dac = (_section(raw, n, source) for n in ("rig", "adc", "dac"))
    serial, sensors, valve, lines = (_section(raw, n, source) for n in ("serial", "sensors", "valve", "gpio_lines"))
    if "contraction" not in sensors:
        raise ConfigError(f"{source}: [sensors.contraction] missing; the edge needs the volts -> mm calibration")
    if "bar_per_volt" not in valve:
        raise ConfigError(f"{source}: [valve] missing required key 'bar_per_volt'")
    io = rig.get("io")
    if not isinstance(io, str):
        raise ConfigError(f"{source}: [rig] missing required key 'io'")
    scheme = urlsplit(io).scheme
    if scheme not in ("i2c", "serial", "sim"):
        raise ConfigError(
            f"{source}: [rig] io = {io!r} is not a known backend; use i2c:///dev/i2c-N, serial:///dev/ttyXXX or sim://rig"
        )
    buses: dict[str, object] = {}
    devices: dict[str, dict[str, object]] = {}
    channels: dict[str, object] = {}
    if scheme == "serial":
        buses["daq"] = {"url": io, **({"baud": serial["baud"]} if "baud" in serial else {})}
        options: dict[str, object] = {k: v for k, v in serial.items() if k in ("sample_rate_hz", "timeout_s")}
        devices["daq"] = {"driver": "serial-daq", "bus": "daq", "vdd_v": dac.get("vdd_v", 5.0)}
        devices["daq"].update(options)
        sensor_device = valve_device = line_device = "daq"
    else:
        buses["i2c"] = {"url": io, "hz": rig.get("i2c_bus_hz", 400_000)}
        buses["gpio"] = {"url": rig.get("gpio", "sim://rig")}
        chip = adc.get("chip", "ADS1115")
        if not isinstance(chip, str):
            raise ConfigError(f"{source}: [adc] chip = {chip!r} is not a string")
        devices["adc"] = {
            "driver": chip.lower(),
            "bus": "i2c",
            "address": adc.get("address", 0x48),
            **{k: v for k, v in adc.items() if k in ("data_rate_sps", "full_scale_v")},
        }
        if dac.get("chip", "MCP4725") != "MCP4725":
            raise ConfigError(f"{source}: [dac] chip = {dac.get('chip')!r} unknown; use MCP4725")
        devices["dac"] = {
            "driver": "mcp4725",
            "bus": "i2c",
            "address": dac.get("address", 0x60),
            "vdd_v": dac.get("vdd_v", 5.0),
        }
        devices["lines"] = {"driver": "gpio", "bus": "gpio"}
        sensor_device, valve_device, line_device = "adc", "dac", "lines"
    for name in ("contraction", "pressure"):
        if name in sensors:
            channels[name] = _sensor(sensors[name], name, sensor_device, source)
    channels["valve"] = {"device": valve_device, "unit": "bar", "scale": valve["bar_per_volt"]}
    active_low = lines.get("active_low", ["estop"])
    if not isinstance(active_low, list) or set(active_low) - {"valve_enable", "estop"}:
        raise ConfigError(f"{source}: [gpio_lines] active_low names unknown lines {active_low}")
    for name, default in (("valve_enable", 17), ("estop", 27)):
        channels[name] = {"device": line_device, "input": lines.get(name, default), "active_low": name in active_low}
    if scheme == "serial":
        for name in ("valve_enable", "estop"):
            channels[name] = {"device": "daq"}
    return {**raw, "buses": buses, "devices": devices, "channels": channels}
