"""Safety state machine around the control law: configure -> armed -> running -> safe.

The supervisor is pure like the control law: each tick it checks the frame the runtime read
(:mod:`edge.runtime.frame`) and fills its command, or vents. One rule covers every device: a
non-zero ``rd_<device>`` (this tick's read) or ``wr_<device>`` (the latest write, so a failing
valve DAC is seen too) counts towards ``bus_error_streak`` consecutive ticks. Any fault moves
it to ``SAFE`` in that same tick: the command is the vent state (valve disabled, zero pressure)
and the reason is kept. ``SAFE`` is latched: only :meth:`Supervisor.reset` leaves it.

A stuck sensor stays in range, so range checks miss it: a reading that has not changed by a
single bit for ``stuck_window_s`` while the command swept more than ``stuck_command_span_bar``
is declared stuck (a live sensor on a moving muscle always shows at least its noise). On a
joint the swept command is the differential pressure: raising both muscles together moves no
angle, and an encoder at rest reads the same count.
"""

from __future__ import annotations

import ctypes
import errno as errno_codes
import math
from dataclasses import dataclass, field
from enum import Enum
from typing import Generic, TypeVar

from edge.control.law import ControlLaw, Readings, TickFrame
from edge.control.twin import TWIN_FAULT, TWIN_WARN, TwinWatch
from edge.runtime.mismatch import MismatchMonitor


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
    TELEMETRY = 11
    MODEL_MISMATCH = 12
    TWIN_MISMATCH = 13


class State(Enum):
    CONFIGURED = "configured"
    ARMED = "armed"
    RUNNING = "running"
    SAFE = "safe"


STATE_CODES = {state: i for i, state in enumerate(State)}
SAFE_CODE = STATE_CODES[State.SAFE]
RUNNING_CODE = STATE_CODES[State.RUNNING]


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
    angle_min_deg: float = -60.0  # a joint's angle range (rigs with an ``angle`` channel)
    angle_max_deg: float = 60.0
    tracking_error_max_deg: float = 20.0
    # the bundle does not match the rig (edge.runtime.mismatch): the feedback carrying more than
    # this share of the command over mismatch_window_s warns, or trips with mismatch_fault
    mismatch_share: float = 0.3  # 0 disables
    mismatch_window_s: float = 5.0
    mismatch_fault: bool = False
    # the forward twin (edge.control.twin): the residual's RMS over twin_window_s above
    # twin_warn_share of the bundle's output span warns (0 disables); above twin_mismatch_mm
    # it trips (0: never)
    twin_warn_share: float = 0.06
    twin_window_s: float = 2.0
    twin_mismatch_mm: float = 0.0


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
        if command_bar < self._low:
            self._low = command_bar
        elif command_bar > self._high:
            self._high = command_bar
        frozen = t - self._since
        return frozen if frozen >= self.window_s and self._high - self._low > self.command_span_bar else 0.0


def _errno_name(code: int) -> str:
    return errno_codes.errorcode.get(code, str(code))


F = TypeVar("F", bound=TickFrame)


@dataclass
class Supervisor(Generic[F]):
    """Runs ``controller`` while everything is healthy; vents and latches on the first fault.

    Args:
        controller: the control law (:class:`edge.control.law.ControlLaw` on frames ``F``).
        limits: the ``[safety]`` bounds.
        status_fields: ``(device, read field, write field)`` of every device in the frame.
        channel_limits: ``(field, min, max)`` of further channels to range-check.
        period_s: the tick period [s] (lateness beyond it is an overrun).
        output_field: the controlled output's frame field (``contraction_mm``; ``angle_deg``
            on a joint, checked against the ``angle_*_deg`` limits).
        vent_fields: further command fields zeroed on venting (a joint's second valve).
        pressure_fields: further pressure fields [bar] held to ``pressure_max_bar`` (a joint's
            second muscle).
    """

    controller: ControlLaw[F]
    limits: SafetyLimits = field(default_factory=SafetyLimits)
    status_fields: tuple[tuple[str, str, str], ...] = ()
    channel_limits: tuple[tuple[str, float, float], ...] = ()
    period_s: float = 0.001
    state: State = State.CONFIGURED
    fault: str | None = None
    fault_kind: Fault | None = None
    device_errors: dict[str, str] = field(default_factory=dict)  # latest message per device (runtime fills)
    output_field: str = "contraction_mm"
    vent_fields: tuple[str, ...] = ()
    pressure_fields: tuple[str, ...] = ()
    twin_span_mm: float = 0.0  # the bundle's output span: the twin's warning bound is a share of it
    bus_error_streak: int = field(init=False, default=0)  # ticks in a row with a device error (read only)
    _overruns: int = 0
    _armed_at: float = math.nan
    _stuck: tuple[StuckDetector, StuckDetector] = field(init=False)
    _status: ctypes.Array[ctypes.c_char] | None = None
    _status_zero: bytes = b""
    mismatch: MismatchMonitor | None = field(init=False, default=None)
    twin_watch: TwinWatch | None = field(init=False, default=None)
    warnings: list[str] = field(init=False, default_factory=list)  # the runtime reports each once

    def __post_init__(self) -> None:
        self._period_us = self.period_s * 1e6
        lim = self.limits
        if self.output_field == "angle_deg":
            self._y_range = (lim.angle_min_deg, lim.angle_max_deg, lim.tracking_error_max_deg, "angle", "deg")
        else:
            self._y_range = (
                lim.contraction_min_mm, lim.contraction_max_mm, lim.tracking_error_max_mm, "contraction", "mm"
            )  # fmt: skip
        self._stuck = (
            StuckDetector(lim.stuck_window_s, lim.stuck_command_span_bar),
            StuckDetector(lim.stuck_window_s, lim.stuck_command_span_bar),
        )
        joint = self.output_field == "angle_deg"
        if self.controller.inverse is not None and lim.mismatch_share > 0:  # only a model can mismatch
            self.mismatch = MismatchMonitor(lim.mismatch_share, lim.mismatch_window_s, "deg" if joint else "bar")
        self._feedback_field = "u_fb_deg" if joint else "u_fb_bar"
        self._residual_field = "twin_residual_mm"  # only a muscle's frame has it (and a twin)
        if self.controller.twin is not None:
            self.twin_watch = TwinWatch(
                lim.twin_warn_share * self.twin_span_mm, lim.twin_mismatch_mm, lim.twin_window_s, self.period_s
            )

    def arm(self, readings: Readings) -> None:
        if self.state is not State.CONFIGURED:
            raise RuntimeError(f"cannot arm from {self.state.value}; reset first")
        self.controller.arm(readings)
        self.bus_error_streak = self._overruns = 0
        self._armed_at = math.nan
        for detector in self._stuck:
            detector.reset()
        if self.mismatch is not None:
            self.mismatch.reset()
        if self.twin_watch is not None:
            self.twin_watch.reset()
        self.state = State.ARMED

    def reset(self) -> None:
        """Leave the latched safe state (an operator's explicit action)."""
        self.state, self.fault, self.fault_kind = State.CONFIGURED, None, None

    def trip(self, frame: F, kind: Fault, reason: str) -> None:
        """Vent and latch (first fault wins); also for faults found outside the tick."""
        if self.state is not State.SAFE:
            self.state, self.fault, self.fault_kind = State.SAFE, reason, kind
        self._vent(frame)

    def _vent(self, frame: F) -> None:
        self.controller.vent(frame)
        frame.valve_enable = 0.0
        for name in self.vent_fields:
            setattr(frame, name, 0.0)
        frame.state = STATE_CODES[self.state]
        frame.fault = self.fault_kind.value if self.fault_kind else 0

    def device_fault(self, frame: F) -> str | None:
        """The one rule: the first device whose read or latest write failed, described."""
        for device, read, write in self.status_fields:
            code = getattr(frame, read)
            if code:
                return f"{device} read failed ({_errno_name(code)}): {self.device_errors.get(device, '')}".rstrip(": ")
            code = getattr(frame, write)
            if code:
                return f"{device} write failed ({_errno_name(code)}): {self.device_errors.get(device, '')}".rstrip(": ")
        return None

    def bind(self, status: ctypes.Array[ctypes.c_char]) -> None:
        """Check the device statuses of the frame through ``status``, a ctypes byte array over
        all its ``rd_*`` / ``wr_*`` fields (one comparison per tick instead of one per field)."""
        self._status, self._status_zero = status, bytes(len(status.raw))

    def step(self, frame: F, dt: float) -> None:
        """Check ``frame`` (read this tick) and fill its command, or vent it (see module doc)."""
        state = self.state
        if state is State.CONFIGURED or state is State.SAFE:
            self._vent(frame)
            return None
        lim = self.limits
        if frame.estop == 1.0:
            return self.trip(frame, Fault.ESTOP, "e-stop pressed")
        status = self._status
        failed = None
        if status is None or status.raw != self._status_zero:
            failed = self.device_fault(frame) if self.status_fields else None
        if failed is not None:
            self.bus_error_streak += 1
            if self.bus_error_streak >= lim.bus_error_streak:
                return self.trip(
                    frame, Fault.BUS, f"{self.bus_error_streak} consecutive ticks with a device error; {failed}"
                )
        elif self.bus_error_streak:
            self.bus_error_streak = 0
        if frame.lateness_us > self._period_us:
            self._overruns += 1
            if self._overruns >= lim.overrun_streak:
                return self.trip(frame, Fault.OVERRUN, f"{self._overruns} consecutive deadline overruns")
        elif self._overruns:
            self._overruns = 0
        t, y, p = frame.t, getattr(frame, self.output_field), frame.pressure_bar
        controller = self.controller
        if failed is not None and y != y:  # the sensor's device failed this tick: hold
            frame.valve_enable = 1.0
            controller.hold(frame, state is State.ARMED)
            frame.state, frame.fault = STATE_CODES[state], 0
            return None
        y_min, y_max, track_max, label, unit = self._y_range
        if not y_min <= y <= y_max:
            if y != y or y in (math.inf, -math.inf):
                return self.trip(frame, Fault.SENSOR_NONFINITE, f"{label} reading is not finite")
            return self.trip(
                frame,
                Fault.SENSOR_RANGE,
                f"{label} {y:.1f} {unit} outside {y_min}..{y_max} {unit} (sensor disconnected or saturated?)",
            )
        if p > lim.pressure_max_bar:
            return self.trip(frame, Fault.OVERPRESSURE, f"overpressure {p:.2f} bar > {lim.pressure_max_bar} bar")
        for name in self.pressure_fields:
            q = getattr(frame, name)
            if q > lim.pressure_max_bar:
                return self.trip(
                    frame, Fault.OVERPRESSURE, f"overpressure {name} {q:.2f} bar > {lim.pressure_max_bar} bar"
                )
        if self.channel_limits:
            for name, low, high in self.channel_limits:
                value = getattr(frame, name)
                if not low <= value <= high:
                    return self.trip(frame, Fault.SENSOR_RANGE, f"{name} {value:.3g} outside {low:g}..{high:g}")
        if self._armed_at != self._armed_at:
            self._armed_at = t
        last = controller.sweep_command_bar
        stuck_y, stuck_p = self._stuck
        if y != stuck_y._value:  # a live reading changes (nearly) every tick: the detector restarts, inline
            stuck_y._value, stuck_y._since, stuck_y._low, stuck_y._high = y, t, last, last
        else:
            frozen = stuck_y.stuck_for(t, y, last)
            if frozen:
                return self._stuck_trip(frame, label, y, frozen)
        if p == p:
            if p != stuck_p._value:
                stuck_p._value, stuck_p._since, stuck_p._low, stuck_p._high = p, t, last, last
            else:
                frozen = stuck_p.stuck_for(t, p, last)
                if frozen:
                    return self._stuck_trip(frame, "pressure", p, frozen)
        u = controller.fill_from(frame, dt, t, y, p)
        bias = controller.last_bias
        if bias - bias != 0.0:  # inf or nan
            return self.trip(
                frame,
                Fault.MODEL_OUTPUT,
                f"model output not finite (feedforward + correction {bias})",
            )
        if u - u != 0.0:
            return self.trip(frame, Fault.MODEL_OUTPUT, "control output is not finite")
        error = controller.last_reference - y
        if t - self._armed_at >= lim.tracking_grace_s:
            if error > track_max or -error > track_max:
                return self.trip(frame, Fault.TRACKING, f"tracking error {abs(error):.1f} {unit} > {track_max} {unit}")
            mismatch = self.mismatch
            if mismatch is not None and mismatch.add(t, bias, getattr(frame, self._feedback_field)) is not None:
                if lim.mismatch_fault:
                    return self.trip(frame, Fault.MODEL_MISMATCH, mismatch.warning or "model mismatch")
                self.warnings.append(mismatch.warning or "model mismatch")
            watch = self.twin_watch
            if watch is not None:
                verdict = watch.add(t, getattr(frame, self._residual_field))
                if verdict == TWIN_FAULT:
                    return self.trip(frame, Fault.TWIN_MISMATCH, watch.fault or "forward twin mismatch")
                if verdict == TWIN_WARN:
                    self.warnings.append(watch.warning or "forward twin mismatch")
        self.state = State.RUNNING
        frame.valve_enable, frame.state, frame.fault = 1.0, RUNNING_CODE, 0
        return None

    def _stuck_trip(self, frame: F, label: str, value: float, frozen: float) -> None:
        self.trip(
            frame,
            Fault.SENSOR_STUCK,
            f"{label} sensor stuck at {value:.3f} for {frozen:.2f} s while the command swept "
            f"> {self.limits.stuck_command_span_bar} bar",
        )
