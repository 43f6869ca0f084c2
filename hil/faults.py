"""Faults scheduled in time on the emulated rig, from the rig config or the ``sim://`` URL:
``dac_nack@2.0``, ``estop@3.0``, ``sensor_stuck@1.5``, ``sensor_stuck:pressure@1.5``.

Each entry is ``KIND[:SENSOR]@SECONDS`` (simulated or wall-clock time since the rig opened);
SENSOR is ``contraction`` (default) or ``pressure``. The fault starts then and stays. What the
edge must do about each is in :data:`FAULT_KINDS`.
"""

from __future__ import annotations

import errno
import math
from collections.abc import Callable
from dataclasses import dataclass

from edge.errors import ConfigError
from hil.rig import HilRig

LEAK_PRESSURE_GAIN = 0.8  # a leak orifice against the line's restriction: the muscle keeps 80 %
FAULT_KINDS = {
    "estop": "the e-stop is pressed",
    "dac_nack": "the valve DAC stops acknowledging (every write fails)",
    "adc_nack": "the ADC stops acknowledging (every read fails)",
    "gpio_error": "the GPIO chip fails every access with OSError (as libgpiod does when the chip goes away)",
    "sensor_disconnected": "the sensor input is pulled to the ADC supply rail",
    "sensor_saturated": "the sensor is driven past the ADC's full scale",
    "sensor_stuck": "the sensor voltage freezes (found once the command has swept 0.5 bar)",
    "pressure_high": "the pressure transducer reads the supply rail (overpressure)",
    "sensor_detached": "the position sensor slips off the muscle: it reads where it was, with its noise",
    "leak": f"the muscle leaks: it holds {LEAK_PRESSURE_GAIN:.0%} of the pressure the transducer reads at the valve",
}
SENSORS = ("contraction", "pressure")
# no range or stuck check sees these (the reading stays plausible): the forward twin warns
# (edge.control.twin), or trips with [safety] twin_mismatch_mm
TWIN_WATCHED_KINDS = ("sensor_detached", "leak")


@dataclass(frozen=True)
class ScheduledFault:
    kind: str
    at_s: float
    sensor: str = "contraction"

    @property
    def label(self) -> str:
        return f"{self.kind}{':' + self.sensor if self.sensor != 'contraction' else ''}@{self.at_s:g}"


def parse_faults(items: list[str], source: str) -> list[ScheduledFault]:
    """``["dac_nack@2.0", ...]`` -> scheduled faults, sorted; one clear error per bad entry."""
    faults = []
    for item in items:
        head, at, when = item.strip().partition("@")
        kind, _, sensor = head.partition(":")
        if kind not in FAULT_KINDS or not at:
            raise ConfigError(
                f"{source}: HIL fault {item!r} unknown; write KIND@SECONDS with KIND one of {', '.join(FAULT_KINDS)}"
            )
        try:
            at_s = float(when)
        except ValueError as exc:
            raise ConfigError(f"{source}: HIL fault {item!r}: {when!r} is not a time in seconds") from exc
        if not math.isfinite(at_s) or at_s < 0:
            raise ConfigError(f"{source}: HIL fault {item!r}: the time must be finite and >= 0 s")
        if sensor and sensor not in SENSORS:
            raise ConfigError(f"{source}: HIL fault {item!r}: sensor {sensor!r} unknown; use {' or '.join(SENSORS)}")
        faults.append(ScheduledFault(kind, at_s, sensor or "contraction"))
    return sorted(faults, key=lambda f: f.at_s)


class FaultSchedule:
    """Applies each fault when the rig's clock passes its time (hooked into the rig)."""

    def __init__(self, rig: HilRig, faults: list[ScheduledFault], adc_address: int, dac_address: int) -> None:
        self.rig, self.pending = rig, list(faults)
        self.origin = rig.clock.now()
        self.applied: list[str] = []
        self._addresses = {"adc": adc_address, "dac": dac_address}
        self._busy = False
        rig.hooks.append(self.apply_due)

    def apply_due(self, now: float) -> None:
        if self._busy or not self.pending:
            return
        self._busy = True  # applying a fault may sync the rig, which calls back here
        try:
            while self.pending and now - self.origin >= self.pending[0].at_s - 1e-12:
                fault = self.pending.pop(0)
                self._apply(fault)
                self.applied.append(fault.label)
        finally:
            self._busy = False

    def _channel(self, sensor: str) -> int:
        quantity = f"{sensor}_mm" if sensor == "contraction" else f"{sensor}_bar"
        for channel, wired in self.rig.wiring.sensors.items():
            if wired.quantity == quantity:
                return channel
        raise ConfigError(f"HIL fault on {sensor}: no {sensor} sensor is wired on this rig")

    def _apply(self, fault: ScheduledFault) -> None:
        rig, kind = self.rig, fault.kind
        actions: dict[str, Callable[[], None]] = {
            "estop": lambda: rig.press_estop(),
            "dac_nack": lambda: rig.bus.faults.nack_burst(10**12, address=self._addresses["dac"]),
            "adc_nack": lambda: rig.bus.faults.nack_burst(10**12, address=self._addresses["adc"]),
            "gpio_error": lambda: rig.gpio.fail(errno.ENODEV),
            "sensor_disconnected": lambda: rig.fail_sensor(self._channel(fault.sensor), "disconnected"),
            "sensor_saturated": lambda: rig.fail_sensor(self._channel(fault.sensor), "saturated"),
            "sensor_stuck": lambda: rig.fail_sensor(self._channel(fault.sensor), "stuck"),
            "pressure_high": lambda: rig.fail_sensor(self._channel("pressure"), "disconnected"),
            "sensor_detached": lambda: rig.fail_sensor(self._channel(fault.sensor), "detached"),
            "leak": lambda: rig.leak(LEAK_PRESSURE_GAIN),
        }
        actions[kind]()
