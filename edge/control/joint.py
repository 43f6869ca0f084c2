"""The antagonistic joint's control law (seed 003), pure: frame in, two valve commands out.

Per tick, with the desired angle ``theta_d`` [deg]:

1. feedforward ``u_ff`` [bar]: the inverse Preisach model of the joint (the bundle's inverse
   table, fitted on a joint recording ``t,u,y`` with ``u`` the differential command [bar] and
   ``y`` the angle [deg]: ``pmactl fit --model preisach --preisach-method forc --units bar,deg``);
2. feedback ``u_fb`` [bar]: PID on the angle error (seed 003 eq 8:
   ``u(k) = u_IPM(k) + K_P e(k) + K_I sum e + K_D (e(k) - e(k-q))``, here with the derivative on
   the filtered measurement and anti-windup, :class:`edge.control.pid.PID`);
3. static inversion of the muscle force law for the two pressures: each muscle's contraction
   follows from ``theta_d`` (``x_A = x_0 + r theta``, ``x_B = x_0 - r theta``, seed 003 eq 1 for a
   pulley), its force per bar ``c(x) = pi r_0^2 1e5 [a (1 - k x / L_0)^2 - b]`` [N/bar]
   (Tondu-Lopez, seed 004 eq 1), and the pressures solve ``p_A c_A + p_B c_B = 2 F_0`` (a common
   pretension force ``F_0``) and ``p_A - p_B = 2 u`` with ``u = u_ff + u_fb`` (the differential the
   Preisach map was identified on). At ``theta_d = 0`` this is ``p = p_0 +- u`` with ``p_0`` the
   pretension pressure;
4. each pressure limited to the ``[control]`` range and slew rate.

Frame fields: ``reference_deg``, ``u_ff_bar``, ``u_fb_bar``, ``u_nn_bar`` (0: no neural
correction on the joint), ``u_bar`` (valve A) and ``valve_b_bar`` (valve B).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from edge.control.pid import PID, PIDGains
from edge.control.tick import Limits, Readings
from edge.hysteresis.lut import CompiledModel

DEG = math.pi / 180.0


@dataclass(frozen=True)
class JointModel:
    """The joint's statics for the inversion (the ``[joint]`` section of the rig config).

    Muscles: Tondu-Lopez ``F = pi r_0^2 p [a (1 - k eps)^2 - b]`` with ``eps = x / L_0``;
    geometry: a pulley of radius ``pulley_radius_mm``; each muscle is mounted so that it pulls
    ``pretension_n`` [N] at ``pretension_bar`` [bar] with the joint at 0 deg.
    """

    pulley_radius_mm: float = 25.0
    pretension_n: float = 300.0
    pretension_bar: float = 2.5
    muscle_radius_mm: float = 10.0
    rest_length_mm: float = 400.0
    tondu_a: float = 16.7
    tondu_b: float = 6.55
    tondu_k: float = 1.5

    def newton_per_bar(self, contraction_mm: float) -> float:
        """Force per bar of one muscle at ``contraction_mm`` [N/bar] (negative past its stroke)."""
        eps = contraction_mm / self.rest_length_mm
        area = math.pi * (self.muscle_radius_mm * 1e-3) ** 2
        return area * 1e5 * (self.tondu_a * (1.0 - self.tondu_k * eps) ** 2 - self.tondu_b)

    def mount_contraction_mm(self) -> float:
        """Each muscle's contraction at 0 deg [mm]: where it pulls ``pretension_n`` at
        ``pretension_bar`` (bisection on the falling branch of the force law)."""
        lo = 0.0
        hi = (1.0 - math.sqrt(self.tondu_b / self.tondu_a)) / self.tondu_k * self.rest_length_mm
        target = self.pretension_n / self.pretension_bar
        if self.newton_per_bar(lo) < target:
            raise ValueError(
                f"a muscle cannot pull {self.pretension_n} N at {self.pretension_bar} bar at any contraction; "
                "lower [joint] pretension_n or raise pretension_bar"
            )
        for _ in range(80):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if self.newton_per_bar(mid) > target else (lo, mid)
        return 0.5 * (lo + hi)


class JointPressures:
    """Step 3 of the module docstring: the two pressures [bar] from the desired angle [deg] and
    the differential ``u`` [bar]."""

    def __init__(self, model: JointModel) -> None:
        self.model = model
        self.x0_mm = model.mount_contraction_mm()
        self.c_floor = 0.05 * model.newton_per_bar(self.x0_mm)  # a muscle near the end of its stroke
        self.force_n = model.pretension_n

    def __call__(self, angle_deg: float, u_bar: float) -> tuple[float, float]:
        arc = self.model.pulley_radius_mm * angle_deg * DEG
        c_a = max(self.model.newton_per_bar(self.x0_mm + arc), self.c_floor)
        c_b = max(self.model.newton_per_bar(self.x0_mm - arc), self.c_floor)
        p_b = 2.0 * (self.force_n - u_bar * c_a) / (c_a + c_b)
        return p_b + 2.0 * u_bar, p_b


class JointController:
    """Inverse-Preisach feedforward + PID on the angle + static inversion to two pressures.

    Args:
        reference: desired angle [deg] as a function of time [s].
        gains: PID gains in bar of differential per deg (kp), per deg s (ki), bar s per deg (kd).
        model: the joint's statics (:class:`JointModel`).
        inverse: the inverse Preisach table (angle [deg] -> differential [bar]) or None: PID alone.
        limits: each valve's pressure range and slew rate.
    """

    correction = None  # no learned correction on the joint

    def __init__(
        self,
        reference: Callable[[float], float],
        gains: PIDGains,
        model: JointModel,
        inverse: CompiledModel | None = None,
        limits: Limits | None = None,
    ) -> None:
        self.reference = reference
        self.limits = lim = limits or Limits()
        self.inverse = inverse
        self.pressures = JointPressures(model)
        half_span = 0.5 * (lim.pressure_max_bar - lim.pressure_min_bar)
        self.pid = PID(PIDGains(gains.kp, gains.ki, gains.kd, gains.tau_d_s, -half_span, half_span))
        self._last_bar = self._last_b_bar = 0.0
        self.reference_mm_ = math.nan  # the supervisor's name for the latest reference (here deg)
        self.bias_bar_ = 0.0

    def arm(self, readings: Readings, pressure_bar: float = 0.0) -> None:
        """Bumpless start from the present angle (``readings.contraction_mm`` carries it, deg)."""
        if self.inverse is not None:
            self.inverse.reset()
        self.pid.reset(readings.contraction_mm, 0.0)
        self._last_bar = self._last_b_bar = pressure_bar

    def fill_from(self, frame: Any, dt: float, t: float, y: float, p: float) -> float:
        """Fill the command fields of ``frame`` for angle ``y`` [deg]; returns valve A's command."""
        reference = self.reference_mm_ = self.reference(t)
        feedforward = self.bias_bar_ = self.inverse.step(reference) if self.inverse is not None else 0.0
        if not math.isfinite(feedforward):
            frame.reference_deg, frame.u_ff_bar, frame.u_nn_bar, frame.u_fb_bar = reference, feedforward, 0.0, 0.0
            frame.u_bar = frame.valve_b_bar = math.nan
            return math.nan
        total = self.pid.step(reference, y, dt, feedforward)
        p_a, p_b = self.pressures(reference, total)
        lim = self.limits
        step = lim.slew_bar_per_s * dt
        p_a = min(max(p_a, self._last_bar - step, lim.pressure_min_bar), self._last_bar + step, lim.pressure_max_bar)
        p_b = min(
            max(p_b, self._last_b_bar - step, lim.pressure_min_bar), self._last_b_bar + step, lim.pressure_max_bar
        )
        self._last_bar, self._last_b_bar = p_a, p_b
        frame.reference_deg, frame.u_ff_bar, frame.u_nn_bar = reference, feedforward, 0.0
        frame.u_fb_bar = total - feedforward
        frame.u_bar, frame.valve_b_bar = p_a, p_b
        return p_a
