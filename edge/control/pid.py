"""PID with anti-windup, derivative on measurement and bumpless transfer (pure, explicit state).

``u = kp e + ki integral(e) - kd d(y_filtered)/dt``: the derivative acts on the measurement, so a
set-point step gives no derivative kick; it is low-pass filtered (time constant ``tau_d_s``).
Anti-windup by conditional integration: the integrator does not move in the direction that
would push a saturated output further. :meth:`PID.reset` sets the integrator so that the output
continues from a given value (bumpless transfer on arming or on switching feedforward).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class PIDGains:
    """Gains in output units per unit error (kp), per unit error-second (ki), per unit/s (kd)."""

    kp: float
    ki: float = 0.0
    kd: float = 0.0
    tau_d_s: float = 0.02
    out_min: float = -math.inf
    out_max: float = math.inf


class PID:
    """One PID loop; call :meth:`step` once per tick with the tick's ``dt``."""

    def __init__(self, gains: PIDGains) -> None:
        if gains.out_min >= gains.out_max:
            raise ValueError(f"PID limits inverted: out_min {gains.out_min} >= out_max {gains.out_max}")
        self.gains = gains
        self.integral = 0.0
        self._y_filtered: float | None = None
        self._derivative = 0.0
        self._dt, self._alpha = math.nan, 0.0

    def reset(self, measurement: float, output: float = 0.0) -> None:
        """Bumpless start: the next output equals ``output`` if the error is zero."""
        self._y_filtered = measurement
        self._derivative = 0.0
        self.integral = output

    def step(self, setpoint: float, measurement: float, dt: float, bias: float = 0.0) -> float:
        """Output for this tick; ``bias`` (e.g. feedforward) counts towards saturation."""
        g = self.gains
        error = setpoint - measurement
        previous = self._y_filtered
        if previous is None:
            self.reset(measurement)
            previous = measurement
        if dt != self._dt:  # the filter coefficient, once per tick length
            self._dt, self._alpha = dt, dt / (g.tau_d_s + dt)
        filtered = self._y_filtered = previous + self._alpha * (measurement - previous)
        derivative = self._derivative = (filtered - previous) / dt if dt > 0 else 0.0
        p_term, d_term, increment = g.kp * error, g.kd * derivative, g.ki * error * dt
        unclamped = p_term + self.integral + increment - d_term + bias  # this order: the golden telemetry
        if not ((unclamped > g.out_max and error > 0) or (unclamped < g.out_min and error < 0)):
            self.integral += increment
        output = p_term + self.integral - d_term + bias
        return g.out_min if output < g.out_min else g.out_max if output > g.out_max else output
