"""The rig configuration: a TOML file, validated on load with one clear error per mistake.

Each ``[section]`` is a dataclass below; its fields are the section's keys (a field without a
default is required) and their annotated types are checked. Backends are chosen by URL:

* ``io``: ``i2c:///dev/i2c-1`` (ADS1x15 + MCP4725 on Linux I2C), ``serial:///dev/ttyACM0`` (the
  serial DAQ protocol, ``docs/serial-daq.md``), or ``sim://rig?...`` (the HIL emulator, loaded
  through the ``pmactl.backends`` entry point so that ``edge`` never imports ``hil``).
* ``gpio``: ``gpiochip:///dev/gpiochip0`` (libgpiod v2) or ``sim://rig``; unused over serial,
  where the DAQ carries the valve-enable and e-stop lines.

The wires set the fastest loop: :func:`fastest_period_s` adds up conversion and bus time per
tick, and :func:`load_config` refuses a faster ``rate_hz`` with that figure in the message.
"""

from __future__ import annotations

import dataclasses
import difflib
import tomllib
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import urlsplit

from edge.devices.ads1x15 import DATA_RATES, FULL_SCALE_V, ADS1x15
from edge.devices.daq_protocol import COMMAND_FORMAT, SAMPLE_FORMAT
from edge.devices.mcp4725 import MCP4725
from edge.errors import ConfigError
from edge.runtime.safety import SafetyLimits

IO_SCHEMES = ("i2c", "serial", "sim")
GPIO_SCHEMES = ("gpiochip", "sim")
COMPUTE_BUDGET_S = 50e-6  # whole-tick compute p99 target (bench/edge_bench.py measures it)
UART_BITS_PER_BYTE = 10  # start + 8 data + stop
FRAME_OVERHEAD_BYTES = 8  # sync 2, len 1, seq 2, type 1, crc 2


@dataclass(frozen=True)
class RigSection:
    """Where the hardware is: backend URLs and the I2C clock [Hz]."""

    io: str
    gpio: str = "sim://rig"
    i2c_bus_hz: int = 400_000


@dataclass(frozen=True)
class LoopSection:
    """The control loop: rate [Hz] and real-time settings (applied when permitted)."""

    rate_hz: float = 1000.0
    realtime: bool = True
    priority: int = 80
    cpu: int = -1  # -1: leave the affinity alone
    watchdog_s: float = 0.05  # a stalled loop vents after this long (real-time runs)


@dataclass(frozen=True)
class AdcSection:
    chip: str = "ADS1115"
    address: int = 0x48
    data_rate_sps: int = 860
    full_scale_v: float = 4.096


@dataclass(frozen=True)
class DacSection:
    chip: str = "MCP4725"
    address: int = 0x60
    vdd_v: float = 5.0


@dataclass(frozen=True)
class SerialSection:
    baud: int = 921_600
    sample_rate_hz: int = 1000
    timeout_s: float = 0.002  # wait this long for a fresh sample before calling the tick a bus error


@dataclass(frozen=True)
class ContractionSensor:
    """Displacement sensor: contraction_mm = (volts - volts_at_zero_mm) * mm_per_volt."""

    channel: int
    mm_per_volt: float
    volts_at_zero_mm: float


@dataclass(frozen=True)
class PressureSensor:
    """Pressure transducer: pressure_bar = (volts - volts_at_zero_bar) * bar_per_volt."""

    channel: int
    bar_per_volt: float
    volts_at_zero_bar: float


@dataclass(frozen=True)
class ValveSection:
    """Proportional valve: commanded pressure [bar] per DAC volt."""

    bar_per_volt: float


@dataclass(frozen=True)
class GpioLinesSection:
    """Line offsets on the gpiochip (ignored by ``sim://``), and which are active low."""

    valve_enable: int = 17
    estop: int = 27
    active_low: list[str] = field(default_factory=lambda: ["estop"])


@dataclass(frozen=True)
class ControlSection:
    """PID gains and command limits. Seed 000 Table 3 (Kp 1, Ki 0.01, Kd 0, per cm) is a start;
    on the HIL rig Kp 0.05 bar/mm, Ki 0.5 bar/(mm s) tracks best with feedforward."""

    kp_bar_per_mm: float = 0.05
    ki_bar_per_mm_s: float = 0.5
    kd_bar_s_per_mm: float = 0.0
    derivative_filter_s: float = 0.005
    pressure_min_bar: float = 0.0
    pressure_max_bar: float = 6.0
    slew_bar_per_s: float = 20.0


@dataclass(frozen=True)
class TelemetrySection:
    ring_ticks: int = 65_536
    flush_interval_s: float = 0.1


@dataclass(frozen=True)
class SensorsSection:
    contraction: ContractionSensor
    pressure: PressureSensor | None = None


@dataclass(frozen=True)
class RigConfig:
    """A validated rig configuration (see the module docstring)."""

    rig: RigSection
    valve: ValveSection
    sensors: SensorsSection
    loop: LoopSection = field(default_factory=LoopSection)
    adc: AdcSection = field(default_factory=AdcSection)
    dac: DacSection = field(default_factory=DacSection)
    serial: SerialSection = field(default_factory=SerialSection)
    gpio_lines: GpioLinesSection = field(default_factory=GpioLinesSection)
    control: ControlSection = field(default_factory=ControlSection)
    safety: SafetyLimits = field(default_factory=SafetyLimits)
    telemetry: TelemetrySection = field(default_factory=TelemetrySection)
    source: str = "<config>"

    @property
    def io_scheme(self) -> str:
        return urlsplit(self.rig.io).scheme

    @property
    def period_s(self) -> float:
        return 1.0 / self.loop.rate_hz


# ---------------------------------------------------------------------------------------------
# generic section parsing


def _type_ok(value: object, annotation: object) -> bool:
    origin = typing.get_origin(annotation)
    if origin in (types.UnionType, typing.Union):
        return any(_type_ok(value, arg) for arg in typing.get_args(annotation))
    if origin is list:
        (item,) = typing.get_args(annotation)
        return isinstance(value, list) and all(_type_ok(v, item) for v in value)
    if annotation is float:
        return isinstance(value, int | float) and not isinstance(value, bool)
    if annotation is int:
        return isinstance(value, int) and not isinstance(value, bool)
    if annotation is type(None):
        return value is None
    return isinstance(value, annotation)  # type: ignore[arg-type]


def _parse(cls: type, table: object, where: str, source: str) -> object:
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: [{where}] must be a table")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.name != "source"}
    for key in table:
        if key not in fields:
            close = difflib.get_close_matches(key, fields, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(fields)}"
            raise ConfigError(f"{source}: [{where}] unknown key {key!r}{hint}")
    values = {}
    for name, spec in fields.items():
        annotation = hints[name]
        required = spec.default is dataclasses.MISSING and spec.default_factory is dataclasses.MISSING
        if name not in table:
            if required:
                raise ConfigError(f"{source}: [{where}] missing required key {name!r}")
            continue
        value = table[name]
        nested = _dataclass_in(annotation)
        if nested is not None and isinstance(value, dict):
            values[name] = _parse(nested, value, f"{where}.{name}" if where else name, source)
        elif _type_ok(value, annotation):
            values[name] = float(value) if annotation is float else value
        else:
            raise ConfigError(f"{source}: [{where}] {name} = {value!r} is not {_type_name(annotation)}")
    return cls(**values)


def _dataclass_in(annotation: object) -> type | None:
    candidates = typing.get_args(annotation) or (annotation,)
    for candidate in candidates:
        if dataclasses.is_dataclass(candidate):
            return candidate  # type: ignore[return-value]
    return None


def _type_name(annotation: object) -> str:
    return {float: "a number", int: "an integer", str: "a string", bool: "true or false"}.get(
        annotation,  # type: ignore[arg-type]
        str(annotation).replace("typing.", ""),
    )


# ---------------------------------------------------------------------------------------------
# loading and checks


def load_config(path: str | Path) -> RigConfig:
    """Read and validate a rig configuration; raises :class:`ConfigError` naming the mistake."""
    source = str(path)
    try:
        raw = tomllib.loads(Path(path).read_text())
    except FileNotFoundError as exc:
        raise ConfigError(f"{source}: no such file; start from docs/examples/hil-rig.toml") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML ({exc})") from exc
    return config_from_dict(raw, source)


def config_from_dict(raw: dict[str, object], source: str = "<config>") -> RigConfig:
    """Validate an already parsed TOML document."""
    if "sensors" in raw and isinstance(raw["sensors"], dict) and "contraction" not in raw["sensors"]:
        raise ConfigError(f"{source}: [sensors.contraction] missing; the edge needs the volts -> mm calibration")
    for section in ("rig", "valve", "sensors"):
        if section not in raw:
            raise ConfigError(f"{source}: section [{section}] missing; see docs/examples/hil-rig.toml")
    config = _parse(RigConfig, raw, "", source)
    assert isinstance(config, RigConfig)
    config = dataclasses.replace(config, source=source)
    _check_values(config)
    _check_rate(config)
    return config


def _check_values(config: RigConfig) -> None:
    src = config.source
    io = urlsplit(config.rig.io)
    if io.scheme not in IO_SCHEMES or not (io.path or io.netloc):
        raise ConfigError(
            f"{src}: [rig] io = {config.rig.io!r} is not a known backend; use i2c:///dev/i2c-N, "
            "serial:///dev/ttyXXX or sim://rig"
        )
    gpio = urlsplit(config.rig.gpio)
    if config.io_scheme != "serial" and gpio.scheme not in GPIO_SCHEMES:
        raise ConfigError(
            f"{src}: [rig] gpio = {config.rig.gpio!r} is not a known backend; use gpiochip:///dev/gpiochipN or sim://rig"
        )
    if config.loop.rate_hz <= 0:
        raise ConfigError(f"{src}: [loop] rate_hz = {config.loop.rate_hz} must be positive")
    if config.loop.watchdog_s < 3 * config.period_s:
        raise ConfigError(
            f"{src}: [loop] watchdog_s = {config.loop.watchdog_s} is under 3 periods ({3 * config.period_s:g} s); "
            "the watchdog would fire on a normal tick"
        )
    if config.adc.chip not in DATA_RATES:
        raise ConfigError(f"{src}: [adc] chip = {config.adc.chip!r} unknown; use one of {sorted(DATA_RATES)}")
    if config.adc.data_rate_sps not in DATA_RATES[config.adc.chip]:
        raise ConfigError(
            f"{src}: [adc] {config.adc.chip} has no {config.adc.data_rate_sps} SPS; "
            f"use one of {DATA_RATES[config.adc.chip]}"
        )
    if config.adc.full_scale_v not in FULL_SCALE_V:
        raise ConfigError(f"{src}: [adc] full_scale_v {config.adc.full_scale_v} is not one of {sorted(FULL_SCALE_V)}")
    if config.dac.chip != "MCP4725":
        raise ConfigError(f"{src}: [dac] chip = {config.dac.chip!r} unknown; use MCP4725")
    sensors = config.sensors
    channels = [sensors.contraction.channel] + ([sensors.pressure.channel] if sensors.pressure else [])
    if any(not 0 <= c <= 3 for c in channels) or len(set(channels)) != len(channels):
        raise ConfigError(f"{src}: [sensors] channels {channels} must be distinct and in 0..3")
    scales = {"contraction.mm_per_volt": sensors.contraction.mm_per_volt}
    if sensors.pressure:
        scales["pressure.bar_per_volt"] = sensors.pressure.bar_per_volt
    for name, scale in scales.items():
        if scale == 0:
            raise ConfigError(f"{src}: [sensors.{name}] is 0; the calibration must map volts to a range")
    if config.valve.bar_per_volt <= 0:
        raise ConfigError(f"{src}: [valve] bar_per_volt = {config.valve.bar_per_volt} must be positive")
    _check_ordered(src, "control", "pressure_min_bar", config.control.pressure_min_bar, config.control.pressure_max_bar)
    _check_ordered(
        src, "safety", "contraction_min_mm", config.safety.contraction_min_mm, config.safety.contraction_max_mm
    )
    if config.control.pressure_max_bar > config.safety.pressure_max_bar:
        raise ConfigError(
            f"{src}: [control] pressure_max_bar {config.control.pressure_max_bar} exceeds [safety] pressure_max_bar "
            f"{config.safety.pressure_max_bar}; the controller would trip its own overpressure limit"
        )
    unknown_lines = set(config.gpio_lines.active_low) - {"valve_enable", "estop"}
    if unknown_lines:
        raise ConfigError(f"{src}: [gpio_lines] active_low names unknown lines {sorted(unknown_lines)}")
    if config.telemetry.ring_ticks < 1024:
        raise ConfigError(f"{src}: [telemetry] ring_ticks {config.telemetry.ring_ticks} < 1024; give it at least 1 s")


def _check_ordered(src: str, section: str, low_name: str, low: float, high: float) -> None:
    if not low < high:
        high_name = low_name.replace("_min_", "_max_")
        raise ConfigError(f"{src}: [{section}] {low_name} {low} >= {high_name} {high}; limits inverted")


def fastest_period(config: RigConfig) -> tuple[float, str]:
    """The shortest loop period the configured chips and wires can meet [s], and how it adds up.

    I2C: the conversions and transfers of a tick run one after another, then the compute
    budget. Serial: the DAQ converts on its own, so a tick needs the wire time of one sample and
    one command plus compute, and no tick can be shorter than the DAQ's sample interval.
    """
    if config.io_scheme == "serial":
        serial = config.serial
        wire_bytes = SAMPLE_FORMAT.size + COMMAND_FORMAT.size + 2 * FRAME_OVERHEAD_BYTES
        wire_s = wire_bytes * UART_BITS_PER_BYTE / serial.baud
        sample_s = 1.0 / serial.sample_rate_hz
        return max(sample_s, wire_s + COMPUTE_BUDGET_S), (
            f"serial DAQ: one sample every {sample_s * 1e3:.3f} ms; {wire_bytes} bytes on the wire per tick "
            f"take {wire_s * 1e3:.3f} ms at {serial.baud} baud, plus {COMPUTE_BUDGET_S * 1e6:.0f} us compute"
        )
    channels = 2 if config.sensors.pressure else 1
    conversion_s = 1.0 / config.adc.data_rate_sps
    bus_hz = config.rig.i2c_bus_hz
    bus_s = (channels * ADS1x15.read_bus_bits() + MCP4725.write_bus_bits()) / bus_hz
    return channels * conversion_s + bus_s + COMPUTE_BUDGET_S, (
        f"{config.adc.chip} at {config.adc.data_rate_sps} SPS: {channels} conversion(s) of "
        f"{conversion_s * 1e3:.3f} ms, {bus_s * 1e3:.3f} ms of I2C at {bus_hz / 1e3:g} kHz, "
        f"plus {COMPUTE_BUDGET_S * 1e6:.0f} us compute"
    )


def fastest_period_s(config: RigConfig) -> float:
    """The shortest loop period the configured chips and wires can meet [s]."""
    return fastest_period(config)[0]


def _check_rate(config: RigConfig) -> None:
    fastest, breakdown = fastest_period(config)
    if config.period_s < fastest - 1e-12:
        raise ConfigError(
            f"{config.source}: [loop] rate_hz {config.loop.rate_hz:g} needs a {config.period_s * 1e3:.3f} ms period, "
            f"but the fastest this rig can meet is {fastest * 1e3:.3f} ms ({1.0 / fastest:.0f} Hz): {breakdown}; "
            "lower rate_hz or use faster converters"
        )
