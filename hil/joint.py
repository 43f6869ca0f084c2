"""An antagonistic joint: two pneumatic muscles on a pulley, an angle sensor and two valves (Schreiber).

Each muscle is the single-muscle physics of :mod:`hil.plant` (Tondu-Lopez force
:func:`~hil.plant.muscle_force_n`, braid friction as Maxwell-slip elements
:func:`~hil.plant.slip_friction` / :func:`~hil.plant.advance_slips`, valve
:func:`~hil.plant.valve_step`, pneumatic dead time), with the muscle's own ``PlantParams`` (its
load, return spring and damping are not used: the joint replaces them).

Kinematics (Schreiber eq 1 with equal upper and lower attachment radii ``r``, to first order in
the angle; a pulley exactly): muscle A contracts by ``x_A = x_pre + r theta`` and muscle B by
``x_B = x_pre - r theta``, ``theta`` [rad] positive towards A. Pretension: both muscles are
mounted at the contraction ``x_pre`` where each pulls ``pretension_n`` at ``pretension_bar``
(the rest lengths are the muscle's ``rest_length_m``). Torque balance, solved implicitly for
``theta`` at every step (as the single muscle's force balance)::

    r [F_A(p_A, x_A) - S_A] - r [F_B(p_B, x_B) - S_B] = k_theta theta + c_theta dtheta/dt + tau_load

``S`` the braid friction of each muscle (its slip elements move with its own contraction). The
angle sensor is an encoder of ``encoder_counts`` per revolution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

from hil.plant import (
    PlantParams,
    advance_slips,
    decreasing_root,
    muscle_force_n,
    slip_friction,
    valve_step,
)


@dataclass(frozen=True)
class JointParams:
    """The joint's geometry and the muscles it is made of (SI units unless named otherwise)."""

    muscle: PlantParams = field(default_factory=PlantParams)
    pulley_radius_m: float = 0.025
    pretension_bar: float = 2.5
    pretension_n: float = 300.0
    return_stiffness_nm_per_rad: float = 2.0
    damping_nm_s_per_rad: float = 0.5
    load_torque_nm: float = 0.0
    encoder_counts: int = 16384  # a 14-bit magnetic encoder (0.022 deg)

    @property
    def dt_s(self) -> float:
        return self.muscle.dt_s


class JointState(NamedTuple):
    """Pressures [bar], angle [rad], angular speed [rad/s], each muscle's slip stretches [m],
    commands in each pneumatic line [bar]."""

    pressure_a_bar: float
    pressure_b_bar: float
    angle_rad: float
    speed_rad_s: float
    slips_a_m: tuple[float, ...]
    slips_b_m: tuple[float, ...]
    line_a_bar: tuple[float, ...]
    line_b_bar: tuple[float, ...]


def pretension_contraction_m(params: JointParams) -> float:
    """Mounting contraction [m] where a muscle pulls ``pretension_n`` at ``pretension_bar`` (bisection)."""
    lo, hi = 0.0, (1.0 - math.sqrt(params.muscle.tondu_b / params.muscle.tondu_a)) / params.muscle.tondu_k
    hi *= params.muscle.rest_length_m
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if (
            muscle_force_n(params.muscle, params.pretension_bar, mid, params.muscle.reference_temperature_c)
            > params.pretension_n
        ):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def joint_initial_state(params: JointParams, pressure_a_bar: float, pressure_b_bar: float) -> JointState:
    """At rest at the given pressures, reached from the mounting angle 0 with the friction elements
    unstretched there (so they are stretched by the move, as the single muscle's initial state);
    the pneumatic lines full of the same commands."""
    steps = params.muscle.delay_steps
    slack = (0.0,) * len(params.muscle.slip_stiffness_n_per_m)
    state = JointState(
        pressure_a_bar, pressure_b_bar, 0.0, 0.0, slack, slack, (pressure_a_bar,) * steps, (pressure_b_bar,) * steps
    )
    angle = _angle_balance(params, state, pressure_a_bar, pressure_b_bar, damping=0.0)
    move = params.pulley_radius_m * angle
    return state._replace(
        angle_rad=angle,
        slips_a_m=advance_slips(params.muscle, slack, move, 1.0),
        slips_b_m=advance_slips(params.muscle, slack, -move, 1.0),
    )


def _angle_balance(params: JointParams, x: JointState, pa: float, pb: float, damping: float) -> float:
    """Angle [rad] where the torques balance (safeguarded Newton, as the single muscle's balance)."""
    m = params.muscle
    r = params.pulley_radius_m
    x_pre = pretension_contraction_m(params)
    limits = [f / k for f, k in zip(m.slip_break_force_n, m.slip_stiffness_n_per_m)]
    viscous = damping / params.dt_s
    temperature = m.reference_temperature_c
    span = (0.6 / m.tondu_k * m.rest_length_m - x_pre) / r
    lo, hi = -span, span

    def imbalance(angle: float) -> tuple[float, float]:
        move = r * (angle - x.angle_rad)
        xa, xb = x_pre + r * angle, x_pre - r * angle
        h = 1e-7
        fa = muscle_force_n(m, pa, xa, temperature)
        fb = muscle_force_n(m, pb, xb, temperature)
        dfa = (muscle_force_n(m, pa, xa + h, temperature) - fa) / h
        dfb = (muscle_force_n(m, pb, xb + h, temperature) - fb) / h
        sa, ka = slip_friction(x.slips_a_m, move, m.slip_stiffness_n_per_m, limits)
        sb, kb = slip_friction(x.slips_b_m, -move, m.slip_stiffness_n_per_m, limits)
        torque = r * (fa - sa) - r * (fb - sb) - params.return_stiffness_nm_per_rad * angle
        torque -= viscous * (angle - x.angle_rad) + params.load_torque_nm
        slope = r * r * (dfa - ka) + r * r * (dfb - kb) - params.return_stiffness_nm_per_rad - viscous
        return torque, slope

    return decreasing_root(imbalance, x.angle_rad, lo, hi, value_tol=1e-10, bracket_tol=1e-13)


def joint_update(t: float, x: JointState, u_a: float, u_b: float, params: JointParams) -> JointState:
    """Advance one step with pressure commands ``u_a``, ``u_b`` [bar] issued at ``t``."""
    m = params.muscle
    if m.delay_steps:
        line_a, command_a = (*x.line_a_bar[1:], u_a), x.line_a_bar[0]
        line_b, command_b = (*x.line_b_bar[1:], u_b), x.line_b_bar[0]
    else:
        line_a, command_a, line_b, command_b = x.line_a_bar, u_a, x.line_b_bar, u_b
    pa = valve_step(m, x.pressure_a_bar, command_a)
    pb = valve_step(m, x.pressure_b_bar, command_b)
    angle = _angle_balance(params, x, pa, pb, params.damping_nm_s_per_rad)
    move = params.pulley_radius_m * (angle - x.angle_rad)
    return JointState(
        pa,
        pb,
        angle,
        (angle - x.angle_rad) / params.dt_s,
        advance_slips(m, x.slips_a_m, move, 1.0),
        advance_slips(m, x.slips_b_m, -move, 1.0),
        line_a,
        line_b,
    )


def encoder_angle_deg(params: JointParams, angle_rad: float) -> float:
    """What the angle sensor reports [deg]: the angle rounded to the encoder's counts."""
    count = round(angle_rad / (2 * math.pi) * params.encoder_counts)
    return count * 360.0 / params.encoder_counts
