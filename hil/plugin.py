"""The ``sim`` backend of the edge runtime (entry point ``pmactl.backends``).

Every ``sim://`` bus of a rig config is one emulated rig (:class:`~hil.rig.HilRig`). Its chips
sit at the addresses the config's devices name, its sensors are wired as the config's channel
table says (``volts = value / scale + zero``, the inverse of the edge's calibration) and its
valve takes the ``valve`` channel's bar per volt, so the calibration lives in one place.

``sim://joint`` is the antagonistic joint instead (:mod:`hil.joint_rig`): channels ``angle``
[deg], ``pressure`` and ``pressure_b`` [bar] on the ADC, ``valve`` and ``valve_b`` on two
MCP4725 (each at the address its device names); effects ``none`` and ``transport_delay``.

URL options (``sim://rig?effect=creep&seed=3&clock=realtime&faults=dac_nack@2.0,estop@3``):
``effect`` (a plant effect of :mod:`hil.effects`), ``seed``, ``clock`` (``lockstep``, the
default, or ``realtime``), ``faults`` (:mod:`hil.faults`), ``adc`` (checked against the ADC's
driver). A bus table may also give ``faults = ["dac_nack@2.0", ...]``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any
from urllib.parse import parse_qs, urlsplit

import numpy as np

from edge.errors import ConfigError
from edge.hal.clock import MonotonicClock
from edge.runtime.config import RigConfig
from edge.runtime.rigspec import ANALOG_IN, BusSpec, DeviceSpec
from hil.effects import EFFECTS, apply_effect
from hil.faults import FaultSchedule, parse_faults
from hil.plant import PlantParams
from hil.rig import DEFAULT_WIRING, HilRig, Sensor, Wiring

OPTIONS = {"adc", "effect", "seed", "clock", "faults"}
QUANTITIES = {
    "contraction": "contraction_mm",
    "pressure": "pressure_bar",
    "load": "load_kg",
    "temperature": "temperature_c",
}
JOINT_QUANTITIES = {"angle": "angle_deg", "pressure": "pressure_bar", "pressure_b": "pressure_b_bar"}
ADC_DRIVERS = {"ads1115": "ADS1115", "ads1015": "ADS1015"}
RIGS = ("rig", "joint")


class _SimGpioChip:
    """``request()`` on the emulated lines (the names are the rig's)."""

    def __init__(self, rig: HilRig) -> None:
        self._rig = rig

    def request(self, outputs: dict[str, int], inputs: dict[str, int], active_low: frozenset[str]) -> Any:
        unknown = (set(outputs) | set(inputs)) - {"valve_enable", "estop"}
        if unknown:
            raise ConfigError(f"sim:// has the GPIO lines valve_enable and estop, not {sorted(unknown)}")
        return self._rig.gpio


class SimRig:
    """A HilRig exposed as the ``pmactl.backends`` plug-in protocol (``edge.runtime.rig``)."""

    def __init__(self, rig: HilRig, lockstep: bool, truth: dict[str, object], schedule: FaultSchedule | None) -> None:
        self.rig, self.lockstep, self.truth, self.schedule = rig, lockstep, truth, schedule
        self.bus, self.gpio, self.clock = rig.bus, rig.gpio, rig.clock

    def handle(self, bus: BusSpec, kind: str) -> Any:
        if kind == "i2c":
            return self.rig.bus
        if kind == "gpio":
            return _SimGpioChip(self.rig)
        raise ConfigError(f"sim:// has no {kind} bus; serve the emulated DAQ with pmactl hil serve and use serial://")

    def close(self) -> None:
        """Nothing to release."""


def _query(buses: list[BusSpec], source: str) -> tuple[dict[str, str], list[str]]:
    query: dict[str, str] = {}
    faults: list[str] = []
    for bus in buses:
        for key, values in parse_qs(urlsplit(bus.url).query).items():
            if key not in OPTIONS:
                raise ConfigError(f"{source}: sim:// option {key!r} unknown; use {sorted(OPTIONS)}")
            if key == "faults":
                faults += [f for v in values for f in v.split(",") if f]
            else:
                query[key] = values[-1]
        extra = bus.options.get("faults", [])
        if not isinstance(extra, list) or not all(isinstance(f, str) for f in extra):
            raise ConfigError(f'{source}: [buses.{bus.name}] faults must be a list of strings like "estop@3.0"')
        faults += extra
        unknown = set(bus.options) - {"faults", "hz"}
        if unknown:
            raise ConfigError(
                f"{source}: [buses.{bus.name}] unknown key(s) {sorted(unknown)} for sim://; known: faults, hz"
            )
    return query, faults


def _clock_and_seed(query: dict[str, str], source: str) -> tuple[bool, int]:
    """(lockstep?, seed) from the sim:// URL's ``clock`` and ``seed`` options."""
    clock_mode = query.get("clock", "lockstep")
    if clock_mode not in ("lockstep", "realtime"):
        raise ConfigError(f"{source}: sim:// clock={clock_mode!r}; use lockstep or realtime")
    try:
        seed = int(query.get("seed", "0"))
    except ValueError as exc:
        raise ConfigError(f"{source}: sim:// seed={query['seed']!r} is not an integer") from exc
    return clock_mode == "lockstep", seed


def _bus_hz(buses: list[BusSpec]) -> float | None:
    """The I2C clock [Hz] a bus table gives (lockstep runs pay each transfer's wire time), if any."""
    hz = next((b.options["hz"] for b in buses if "hz" in b.options), None)
    return float(hz) if isinstance(hz, int | float) else None


def wiring_from_config(config: RigConfig, devices: set[str]) -> Wiring:
    """The emulated sensors and valve wired as ``config``'s channels on ``devices`` say."""
    return _wiring(config, devices)


def _wiring(config: RigConfig, sim_devices: set[str], kind: str = "rig") -> Wiring:
    sensors = {}
    quantities = JOINT_QUANTITIES if kind == "joint" else QUANTITIES
    for channel in config.rig.channels:
        if channel.kind != ANALOG_IN or channel.device not in sim_devices:
            continue
        quantity = quantities.get(channel.name)
        if quantity is None:
            raise ConfigError(
                f"{config.source}: [channels.{channel.name}] sim://{kind} emulates {', '.join(quantities)} sensors only"
            )
        sensors[int(channel.input or 0)] = Sensor(quantity, channel.scale, channel.zero)
    valve, valve_b = config.rig.channel("valve"), config.rig.channel("valve_b")
    return Wiring(
        sensors or DEFAULT_WIRING.sensors,
        valve.scale if valve else DEFAULT_WIRING.valve_bar_per_volt,
        valve_b.scale if valve_b else DEFAULT_WIRING.valve_b_bar_per_volt,
    )


def open_sim(buses: list[BusSpec], config: RigConfig) -> SimRig:
    """The emulated rig behind ``buses`` (every ``sim://`` bus of ``config``)."""
    source = config.source
    query, fault_items = _query(buses, source)
    names = {b.name for b in buses}
    kinds = {b.path for b in buses}
    if len(kinds) > 1 or not kinds <= set(RIGS):
        raise ConfigError(f"{source}: sim:// buses name {sorted(kinds)}; use sim://rig or sim://joint for all of them")
    kind = kinds.pop()
    devices = [d for d in config.rig.devices if d.bus in names]
    adcs = [d for d in devices if d.driver in ADC_DRIVERS]
    dacs = [d for d in devices if d.driver == "mcp4725"]
    if kind == "joint":
        return _open_joint(config, query, fault_items, buses, adcs, dacs)
    if len(adcs) > 1 or len(dacs) > 1:
        raise ConfigError(f"{source}: sim:// emulates one ADC and one DAC; the config has {len(adcs)} and {len(dacs)}")
    variant = ADC_DRIVERS[adcs[0].driver] if adcs else "ADS1115"
    if query.get("adc", variant) != variant:
        raise ConfigError(
            f"{source}: sim:// emulates an {query['adc']} but the ADC's driver is {variant}; make them agree"
        )
    effect = query.get("effect", "none")
    if effect not in EFFECTS:
        raise ConfigError(f"{source}: sim:// effect {effect!r} unknown; use one of {list(EFFECTS)}")
    lockstep, seed = _clock_and_seed(query, source)
    faults = parse_faults(fault_items, source)
    params, truth = apply_effect(effect, PlantParams(), np.random.default_rng(seed), 3600.0)
    clock = None if lockstep else MonotonicClock()
    rig = HilRig(
        params,
        clock=clock,
        seed=seed,
        adc_variant=variant,
        bus_hz=_bus_hz(buses),
        wiring=_wiring(config, {d.name for d in devices}),
    )
    adc_address = adcs[0].address if adcs and adcs[0].address is not None else 0x48
    dac_address = dacs[0].address if dacs and dacs[0].address is not None else 0x60
    rig.bus.devices.clear()
    rig.bus.attach(adc_address, rig.adc)
    rig.bus.attach(dac_address, rig.dac)
    schedule = FaultSchedule(rig, faults, adc_address, dac_address) if faults else None
    if schedule is not None:
        rig.gpio.before_access.append(lambda: schedule.apply_due(rig.clock.now()))
    return SimRig(rig, lockstep, truth, schedule)


def _open_joint(
    config: RigConfig,
    query: dict[str, str],
    fault_items: list[str],
    buses: list[BusSpec],
    adcs: list[DeviceSpec],
    dacs: list[DeviceSpec],
) -> SimRig:
    """``sim://joint``: the antagonistic joint of :mod:`hil.joint_rig`."""
    from hil.joint import JointParams
    from hil.joint_record import JOINT_EFFECTS
    from hil.joint_rig import DAC_B_ADDRESS, JointHilRig

    source = config.source
    valve, valve_b = config.rig.channel("valve"), config.rig.channel("valve_b")
    if len(adcs) != 1 or valve is None or valve_b is None:
        raise ConfigError(
            f"{source}: sim://joint emulates one ADC and two valves (channels valve and valve_b); "
            "see docs/examples/hil-joint.toml"
        )
    effect = query.get("effect", "none")
    if effect not in JOINT_EFFECTS:
        raise ConfigError(f"{source}: sim://joint effect {effect!r} unknown; use one of {list(JOINT_EFFECTS)}")
    lockstep, seed = _clock_and_seed(query, source)
    variant = ADC_DRIVERS[adcs[0].driver]
    faults = parse_faults(fault_items, source)
    joint = JointParams()
    muscle, truth = apply_effect(effect, joint.muscle, np.random.default_rng(seed), 3600.0)
    rig = JointHilRig(
        replace(joint, muscle=muscle),
        clock=None if lockstep else MonotonicClock(),
        seed=seed,
        adc_variant=variant,
        bus_hz=_bus_hz(buses),
        wiring=_wiring(config, {d.name for d in [*adcs, *dacs]}, "joint"),
    )
    by_name = {d.name: d for d in dacs}
    dac_a, dac_b = by_name.get(valve.device), by_name.get(valve_b.device)
    if dac_a is None or dac_b is None or dac_a is dac_b:
        raise ConfigError(f"{source}: sim://joint needs valve and valve_b on two mcp4725 devices")
    adc_address = adcs[0].address if adcs[0].address is not None else 0x48
    dac_address = dac_a.address if dac_a.address is not None else 0x60
    rig.bus.devices.clear()
    rig.bus.attach(adc_address, rig.adc)
    rig.bus.attach(dac_address, rig.dac)
    rig.bus.attach(dac_b.address if dac_b.address is not None else DAC_B_ADDRESS, rig.dac_b)
    schedule = FaultSchedule(rig, faults, adc_address, dac_address) if faults else None
    if schedule is not None:
        rig.gpio.before_access.append(lambda: schedule.apply_due(rig.clock.now()))
    return SimRig(rig, lockstep, {**truth, "rig": "joint"}, schedule)
