"""The antagonistic joint's control law (Schreiber Figs 4 and 10), pure: frame in, two valve
commands out.

Schreiber linearises the joint first and compensates the hysteresis that is left. Per tick,
with the desired angle ``theta_d`` [deg]:

1. feedforward ``u_ff`` [deg]: the inverse Preisach model of the *statically inverted* joint,
   i.e. of the map commanded angle -> measured angle (the bundle's inverse table, units
   ``deg,deg``; identified from first-order descending curves recorded through this same
   static inversion: ``pmactl hil record --rig joint --joint-command angle --scenario forc``,
   then ``pmactl fit --model preisach --preisach-method forc --units deg,deg``);
2. feedback ``u_fb`` [deg]: PID on the angle error (Schreiber eq 8,
   ``u(k) = u_IPM(k) + K_P e(k) + K_I sum e + K_D (e(k) - e(k-q))``; here the derivative acts
   on the filtered measurement, with anti-windup, :class:`edge.control.pid.PID`). Without a
   model ("PID alone") ``u_ff = 0``;
   With ``through_model`` the PID's output moves the desired angle instead and the sum goes
   through the inverse model, ``theta_c = IPM(theta_d + PID(e))``: the model's memory then sees
   exactly what the joint is commanded, so the integrator carries no memory offset across a
   reversal (eq 8's sum lets it, which shows as a held overshoot after steps);
3. static inversion (Schreiber Fig 4) of the commanded angle ``theta_c = u_ff + u_fb``: each
   muscle's contraction from the pulley (``x_A = x_0 + r theta_c``, ``x_B = x_0 - r theta_c``),
   forces ``F_A,B = F_0 +- K theta_c / (2 r)`` (a common pretension force ``F_0`` plus what holds
   the return spring ``K``), and each pressure from the Tondu-Lopez force law (PAMInertial eq 1)
   ``p = F / c(x)``, ``c(x) = pi r_0^2 1e5 [a (1 - k x / L_0)^2 - b]`` [N/bar];
4. the pressures limited to the ``[control]`` slew rate together (the valve that must move
   further sets the pace, the other moves by the same fraction, so a step does not twist the
   joint through an unbalanced co-contraction), then each to the pressure range.

Frame fields: ``reference_deg``, ``u_ff_deg``, ``u_fb_deg``, ``u_bar`` (valve A) and
``valve_b_bar`` (valve B).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from edge.control.law import JointFrame, Readings
from edge.control.pid import PID, PIDGains
from edge.control.tick import Limits
from edge.hysteresis.lut import CompiledModel

DEG = math.pi / 180.0
COMMAND_LIMIT_DEG = 90.0  # the commanded angle never leaves +-90 deg


@dataclass(frozen=True)
class JointModel:
    """The joint's statics for the inversion (the ``[joint]`` section of the rig config).

    Muscles: Tondu-Lopez ``F = pi r_0^2 p [a (1 - k eps)^2 - b]`` with ``eps = x / L_0``;
    geometry: a pulley of radius ``pulley_radius_mm``; each muscle is mounted so that it pulls
    ``pretension_n`` [N] at ``pretension_bar`` [bar] with the joint at 0 deg; a return spring of
    ``return_stiffness_nm_per_rad`` [N m/rad] (0 if the joint has none).
    """

    pulley_radius_mm: float = 25.0
    pretension_n: float = 300.0
    pretension_bar: float = 2.5
    muscle_radius_mm: float = 10.0
    rest_length_mm: float = 400.0
    tondu_a: float = 16.7
    tondu_b: float = 6.55
    tondu_k: float = 1.5
    return_stiffness_nm_per_rad: float = 0.0

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


class StaticInversion:
    """Step 3 of the module docstring: the two pressures [bar] that hold ``angle_deg``."""

    def __init__(self, model: JointModel) -> None:
        self.model = model
        self.x0_mm = model.mount_contraction_mm()
        self.c_floor = 0.05 * model.newton_per_bar(self.x0_mm)  # a muscle near the end of its stroke
        self._torque_to_force = model.return_stiffness_nm_per_rad / (2e-3 * model.pulley_radius_mm)  # N per rad

    def __call__(self, angle_deg: float) -> tuple[float, float]:
        model = self.model
        angle = angle_deg * DEG
        arc_mm = model.pulley_radius_mm * angle
        c_a = max(model.newton_per_bar(self.x0_mm + arc_mm), self.c_floor)
        c_b = max(model.newton_per_bar(self.x0_mm - arc_mm), self.c_floor)
        spring = self._torque_to_force * angle
        return (model.pretension_n + spring) / c_a, max(model.pretension_n - spring, 0.0) / c_b


class JointController:
    """Inverse-Preisach feedforward + PID on the angle + static inversion to two pressures; a
    ``ControlLaw[JointFrame]`` (:mod:`edge.control.law`).

    Args:
        reference: desired angle [deg] as a function of time [s].
        gains: PID gains in deg of commanded angle per deg of error (kp), per deg s (ki), s (kd).
        model: the joint's statics (:class:`JointModel`).
        inverse: the inverse Preisach table (desired -> commanded angle, deg) or None: PID alone.
        limits: each valve's pressure range and slew rate.
        through_model: the PID's output goes through the inverse model (module docstring)
            instead of being added to its output (Schreiber eq 8).
    """

    correction = None  # no learned correction on the joint
    twin = None  # nor a forward twin

    def __init__(
        self,
        reference: Callable[[float], float],
        gains: PIDGains,
        model: JointModel,
        inverse: CompiledModel | None = None,
        limits: Limits | None = None,
        through_model: bool = False,
    ) -> None:
        self.reference = reference
        self._reference_at: Callable[[float], float] = getattr(reference, "function", reference)  # one call less
        self.through_model = through_model and inverse is not None
        self.limits = limits or Limits()
        self.inverse = inverse
        self.statics = StaticInversion(model)
        self.pid = PID(PIDGains(gains.kp, gains.ki, gains.kd, gains.tau_d_s, -COMMAND_LIMIT_DEG, COMMAND_LIMIT_DEG))
        # the ControlLaw's read-only values, plain attributes (a property costs a call per tick)
        self.last_command_bar = self.last_b_bar = 0.0  # valve A's and valve B's latest commands [bar]
        self.sweep_command_bar = 0.0  # (p_A - p_B) / 2 [bar]: co-contraction moves no angle (stuck check)
        self.last_reference = math.nan  # the desired angle of the latest tick [deg]
        self.last_bias = 0.0  # the feedforward of the latest tick [deg of commanded angle]

    def hold(self, frame: JointFrame, armed: bool) -> None:
        """Both valves keep their latest commands (0 bar before the first run tick)."""
        frame.u_bar, frame.valve_b_bar = (0.0, 0.0) if armed else (self.last_command_bar, self.last_b_bar)

    def vent(self, frame: JointFrame) -> None:
        """Both valves to 0 bar."""
        frame.u_bar = frame.valve_b_bar = 0.0

    def arm(self, readings: Readings, pressure_bar: float = 0.0) -> None:
        """Bumpless start from the present angle (``readings.contraction_mm`` carries it, deg)."""
        if self.inverse is not None:
            self.inverse.reset()
        self.pid.reset(readings.contraction_mm, 0.0)
        self.last_command_bar = self.last_b_bar = pressure_bar
        self.sweep_command_bar = 0.0

    def fill_from(self, frame: JointFrame, dt: float, t: float, y: float, p: float) -> float:
        """Fill the command fields of ``frame`` for angle ``y`` [deg]; returns valve A's command."""
        reference = self.last_reference = self._reference_at(t)
        inverse = self.inverse
        if self.through_model and inverse is not None:
            shifted = self.pid.step(reference, y, dt, reference)  # theta_d + PID(e)
            commanded = self.last_bias = inverse.step(shifted)
            feedforward = commanded - (shifted - reference)  # so that u_ff + u_fb = theta_c
        else:
            feedforward = self.last_bias = inverse.step(reference) if inverse is not None else 0.0
            commanded = math.nan
        if not math.isfinite(feedforward):
            frame.reference_deg, frame.u_ff_deg, frame.u_fb_deg = reference, feedforward, 0.0
            frame.u_bar = frame.valve_b_bar = math.nan
            return math.nan
        if commanded != commanded:
            commanded = self.pid.step(reference, y, dt, feedforward)
        p_a, p_b = self.valves(commanded, dt)
        frame.reference_deg, frame.u_ff_deg, frame.u_fb_deg = reference, feedforward, commanded - feedforward
        frame.u_bar, frame.valve_b_bar = p_a, p_b
        return p_a

    def valves(self, commanded_deg: float, dt: float) -> tuple[float, float]:
        """Steps 3 and 4 of the module docstring: the two valve commands [bar] for the commanded
        angle [deg] after a tick of ``dt`` [s], kept as the latest commands."""
        p_a, p_b = self.statics(commanded_deg)
        lim = self.limits
        step = lim.slew_bar_per_s * dt
        last_a, last_b = self.last_command_bar, self.last_b_bar
        d_a, d_b = p_a - last_a, p_b - last_b
        largest = max(abs(d_a), abs(d_b))
        if largest > step:  # both valves move by the same fraction: the pair stays on the static path
            p_a, p_b = last_a + d_a * step / largest, last_b + d_b * step / largest
        p_a = min(max(p_a, lim.pressure_min_bar), lim.pressure_max_bar)
        p_b = min(max(p_b, lim.pressure_min_bar), lim.pressure_max_bar)
        self.last_command_bar, self.last_b_bar, self.sweep_command_bar = p_a, p_b, 0.5 * (p_a - p_b)
        return p_a, p_b
