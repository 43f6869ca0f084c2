"""The rig configuration: a TOML file, validated on load with one clear error per mistake.

The rig itself is data (:mod:`edge.runtime.rigspec`): ``[buses.*]``, ``[devices.*]`` and
``[channels.*]``. The other sections are the dataclasses below; their fields are the section's
keys, their annotated types are checked and every number must be finite and in range. Configs
in the first format (``[rig] io = ...``, ``[adc]``, ``[dac]``, ``[sensors.*]``) are translated
(:mod:`edge.runtime.legacy_config`).

The wires set the fastest loop: every driver reports its own wire time per tick
(:mod:`edge.runtime.wire`), and a faster ``rate_hz`` is refused with the sum in the message.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import tomllib
import types
import typing
from dataclasses import dataclass, field
from pathlib import Path

from edge.control.adapt import AdaptSettings
from edge.control.joint import JointModel
from edge.drivers.base import DriverClass, channel_kinds, installed_drivers
from edge.errors import ConfigError
from edge.runtime.legacy_config import is_legacy, translate_legacy
from edge.runtime.rigspec import RigSpec, parse_rig
from edge.runtime.safety import SafetyLimits
from edge.runtime.wire import WireTime, fastest_period

RING_BYTES_MAX = 256 * 2**20  # the telemetry ring is preallocated and locked in memory


@dataclass(frozen=True)
class LoopSection:
    """The control loop: rate [Hz] and real-time settings (applied when permitted)."""

    rate_hz: float = 1000.0
    realtime: bool = True
    priority: int = 80
    cpu: int = -1  # -1: leave the affinity alone
    watchdog_s: float = 0.05  # a stalled loop vents after this long (real-time runs)


@dataclass(frozen=True)
class ControlSection:
    """PID gains and command limits. Ai2019 Table 3 (Kp 1, Ki 0.01, Kd 0, per cm) is a start;
    on the HIL rig Kp 0.05 bar/mm, Ki 0.5 bar/(mm s) tracks best with feedforward."""

    kp_bar_per_mm: float = 0.05
    ki_bar_per_mm_s: float = 0.5
    kd_bar_s_per_mm: float = 0.0
    derivative_filter_s: float = 0.005
    pressure_min_bar: float = 0.0
    pressure_max_bar: float = 6.0
    slew_bar_per_s: float = 20.0


@dataclass(frozen=True)
class JointSection(JointModel):
    """An antagonistic joint's statics (:class:`edge.control.joint.JointModel`: mm, N, bar,
    N m/rad, Tondu-Lopez a, b, k) and its angle PID, whose output is a commanded angle: deg per
    deg of error (kp), per deg s (ki_per_s), s (kd_s). Used when the rig has an ``angle`` channel."""

    kp: float = 1.0
    ki_per_s: float = 10.0
    kd_s: float = 0.0
    derivative_filter_s: float = 0.005
    feedback: str = "eq8"  # "eq8": u_IPM + PID; "through_model": IPM(theta_d + PID) (edge.control.joint)


@dataclass(frozen=True)
class TelemetrySection:
    ring_ticks: int = 65_536
    flush_interval_s: float = 0.1


@dataclass(frozen=True)
class BundleSection:
    """Public keys a bundle's signature must verify against (paths relative to the config)."""

    trusted_keys: list[str] = field(default_factory=list)


@dataclass(frozen=True)
class FeedforwardSection:
    """Which feedforward role runs (``edge.control.net_roles``); empty: the bundle's default.
    ``twin``: the forward model that watches the muscle, ``table`` (default) or ``net`` (the
    bundle's forward net, with a net role only). The table is the default because the forward
    net raised false twin warnings on the muscle it was trained on (one run each at 1 and 0.2 Hz)."""

    role: str = ""
    twin: str = "table"


@dataclass(frozen=True)
class RigConfig:
    """A validated rig configuration (see the module docstring)."""

    rig: RigSpec
    loop: LoopSection = field(default_factory=LoopSection)
    control: ControlSection = field(default_factory=ControlSection)
    safety: SafetyLimits = field(default_factory=SafetyLimits)
    telemetry: TelemetrySection = field(default_factory=TelemetrySection)
    joint: JointSection = field(default_factory=JointSection)
    feedforward: FeedforwardSection = field(default_factory=FeedforwardSection)
    adapt: AdaptSettings = field(default_factory=AdaptSettings)
    bundle_trusted_keys: tuple[Path, ...] = ()
    source: str = "<config>"

    @property
    def period_s(self) -> float:
        return 1.0 / self.loop.rate_hz

    @property
    def lockstep_capable(self) -> bool:
        return any(b.scheme == "sim" for b in self.rig.buses)


SECTIONS: dict[str, type] = {
    "loop": LoopSection,
    "control": ControlSection,
    "safety": SafetyLimits,
    "telemetry": TelemetrySection,
    "joint": JointSection,
    "bundle": BundleSection,
    "feedforward": FeedforwardSection,
    "adapt": AdaptSettings,
}
RIG_SECTIONS = ("buses", "devices", "channels")


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
        return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)
    if annotation is int:
        return isinstance(value, int) and not isinstance(value, bool)
    return isinstance(value, annotation)  # type: ignore[arg-type]


def _type_name(annotation: object) -> str:
    names = {float: "a finite number", int: "an integer", str: "a string", bool: "true or false"}
    return names.get(annotation, str(annotation).replace("typing.", ""))  # type: ignore[call-overload]


def parse_section(cls: type, table: object, where: str, source: str) -> object:
    """``cls(**table)`` with unknown keys (closest match named), missing keys and types checked."""
    if not isinstance(table, dict):
        raise ConfigError(f"{source}: [{where}] must be a table")
    hints = typing.get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls)}
    for key in table:
        if key not in fields:
            close = difflib.get_close_matches(key, fields, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else f"; known keys: {', '.join(fields)}"
            raise ConfigError(f"{source}: [{where}] unknown key {key!r}{hint}")
    values = {}
    for name, spec in fields.items():
        required = spec.default is dataclasses.MISSING and spec.default_factory is dataclasses.MISSING
        if name not in table:
            if required:
                raise ConfigError(f"{source}: [{where}] missing required key {name!r}")
            continue
        value, annotation = table[name], hints[name]
        if not _type_ok(value, annotation):
            raise ConfigError(f"{source}: [{where}] {name} = {value!r} is not {_type_name(annotation)}")
        values[name] = float(value) if annotation is float else value
    return cls(**values)


# ---------------------------------------------------------------------------------------------
# loading and checks


def load_config(path: str | Path) -> RigConfig:
    """Read and validate a rig configuration; raises :class:`ConfigError` naming the mistake."""
    source = str(path)
    try:
        raw = tomllib.loads(Path(path).read_text())
    except FileNotFoundError as exc:
        raise ConfigError(f"{source}: no such file; start from docs/examples/hil-rig.toml") from exc
    except IsADirectoryError as exc:
        raise ConfigError(f"{source}: is a directory; give the rig's .toml file") from exc
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{source}: not a text file; give the rig's .toml file") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{source}: not valid TOML ({exc})") from exc
    return config_from_dict(raw, source)


def config_from_dict(raw: dict[str, object], source: str = "<config>") -> RigConfig:
    """Validate an already parsed TOML document."""
    if is_legacy(raw):
        raw = translate_legacy(raw, source)
    unknown = set(raw) - set(SECTIONS) - set(RIG_SECTIONS)
    if unknown:
        close = difflib.get_close_matches(sorted(unknown)[0], [*SECTIONS, *RIG_SECTIONS], n=1)
        hint = f"; did you mean [{close[0]}]?" if close else ""
        raise ConfigError(f"{source}: unknown section(s) {sorted(unknown)}{hint}")
    drivers = installed_drivers()
    rig = parse_rig(raw, source, channel_kinds(drivers))
    sections = {name: parse_section(cls, raw.get(name, {}), name, source) for name, cls in SECTIONS.items()}
    bundle = sections.pop("bundle")
    assert isinstance(bundle, BundleSection)
    config = RigConfig(
        rig,
        bundle_trusted_keys=_trusted_keys(bundle, source),
        source=source,
        **sections,  # type: ignore[arg-type]
    )
    _check_values(config)
    _check_devices(config, drivers)
    _check_rate(config, drivers)
    return config


def _trusted_keys(bundle: BundleSection, source: str) -> tuple[Path, ...]:
    base = Path(source).parent if source != "<config>" else Path.cwd()
    keys = []
    for key in bundle.trusted_keys:
        path = Path(key) if Path(key).is_absolute() else base / key
        if not path.is_file():
            raise ConfigError(f"{source}: [bundle] trusted_keys: {key!r} is not a file (looked at {path})")
        keys.append(path)
    return tuple(keys)


def _in_range(src: str, where: str, name: str, value: float, low: float, high: float, why: str = "") -> None:
    if not low <= value <= high:
        raise ConfigError(f"{src}: [{where}] {name} = {value!r} must be in {low:g}..{high:g}{why}")


def _check_values(config: RigConfig) -> None:
    src, loop, control, safety, telemetry = config.source, config.loop, config.control, config.safety, config.telemetry
    _in_range(src, "loop", "rate_hz", loop.rate_hz, 1.0, 100_000.0)
    _in_range(src, "loop", "priority", loop.priority, 1, 99, " (SCHED_FIFO priorities)")
    _in_range(src, "loop", "cpu", loop.cpu, -1, 4095)
    if not 3 * config.period_s <= loop.watchdog_s <= 10.0:
        raise ConfigError(
            f"{src}: [loop] watchdog_s = {loop.watchdog_s} must be between 3 periods ({3 * config.period_s:g} s) "
            "and 10 s; a shorter one fires on a normal tick"
        )
    for name in ("kp_bar_per_mm", "ki_bar_per_mm_s", "kd_bar_s_per_mm"):
        _in_range(src, "control", name, getattr(control, name), 0.0, 1e3, "; a negative gain drives the muscle away")
    _in_range(src, "control", "derivative_filter_s", control.derivative_filter_s, 1e-6, 10.0)
    _in_range(src, "control", "slew_bar_per_s", control.slew_bar_per_s, 1e-3, 1e4)
    _in_range(src, "control", "pressure_min_bar", control.pressure_min_bar, 0.0, 100.0)
    _check_ordered(src, "control", "pressure_min_bar", control.pressure_min_bar, control.pressure_max_bar)
    _check_ordered(src, "safety", "contraction_min_mm", safety.contraction_min_mm, safety.contraction_max_mm)
    _check_ordered(src, "safety", "angle_min_deg", safety.angle_min_deg, safety.angle_max_deg)
    _in_range(src, "safety", "tracking_error_max_deg", safety.tracking_error_max_deg, 0.01, 360.0)
    _in_range(src, "safety", "pressure_max_bar", safety.pressure_max_bar, 0.01, 100.0)
    _in_range(src, "safety", "tracking_error_max_mm", safety.tracking_error_max_mm, 0.01, 1e4)
    _in_range(src, "safety", "tracking_grace_s", safety.tracking_grace_s, 0.0, 3600.0)
    _in_range(src, "safety", "bus_error_streak", safety.bus_error_streak, 1, 1000)
    _in_range(src, "safety", "overrun_streak", safety.overrun_streak, 1, 1000)
    _in_range(src, "safety", "stuck_window_s", safety.stuck_window_s, 1e-3, 3600.0)
    _in_range(src, "safety", "stuck_command_span_bar", safety.stuck_command_span_bar, 1e-3, 100.0)
    _in_range(
        src, "safety", "mismatch_share", safety.mismatch_share, 0.0, 10.0, " (a share of the command; 0 disables)"
    )
    _in_range(src, "safety", "mismatch_window_s", safety.mismatch_window_s, 0.1, 3600.0)
    span_note = " (a share of the bundle's span; 0 disables)"
    _in_range(src, "safety", "twin_warn_share", safety.twin_warn_share, 0.0, 10.0, span_note)
    _in_range(src, "safety", "twin_window_s", safety.twin_window_s, 0.05, 3600.0)
    _in_range(src, "safety", "twin_mismatch_mm", safety.twin_mismatch_mm, 0.0, 1e4, " (0 disables the fault)")
    _check_adapt(config)
    if control.pressure_max_bar > safety.pressure_max_bar:
        raise ConfigError(
            f"{src}: [control] pressure_max_bar {control.pressure_max_bar} exceeds [safety] pressure_max_bar "
            f"{safety.pressure_max_bar}; the controller would trip its own overpressure limit"
        )
    joint = config.joint
    for name in ("kp", "ki_per_s", "kd_s"):
        _in_range(src, "joint", name, getattr(joint, name), 0.0, 1e4, "; a negative gain drives the joint away")
    _in_range(src, "joint", "derivative_filter_s", joint.derivative_filter_s, 1e-6, 10.0)
    if joint.feedback not in ("eq8", "through_model"):
        raise ConfigError(f'{src}: [joint] feedback = {joint.feedback!r}; use "eq8" or "through_model"')
    for name in ("pulley_radius_mm", "pretension_n", "pretension_bar", "muscle_radius_mm", "rest_length_mm"):
        _in_range(src, "joint", name, getattr(joint, name), 1e-6, 1e6)
    _in_range(src, "joint", "return_stiffness_nm_per_rad", joint.return_stiffness_nm_per_rad, 0.0, 1e6)
    if not joint.tondu_a > joint.tondu_b > 0 or joint.tondu_k <= 0:
        raise ConfigError(f"{src}: [joint] needs tondu_a > tondu_b > 0 and tondu_k > 0 (Tondu-Lopez, PAMInertial eq 1)")
    if config.rig.is_joint:
        try:
            joint.mount_contraction_mm()
        except ValueError as exc:
            raise ConfigError(f"{src}: [joint] {exc}") from exc
    _in_range(src, "telemetry", "flush_interval_s", telemetry.flush_interval_s, 1e-3, 10.0)
    row_bytes = 8 * (12 + len(config.rig.channels)) + 8 * (1 + len(config.rig.devices))
    most = RING_BYTES_MAX // row_bytes
    if not 1024 <= telemetry.ring_ticks <= most:
        raise ConfigError(
            f"{src}: [telemetry] ring_ticks = {telemetry.ring_ticks} must be in 1024..{most} "
            f"(at least 1 s; at most {RING_BYTES_MAX >> 20} MiB of preallocated ring)"
        )


def _check_adapt(config: RigConfig) -> None:
    src, adapt = config.source, config.adapt
    _in_range(src, "adapt", "memory_s", adapt.memory_s, 1e-3, 1e5, " (the forgetting time constant)")
    _in_range(src, "adapt", "offset_max_share", adapt.offset_max_share, 0.0, 10.0, " (a share of the bundle's span)")
    _in_range(src, "adapt", "gain_min", adapt.gain_min, 0.01, 1.0, " (1 is the model's own gain)")
    _in_range(src, "adapt", "gain_max", adapt.gain_max, 1.0, 100.0, " (1 is the model's own gain)")
    _in_range(src, "adapt", "excitation_share", adapt.excitation_share, 0.0, 1.0, " (a share of the bundle's span)")
    _in_range(src, "adapt", "excitation_window_s", adapt.excitation_window_s, 1e-3, 1e5)
    if adapt.enabled and config.rig.is_joint:
        raise ConfigError(f"{src}: [adapt] enabled = true runs on a single muscle only; this rig is a joint")


def _check_ordered(src: str, section: str, low_name: str, low: float, high: float) -> None:
    if not low < high:
        high_name = low_name.replace("_min_", "_max_")
        raise ConfigError(f"{src}: [{section}] {low_name} {low} >= {high_name} {high}; limits inverted")


def _check_devices(config: RigConfig, drivers: dict[str, DriverClass]) -> None:
    rig, src = config.rig, config.source
    taken: dict[tuple[str, int], str] = {}
    for device in rig.devices:
        if device.address is not None:
            if not 0x08 <= device.address <= 0x77:
                raise ConfigError(
                    f"{src}: [devices.{device.name}] address = {device.address:#04x} is not a 7-bit I2C device "
                    "address (0x08..0x77)"
                )
            other = taken.setdefault((device.bus, device.address), device.name)
            if other != device.name:
                raise ConfigError(
                    f"{src}: [devices.{device.name}] address = {device.address:#04x} on bus {device.bus!r} is already "
                    f"[devices.{other}]'s; two chips cannot answer at one address"
                )
        cls, bus = drivers[device.driver], rig.bus(device.bus)
        if bus.scheme not in cls.bus_schemes:
            raise ConfigError(
                f"{src}: [devices.{device.name}] {device.driver} cannot sit on {bus.url!r}; "
                f"use a {' or '.join(sorted(cls.bus_schemes))}:// bus"
            )
        unknown = set(device.options) - set(cls.option_keys)
        if unknown:
            raise ConfigError(
                f"{src}: [devices.{device.name}] unknown key(s) {sorted(unknown)} for {device.driver}; "
                f"known: {sorted(cls.option_keys) or 'none'}"
            )
        cls.check(device, rig.channels_of(device.name), bus, src)


def wire_times(config: RigConfig, drivers: dict[str, DriverClass] | None = None) -> list[WireTime]:
    """What every device costs a tick, in declaration order."""
    drivers = drivers or installed_drivers()
    rig = config.rig
    return [drivers[d.driver].wire_time(d, rig.channels_of(d.name), rig.bus(d.bus)) for d in rig.devices]


def fastest_period_s(config: RigConfig) -> float:
    """The shortest loop period the configured chips and wires can meet [s]."""
    return fastest_period(wire_times(config))[0]


def _check_rate(config: RigConfig, drivers: dict[str, DriverClass]) -> None:
    fastest, breakdown = fastest_period(wire_times(config, drivers))
    if config.period_s < fastest - 1e-12:
        raise ConfigError(
            f"{config.source}: [loop] rate_hz {config.loop.rate_hz:g} needs a {config.period_s * 1e3:.3f} ms period, "
            f"but the fastest this rig can meet is {fastest * 1e3:.3f} ms ({1.0 / fastest:.0f} Hz): {breakdown}; "
            "lower rate_hz or use faster converters"
        )
