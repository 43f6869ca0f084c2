"""The per-tick control law: ``Controller.tick(t, dt, readings) -> Command`` with no I/O.

Structure (seed 000 Fig 12, seed 003 eq 8): the desired trajectory goes through the inverse
hysteresis model (feedforward, a lookup table), an optional neural correction (ONNX, see
:mod:`edge.control.neural`) is added, then PID feedback on the measured output, then limits:
pressure range and slew rate. Time and readings come in as arguments, so tests
run thousands of ticks without a clock.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from edge.control.pid import PID, PIDGains
from edge.hysteresis.lut import CompiledModel


@dataclass(slots=True)  # built every tick: slots, not frozen (a frozen init costs ~0.15 us per field)
class Readings:
    """Sensor values of one tick: contraction [mm], pressure [bar]."""

    contraction_mm: float
    pressure_bar: float = float("nan")


@dataclass(slots=True)  # built every tick: slots, not frozen (a frozen init costs ~0.15 us per field)
class Command:
    """What to send this tick, and why (for telemetry)."""

    pressure_bar: float
    reference_mm: float
    feedforward_bar: float
    correction_bar: float
    feedback_bar: float
    saturated: bool


class Correction(Protocol):
    """A learned feedforward correction (``edge.control.neural.NeuralCorrection``)."""

    def reset(self) -> None: ...

    def step(self, values: tuple[float, ...]) -> float:
        """Correction [bar] from (reference_mm, reference_rate_mm_s, feedforward_bar,
        contraction_mm, pressure_bar, previous_command_bar)."""


@dataclass
class Limits:
    """Pressure range [bar] and the fastest allowed change [bar/s]."""

    pressure_min_bar: float = 0.0
    pressure_max_bar: float = 6.0
    slew_bar_per_s: float = 20.0


class Controller:
    """Inverse-hysteresis feedforward + PID + limits.

    Args:
        reference: desired contraction [mm] as a function of time [s].
        gains: PID gains (bar per mm, bar per mm s, bar s per mm).
        inverse: lookup-table inverse model (contraction -> pressure), or None for PID alone.
        limits: pressure range and slew rate.
        correction: learned correction added to the feedforward, or None.
    """

    def __init__(
        self,
        reference: Callable[[float], float],
        gains: PIDGains,
        inverse: CompiledModel | None = None,
        limits: Limits | None = None,
        correction: Correction | None = None,
    ) -> None:
        self.reference = reference
        self.correction = correction
        self.limits = limits or Limits()
        self.inverse = inverse
        self.pid = PID(
            PIDGains(
                gains.kp, gains.ki, gains.kd, gains.tau_d_s, self.limits.pressure_min_bar, self.limits.pressure_max_bar
            )
        )
        self._last_bar: float | None = None
        self._last_reference: float | None = None

    def arm(self, readings: Readings, pressure_bar: float = 0.0) -> None:
        """Bumpless start from the present state (feedforward memory reset to the rest state)."""
        if self.inverse is not None:
            self.inverse.reset()
        if self.correction is not None:
            self.correction.reset()
        self.pid.reset(readings.contraction_mm, 0.0)
        self._last_bar = pressure_bar
        self._last_reference = None

    def tick(self, t: float, dt: float, readings: Readings) -> Command:
        """The command for time ``t`` [s] after a tick of ``dt`` [s]; no I/O, no clock."""
        reference = self.reference(t)
        feedforward = self.inverse.step(reference) if self.inverse is not None else 0.0
        correction = 0.0
        if self.correction is not None:
            last = self._last_reference
            rate = (reference - last) / dt if last is not None and dt > 0 else 0.0
            previous = self._last_bar if self._last_bar is not None else 0.0
            values = (reference, rate, feedforward, readings.contraction_mm, readings.pressure_bar, previous)
            correction = self.correction.step(values)
        self._last_reference = reference
        bias = feedforward + correction
        if not math.isfinite(bias):  # the supervisor trips on it; keep the PID state clean
            return Command(math.nan, reference, feedforward, correction, 0.0, False)
        total = self.pid.step(reference, readings.contraction_mm, dt, bias=bias)
        feedback = total - bias
        lim = self.limits
        if self._last_bar is not None:
            step = lim.slew_bar_per_s * dt
            total = min(max(total, self._last_bar - step), self._last_bar + step)
        command = min(max(total, lim.pressure_min_bar), lim.pressure_max_bar)
        saturated = command != bias + feedback
        self._last_bar = command
        return Command(command, reference, feedforward, correction, feedback, saturated)
