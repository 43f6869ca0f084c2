"""Safety state machine around the control law: configure -> armed -> running -> safe.

The supervisor is pure like the tick: each call gets the tick's readings and health flags and
returns the command to send. Any fault moves it to ``SAFE`` in that same tick: the command is
the vent state (valve disabled, zero pressure) and the reason is kept. ``SAFE`` is latched:
only :meth:`Supervisor.reset` leaves it, back to ``CONFIGURED``.

A stuck sensor stays in range, so range checks miss it: a reading that has not changed by a
single bit for ``stuck_window_s`` while the command swept more than ``stuck_command_span_bar``
is declared stuck (a live sensor on a moving muscle always shows at least its noise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum

from edge.control.tick import Command, Controller, Readings


class Fault(Enum):
    """Why a run ended; the value is the code in telemetry records (0 means no fault)."""

    ESTOP = 1
    BUS = 2
    OVERRUN = 3
    SENSOR_RANGE = 4
    SENSOR_STUCK = 5
    SENSOR_NONFINITE = 6
    OVERPRESSURE = 7
    TRACKING = 8
    MODEL_OUTPUT = 9
    WATCHDOG = 10


class State(Enum):
    CONFIGURED = "configured"
    ARMED = "armed"
    RUNNING = "running"
    SAFE = "safe"


@dataclass(frozen=True)
class SafetyLimits:
    """Bounds that end a run (units in the names); the ``[safety]`` section of the rig config."""

    contraction_min_mm: float = -9.0
    contraction_max_mm: float = 145.0
    pressure_max_bar: float = 6.5
    tracking_error_max_mm: float = 25.0
    tracking_grace_s: float = 3.0  # after arming, the loop may still be converging
    bus_error_streak: int = 3
    overrun_streak: int = 5
    stuck_window_s: float = 0.3
    stuck_command_span_bar: float = 0.5


@dataclass(slots=True)  # built every tick: slots, not frozen (a frozen init costs ~0.15 us per field)
class Health:
    """What the runtime learned about this tick apart from the readings."""

    bus_error: bool = False
    overrun: bool = False
    estop: bool = False


HEALTHY = Health()


@dataclass(slots=True)  # built every tick: slots, not frozen (a frozen init costs ~0.15 us per field)
class Outcome:
    """The tick's decision: what to command, whether the valve stays enabled, the state."""

    pressure_bar: float
    valve_enabled: bool
    state: State
    fault: str | None = None
    command: Command | None = None
    fault_kind: Fault | None = None


VENT = 0.0


@dataclass
class StuckDetector:
    """Flags a reading frozen to the bit while the command sweeps (see module docstring)."""

    window_s: float
    command_span_bar: float
    _value: float = math.nan
    _since: float = 0.0
    _low: float = math.inf
    _high: float = -math.inf

    def reset(self) -> None:
        self._value, self._low, self._high = math.nan, math.inf, -math.inf

    def stuck_for(self, t: float, value: float, command_bar: float) -> float:
        """Seconds the value has been frozen while the command swept; 0 when it is alive."""
        if value != self._value:
            self._value, self._since = value, t
            self._low = self._high = command_bar
            return 0.0
        self._low, self._high = min(self._low, command_bar), max(self._high, command_bar)
        frozen = t - self._since
        return frozen if frozen >= self.window_s and self._high - self._low > self.command_span_bar else 0.0


@dataclass
class Supervisor:
    """Runs ``controller`` while everything is healthy; vents and latches on the first fault."""

    controller: Controller
    limits: SafetyLimits = field(default_factory=SafetyLimits)
    state: State = State.CONFIGURED
    fault: str | None = None
    fault_kind: Fault | None = None
    _bus_errors: int = 0
    _overruns: int = 0
    _last_pressure: float = 0.0
    _armed_at: float | None = None
    _stuck: dict[str, StuckDetector] = field(default_factory=dict)

    def __post_init__(self) -> None:
        lim = self.limits
        self._stuck = {name: StuckDetector(lim.stuck_window_s, lim.stuck_command_span_bar) for name in ("y", "p")}

    def arm(self, readings: Readings) -> None:
        if self.state is not State.CONFIGURED:
            raise RuntimeError(f"cannot arm from {self.state.value}; reset first")
        self.controller.arm(readings)
        self._bus_errors = self._overruns = 0
        self._armed_at = None
        self._last_pressure = 0.0
        for detector in self._stuck.values():
            detector.reset()
        self.state = State.ARMED

    def reset(self) -> None:
        """Leave the latched safe state (an operator's explicit action)."""
        self.state, self.fault, self.fault_kind = State.CONFIGURED, None, None

    def _trip(self, kind: Fault, reason: str) -> Outcome:
        if self.state is not State.SAFE:
            self.state, self.fault, self.fault_kind = State.SAFE, reason, kind
        return Outcome(VENT, False, self.state, self.fault, None, self.fault_kind)

    def trip(self, kind: Fault, reason: str) -> Outcome:
        """A fault found outside the tick (the runtime's watchdog): vent and latch."""
        return self._trip(kind, reason)

    def tick(self, t: float, dt: float, readings: Readings | None, health: Health | None = None) -> Outcome:
        """One tick: ``readings`` is None when the sensors could not be read this tick."""
        health = health or HEALTHY
        if self.state in (State.CONFIGURED, State.SAFE):
            return Outcome(VENT, False, self.state, self.fault, None, self.fault_kind)
        lim = self.limits
        if health.estop:
            return self._trip(Fault.ESTOP, "e-stop pressed")
        self._bus_errors = self._bus_errors + 1 if health.bus_error or readings is None else 0
        if self._bus_errors >= lim.bus_error_streak:
            return self._trip(Fault.BUS, f"{self._bus_errors} consecutive bus errors")
        self._overruns = self._overruns + 1 if health.overrun else 0
        if self._overruns >= lim.overrun_streak:
            return self._trip(Fault.OVERRUN, f"{self._overruns} consecutive deadline overruns")
        if readings is None:
            return Outcome(VENT if self.state is State.ARMED else self._last_pressure, True, self.state)
        y, p = readings.contraction_mm, readings.pressure_bar
        if not math.isfinite(y):
            return self._trip(Fault.SENSOR_NONFINITE, "contraction reading is not finite")
        if not lim.contraction_min_mm <= y <= lim.contraction_max_mm:
            return self._trip(
                Fault.SENSOR_RANGE,
                f"contraction {y:.1f} mm outside {lim.contraction_min_mm}..{lim.contraction_max_mm} mm "
                "(sensor disconnected or saturated?)",
            )
        if math.isfinite(p) and p > lim.pressure_max_bar:
            return self._trip(Fault.OVERPRESSURE, f"overpressure {p:.2f} bar > {lim.pressure_max_bar} bar")
        if self._armed_at is None:
            self._armed_at = t
        for name, value, label in (("y", y, "contraction"), ("p", p, "pressure")):
            frozen = self._stuck[name].stuck_for(t, value, self._last_pressure) if math.isfinite(value) else 0.0
            if frozen:
                return self._trip(
                    Fault.SENSOR_STUCK,
                    f"{label} sensor stuck at {value:.3f} for {frozen:.2f} s while the command swept "
                    f"> {lim.stuck_command_span_bar} bar",
                )
        command = self.controller.tick(t, dt, readings)
        if not math.isfinite(command.feedforward_bar + command.correction_bar):
            return self._trip(
                Fault.MODEL_OUTPUT,
                f"model output not finite (feedforward {command.feedforward_bar}, correction {command.correction_bar})",
            )
        if not math.isfinite(command.pressure_bar):
            return self._trip(Fault.MODEL_OUTPUT, "control output is not finite")
        settled = t - self._armed_at >= lim.tracking_grace_s
        if settled and abs(command.reference_mm - y) > lim.tracking_error_max_mm:
            return self._trip(
                Fault.TRACKING,
                f"tracking error {abs(command.reference_mm - y):.1f} mm > {lim.tracking_error_max_mm} mm",
            )
        self.state = State.RUNNING
        self._last_pressure = command.pressure_bar
        return Outcome(command.pressure_bar, True, self.state, None, command)
