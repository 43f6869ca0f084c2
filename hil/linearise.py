"""The emulated rig's equivalent first-order-plus-dead-time model, derived from its parameters.

What a frequency-response identification of command ``u`` [bar] -> contraction ``y`` [mm] should
find on the HIL, worked out from :class:`~hil.plant.PlantParams` rather than read off one field:

* dead time ``L``: the pneumatic line's ``dead_time_s``, plus one plant step (the recorder samples
  the sensors before the command of the same instant is applied), plus half the mechanical time
  constant (Skogestad's half rule for the smaller of two lags);
* time constant ``T``: the valve's ``valve_time_constant_s`` plus the other half of the
  mechanical time constant ``c / k``, with ``k = k_spring - dF_muscle/dx`` at the operating point
  (the friction elements sliding, so they add no stiffness);
* gain ``K``: half the peak-to-peak contraction of the quasi-static loop between
  ``p0 - A`` and ``p0 + A`` (the braid friction at its full break force, opposing the motion at
  each end) divided by ``A`` [mm/bar]: the large-signal gain that the first harmonic measures.

These are approximations (the first harmonic of a hysteretic loop is not its half range; the
valve's rate limit is assumed inactive), good to 10-20 %; the dead time is the exact part.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from hil.plant import PlantParams, Schedule, _balance, initial_state, muscle_force_n


@dataclass(frozen=True)
class EquivalentFOTD:
    """``K e^{-sL} / (1 + sT)`` of the rig around ``pressure_bar`` for sinusoids of ``amplitude_bar``."""

    gain_mm_per_bar: float
    time_constant_s: float
    dead_time_s: float
    mechanical_time_constant_s: float


def _contraction_m(params: PlantParams, pressure_bar: float, friction_n: float) -> float:
    """Static contraction at ``pressure_bar`` with ``friction_n`` added to the load [m]."""
    weight_kg = params.load.at(0.0) + friction_n / 9.81
    frictionless = replace(params, slip_break_force_n=(0.0,) * len(params.slip_break_force_n), dead_time_s=0.0)
    loaded = replace(frictionless, load=Schedule((0.0,), (weight_kg,)))
    state = initial_state(loaded, pressure_bar)
    return _balance(loaded, 0.0, state, pressure_bar, damping=0.0)


def equivalent_fotd(params: PlantParams, pressure_bar: float = 2.0, amplitude_bar: float = 0.6) -> EquivalentFOTD:
    """The rig's equivalent FOPDT (module docstring) at 22 degC and the load at t = 0."""
    friction = sum(params.slip_break_force_n)
    top = _contraction_m(params, pressure_bar + amplitude_bar, +friction)
    bottom = _contraction_m(params, pressure_bar - amplitude_bar, -friction)
    gain = (top - bottom) / 2.0 / amplitude_bar * 1e3
    x0 = _contraction_m(params, pressure_bar, 0.0)
    h = 1e-6
    slope = (
        muscle_force_n(params, pressure_bar, x0 + h, 22.0) - muscle_force_n(params, pressure_bar, x0 - h, 22.0)
    ) / (2 * h)
    mechanical = params.damping_n_s_per_m / (params.spring_n_per_m - slope)
    dead = params.dead_time_s + params.dt_s + mechanical / 2.0
    return EquivalentFOTD(gain, params.valve_time_constant_s + mechanical / 2.0, dead, mechanical)


__all__ = ["EquivalentFOTD", "equivalent_fotd"]
