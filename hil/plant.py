"""Pneumatic muscle, proportional valve and load: the emulated rig's physics.

Deliberately *not* one of pmactl's identification models: the hysteresis comes from friction
between braid and bladder as Maxwell-slip elements (PAMInertial sec 2.3), acting inside a force
balance with the Tondu-Lopez static muscle force (PAMInertial eq 1)::

    F_muscle = pi r0^2 p [a (1 - k eps)^2 - b(T)],   eps = contraction / rest length
    F_muscle(p, x) = m(t) g + k_s x + sum_i F_slip_i(x) + c dx/dt

solved implicitly for the contraction ``x`` at every step (stiff slip elements stay stable).
The proportional valve turns the pressure command into chamber pressure as a first-order lag
with a flow-rate limit and an optional dead time. Creep is a slow viscoelastic relaxation of
the contraction; temperature softens the bladder (``b`` falls) and the braid friction. Braid
friction can grow with sliding speed (fibre friction is velocity strengthening), which widens
the loops with the input rate without adding a lag at reversals: rate-dependent hysteresis.
It grows with the square of the speed (viscous-squared seal/braid friction), so loops widen
little at slow rates and strongly at fast ones.

Pure functions in python-control's shape: ``update(t, x, u, params) -> x`` advances one fixed
step ``params.dt_s``; ``output(t, x, params) -> Outputs`` reads the noise-free sensor
quantities. Sensors (noise, quantisation) live in the recorder and the chip emulators.
Defaults: a Festo DMSP-20-400N-like muscle (0-6 bar, up to ~25 % of 400 mm) with a return
spring and a 3.5 kg load.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

GRAVITY = 9.81


@dataclass(frozen=True)
class Schedule:
    """A piecewise-constant schedule: ``values[i]`` from ``times_s[i]`` on (``times_s[0]`` = 0)."""

    times_s: tuple[float, ...] = (0.0,)
    values: tuple[float, ...] = (0.0,)

    def at(self, t: float) -> float:
        value = self.values[0]
        for start, v in zip(self.times_s, self.values):
            if t >= start:
                value = v
            else:
                break
        return value


@dataclass(frozen=True)
class TemperatureProfile:
    """``T(t) = base + rise * (t / duration clipped to 1) + swing * sin(2 pi t / period)`` [degC]."""

    base_c: float = 22.0
    rise_k: float = 0.0
    swing_k: float = 0.0
    duration_s: float = 1.0
    period_s: float = 600.0

    def at(self, t: float) -> float:
        ramp = min(max(t / self.duration_s, 0.0), 1.0)
        return self.base_c + self.rise_k * ramp + self.swing_k * math.sin(2 * math.pi * t / self.period_s)


@dataclass(frozen=True)
class PlantParams:
    """Every physical parameter of the emulated rig (SI units unless the name says otherwise)."""

    dt_s: float = 1e-3
    rest_length_m: float = 0.400
    radius_m: float = 0.010
    tondu_a: float = 16.7  # 3 / tan^2(alpha0), braid angle ~23 deg
    tondu_b: float = 6.55  # 1 / sin^2(alpha0)
    tondu_k: float = 1.5  # shortening factor: max contraction ~25 %
    supply_bar: float = 6.0
    valve_time_constant_s: float = 0.03
    valve_max_rate_bar_per_s: float = 40.0
    dead_time_s: float = 0.0  # transport delay of the pneumatic line
    load: Schedule = field(default_factory=lambda: Schedule((0.0,), (3.5,)))  # kg
    spring_n_per_m: float = 6700.0
    slip_stiffness_n_per_m: tuple[float, ...] = (40e3, 25e3, 15e3, 10e3, 6e3, 4e3)
    slip_break_force_n: tuple[float, ...] = (4.0, 5.0, 6.0, 6.0, 5.0, 4.0)
    damping_n_s_per_m: float = 100.0  # viscous damping of the load motion
    rate_friction_s_per_m: float = 0.0  # braid friction grows by (this x sliding speed)^2
    creep_fraction: float = 0.0  # relaxed share of the contraction under a constant load
    creep_time_constant_s: float = 20.0
    temperature: TemperatureProfile = field(default_factory=TemperatureProfile)
    reference_temperature_c: float = 22.0
    elastic_softening_per_k: float = 0.0  # relative fall of tondu_b per kelvin
    friction_softening_per_k: float = 0.0  # relative fall of the slip break forces per kelvin
    # the chamber pressure that makes force is gain * p - offset of the p the transducer reads: a
    # leak downstream of the line's restriction (gain < 1, the muscle holds less than the valve
    # outlet), or a session shift of the pressure-contraction map (hil.effects "session_shift")
    muscle_pressure_gain: float = 1.0
    muscle_pressure_offset_bar: float = 0.0

    @property
    def delay_steps(self) -> int:
        return int(round(self.dead_time_s / self.dt_s))


class PlantState(NamedTuple):
    """State of the rig: pressure [bar], contraction [m], creep [m], slip stretches [m],
    commands still in the pneumatic line (oldest first) [bar], contraction speed [m/s]."""

    pressure_bar: float
    contraction_m: float
    creep_m: float
    slips_m: tuple[float, ...]
    line_bar: tuple[float, ...]
    speed_m_s: float = 0.0


class Outputs(NamedTuple):
    """Noise-free sensor quantities."""

    contraction_mm: float
    pressure_bar: float
    load_kg: float
    temperature_c: float


def muscle_force_n(params: PlantParams, pressure_bar: float, contraction_m: float, temperature_c: float) -> float:
    """Tondu-Lopez static force with the temperature-softened elastic term [N]."""
    eps = contraction_m / params.rest_length_m
    b = params.tondu_b * (1.0 - params.elastic_softening_per_k * (temperature_c - params.reference_temperature_c))
    area = math.pi * params.radius_m**2
    return area * pressure_bar * 1e5 * (params.tondu_a * (1.0 - params.tondu_k * eps) ** 2 - b)


def initial_state(params: PlantParams, pressure_bar: float = 0.0) -> PlantState:
    """The rig at rest at ``pressure_bar``: forces balanced with the slip elements stretched from
    the unloaded length, the pneumatic line full of the same command."""
    slips = (0.0,) * len(params.slip_stiffness_n_per_m)
    state = PlantState(pressure_bar, 0.0, 0.0, slips, (pressure_bar,) * params.delay_steps)
    position = _balance(params, 0.0, state, pressure_bar, damping=0.0)
    stretched = tuple(
        min(max(position, -f / k), f / k) for f, k in zip(params.slip_break_force_n, params.slip_stiffness_n_per_m)
    )
    return state._replace(contraction_m=position, slips_m=stretched)


def valve_step(params: PlantParams, pressure_bar: float, command_bar: float) -> float:
    """Chamber pressure [bar] one step ``params.dt_s`` later: first-order lag to the clipped
    command, limited to ``valve_max_rate_bar_per_s``."""
    setpoint = min(max(command_bar, 0.0), params.supply_bar)
    change = (setpoint - pressure_bar) * (1.0 - math.exp(-params.dt_s / params.valve_time_constant_s))
    limit = params.valve_max_rate_bar_per_s * params.dt_s
    return pressure_bar + min(max(change, -limit), limit)


def slip_friction(
    slips_m: tuple[float, ...], move_m: float, stiffness: tuple[float, ...], limits_m: list[float]
) -> tuple[float, float]:
    """Braid friction [N] of Maxwell-slip elements after a contraction ``move_m`` from their
    stretches ``slips_m`` (limits = break force / stiffness, already scaled), and its derivative
    with respect to the move [N/m] (only the elements that stick contribute)."""
    friction = 0.0
    slope = 0.0
    for s, kk, lim in zip(slips_m, stiffness, limits_m):
        stretch = s + move_m
        if stretch > lim:
            friction += kk * lim
        elif stretch < -lim:
            friction -= kk * lim
        else:
            friction += kk * stretch
            slope += kk
    return friction, slope


def advance_slips(params: PlantParams, slips_m: tuple[float, ...], move_m: float, scale: float) -> tuple[float, ...]:
    """Element stretches [m] after a contraction ``move_m``, each clipped at its (scaled) slip limit."""
    return tuple(
        min(max(s + move_m, -scale * f / k), scale * f / k)
        for s, f, k in zip(slips_m, params.slip_break_force_n, params.slip_stiffness_n_per_m)
    )


def _friction_scale(params: PlantParams, t: float, speed_m_s: float) -> float:
    """Braid friction relative to nominal: softened by warmth, raised by the square of sliding speed."""
    warmth = params.temperature.at(t) - params.reference_temperature_c
    return (1.0 - params.friction_softening_per_k * warmth) * (1.0 + (params.rate_friction_s_per_m * speed_m_s) ** 2)


def _balance(params: PlantParams, t: float, x: PlantState, pressure_bar: float, damping: float) -> float:
    """Contraction [m] where the forces balance at ``pressure_bar`` (safeguarded Newton)."""
    temperature = params.temperature.at(t)
    weight = params.load.at(t) * GRAVITY
    soften = _friction_scale(params, t, x.speed_m_s)
    stiffness = params.slip_stiffness_n_per_m
    limits = [soften * f / k for f, k in zip(params.slip_break_force_n, stiffness)]
    x_prev, slips = x.contraction_m, x.slips_m
    viscous = damping / params.dt_s
    acting_bar = max(params.muscle_pressure_gain * pressure_bar - params.muscle_pressure_offset_bar, 0.0)
    area_pa = math.pi * params.radius_m**2 * acting_bar * 1e5
    b = params.tondu_b * (1.0 - params.elastic_softening_per_k * (temperature - params.reference_temperature_c))
    a, k_shorten, length = params.tondu_a, params.tondu_k, params.rest_length_m
    lo, hi = -0.1 * length, 0.6 / k_shorten * length

    def imbalance(position: float) -> tuple[float, float]:
        eps = position / length
        force = area_pa * (a * (1.0 - k_shorten * eps) ** 2 - b)
        slope = -2.0 * area_pa * a * k_shorten * (1.0 - k_shorten * eps) / length
        move = position - x_prev
        friction, sticking = slip_friction(slips, move, stiffness, limits)
        slope -= sticking
        value = force - weight - params.spring_n_per_m * position - friction - viscous * move
        return value, slope - params.spring_n_per_m - viscous

    return decreasing_root(imbalance, x_prev, lo, hi, value_tol=1e-9, bracket_tol=1e-12)


def decreasing_root(
    f: Callable[[float], tuple[float, float]],
    start: float,
    lo: float,
    hi: float,
    *,
    value_tol: float,
    bracket_tol: float,
    iterations: int = 60,
) -> float:
    """The root of ``f`` (value, slope), decreasing on [lo, hi], by safeguarded Newton: a Newton
    step when the slope is negative and the step stays inside the bracket, else bisection. Used
    by every force or torque balance of the HIL (single muscle, antagonistic joint)."""
    x = min(max(start, lo), hi)
    for _ in range(iterations):
        value, slope = f(x)
        if value > 0.0:
            lo = x
        else:
            hi = x
        if abs(value) < value_tol or hi - lo < bracket_tol:
            break
        step = x - value / slope if slope < 0.0 else 0.5 * (lo + hi)
        x = step if lo < step < hi else 0.5 * (lo + hi)
    return x


def update(t: float, x: PlantState, u: float, params: PlantParams) -> PlantState:
    """Advance one step of ``params.dt_s`` with pressure command ``u`` [bar] issued at ``t``."""
    if params.delay_steps:
        line = (*x.line_bar[1:], u)
        command = x.line_bar[0]
    else:
        line, command = x.line_bar, u
    dt = params.dt_s
    pressure = valve_step(params, x.pressure_bar, command)
    t_next = t + dt
    contraction = _balance(params, t_next, x, pressure, params.damping_n_s_per_m)
    move = contraction - x.contraction_m
    soften = _friction_scale(params, t_next, x.speed_m_s)
    slips = advance_slips(params, x.slips_m, move, soften)
    creep = x.creep_m
    if params.creep_fraction:
        creep += dt * (params.creep_fraction * contraction - creep) / params.creep_time_constant_s
    return PlantState(pressure, contraction, creep, slips, line, move / dt)


def output(t: float, x: PlantState, params: PlantParams) -> Outputs:
    """Sensor quantities at ``t``: measured contraction is the muscle's minus its creep."""
    return Outputs((x.contraction_m - x.creep_m) * 1e3, x.pressure_bar, params.load.at(t), params.temperature.at(t))


def tendon_force_n(t: float, x: PlantState, params: PlantParams) -> float:
    """What a load cell in series with the muscle reads [N]: the weight, the spring and the damper.

    Equal to the static muscle force minus the braid friction (the friction is inside the muscle).
    """
    return (
        params.load.at(t) * GRAVITY + params.spring_n_per_m * x.contraction_m + params.damping_n_s_per_m * x.speed_m_s
    )


def simulate(
    commands_bar: np.ndarray, params: PlantParams, x0: PlantState | None = None
) -> tuple[np.ndarray, PlantState]:
    """Run ``update`` over a command sequence (one per step); returns outputs (N x 4) and the last state."""
    x = x0 if x0 is not None else initial_state(params, float(commands_bar[0]))
    out = np.empty((commands_bar.size, 4))
    dt = params.dt_s
    for i, u in enumerate(commands_bar.tolist()):
        t = i * dt
        x = update(t, x, u, params)
        out[i] = output(t + dt, x, params)
    return out, x
