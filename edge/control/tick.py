"""The per-tick control law, pure: it fills the command fields of the tick's frame from its
time and readings, with no I/O and no clock.

Structure (Ai2019 Fig 12, Schreiber eq 8): the desired trajectory goes through the inverse
hysteresis model (feedforward, a lookup table), an optional neural correction (ONNX, see
:mod:`edge.control.neural`) is added, then PID feedback on the measured output, then limits:
pressure range and slew rate. With a forward twin (:mod:`edge.control.twin`) the controller
also predicts the contraction from the applied pressure (``twin_mm``, ``twin_residual_mm``);
with online adaptation (:mod:`edge.control.adapt`) it estimates the offset ``a`` and gain
``b`` of the model's output map from that prediction and asks the inverse for ``(r - a) / b``
(``adapt_offset_mm``, ``adapt_gain``). The controller is a
:class:`~edge.control.law.ControlLaw` on :class:`~edge.control.law.MuscleFrame`: it works on the
runtime's frame (:mod:`edge.runtime.frame`) or, for tools without a rig, a :class:`ScratchFrame`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from edge.control.adapt import OutputMapEstimator
from edge.control.law import MuscleFrame, Readings
from edge.control.pid import PID, PIDGains
from edge.control.twin import ForwardModel
from edge.hysteresis.lut import CompiledModel

__all__ = ["Controller", "Correction", "InverseModel", "Limits", "Readings", "ScratchFrame"]


class ScratchFrame:
    """A single muscle's frame (:class:`~edge.control.law.MuscleFrame`) as a plain object, for
    tools and tests that drive the control law without a rig's frame layout. ``rd_sensors`` is
    the errno of the sensor read (0 = ok), for a supervisor given
    ``status_fields=(("sensors", "rd_sensors", "rd_sensors"),)``."""

    __slots__ = (
        "t", "lateness_us", "reference_mm", "u_ff_bar", "u_nn_bar", "u_fb_bar", "u_bar",
        "contraction_mm", "pressure_bar", "estop", "valve_enable", "state", "fault",
        "twin_mm", "twin_residual_mm", "adapt_offset_mm", "adapt_gain", "rd_sensors",
    )  # fmt: skip

    def __init__(self, t: float = 0.0, contraction_mm: float = math.nan, pressure_bar: float = math.nan) -> None:
        self.t, self.lateness_us = t, 0.0
        self.reference_mm = self.u_ff_bar = self.u_nn_bar = self.u_fb_bar = self.u_bar = 0.0
        self.contraction_mm, self.pressure_bar = contraction_mm, pressure_bar
        self.estop, self.valve_enable, self.state, self.fault = 0.0, 0.0, 0, 0
        self.twin_mm = self.twin_residual_mm = self.adapt_offset_mm = self.adapt_gain = math.nan
        self.rd_sensors = 0


class InverseModel(Protocol):
    """A feedforward inverse: the lookup table (``CompiledModel``) or the net (``NetInverse``)."""

    input_range: tuple[float, float]

    def reset(self) -> None: ...

    def step(self, target: float) -> float: ...


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
    """Inverse-hysteresis feedforward + PID + limits; a ``ControlLaw[MuscleFrame]``.

    Args:
        reference: desired contraction [mm] as a function of time [s].
        gains: PID gains (bar per mm, bar per mm s, bar s per mm).
        inverse: lookup-table inverse model (contraction -> pressure), or None for PID alone.
        limits: pressure range and slew rate.
        correction: learned correction added to the feedforward, or None.
        twin: the forward model run on the applied pressure (the bundle's forward table), or None.
        adapt: the output-map estimator fed by the twin (needs ``twin``), or None.
    """

    def __init__(
        self,
        reference: Callable[[float], float],
        gains: PIDGains,
        inverse: CompiledModel | InverseModel | None = None,
        limits: Limits | None = None,
        correction: Correction | None = None,
        twin: ForwardModel | None = None,
        adapt: OutputMapEstimator | None = None,
    ) -> None:
        if adapt is not None and twin is None:
            raise ValueError("online adaptation needs the forward twin's prediction; pass twin=")
        self.reference = reference
        # a Reference wraps its function: call that directly (one Python call less per tick)
        self._reference_at: Callable[[float], float] = getattr(reference, "function", reference)
        self.twin, self.adapt = twin, adapt
        self._twin_table = twin if isinstance(twin, CompiledModel) else None  # it says when it clamped
        self.correction = correction
        self.limits = limits or Limits()
        self.inverse = inverse
        # an inverse that anticipates the plant's lag (the net feedforward) is fed the reference ahead
        self.preview_s = float(getattr(inverse, "preview_s", 0.0))
        self.pid = PID(
            PIDGains(
                gains.kp, gains.ki, gains.kd, gains.tau_d_s, self.limits.pressure_min_bar, self.limits.pressure_max_bar
            )
        )
        # the ControlLaw's read-only values, plain attributes (a property costs a call per tick)
        self.last_command_bar = 0.0  # the latest valve command [bar]
        self.sweep_command_bar = 0.0  # the same: its sweep must move the contraction (stuck check) [bar]
        self.last_reference = math.nan  # the reference of the latest tick [mm]
        self.last_bias = 0.0  # feedforward + correction of the latest tick [bar]
        self._previous_reference = math.nan  # for the correction's reference rate

    def hold(self, frame: MuscleFrame, armed: bool) -> None:
        """The latest command again (0 bar before the first run tick); no model steps."""
        frame.u_bar = 0.0 if armed else self.last_command_bar

    def vent(self, frame: MuscleFrame) -> None:
        """The valve to 0 bar."""
        frame.u_bar = 0.0

    def arm(self, readings: Readings, pressure_bar: float = 0.0) -> None:
        """Bumpless start from the present state (feedforward memory reset to the rest state)."""
        if self.inverse is not None:
            self.inverse.reset()
        if self.correction is not None:
            self.correction.reset()
        if self.twin is not None:
            self.twin.reset()
        if self.adapt is not None:
            self.adapt.reset()
        self.pid.reset(readings.contraction_mm, 0.0)
        self.last_command_bar = self.sweep_command_bar = pressure_bar
        self._previous_reference = math.nan

    def fill(self, frame: MuscleFrame, dt: float) -> None:
        """Set ``reference_mm``, ``u_ff_bar``, ``u_nn_bar``, ``u_fb_bar`` and ``u_bar`` of
        ``frame`` from its ``t`` [s], ``contraction_mm`` and ``pressure_bar``; ``dt`` [s]."""
        self.fill_from(frame, dt, frame.t, frame.contraction_mm, frame.pressure_bar)

    def fill_from(self, frame: MuscleFrame, dt: float, t: float, y: float, p: float) -> float:
        """:meth:`fill` with the readings already at hand (the supervisor has them); returns
        the command ``u_bar`` and keeps :attr:`last_reference` and :attr:`last_bias`
        (feedforward + correction), so no per-tick object is built."""
        reference_at = self._reference_at
        reference = reference_at(t)
        ahead = reference_at(t + self.preview_s) if self.preview_s else reference
        twin, adapt = self.twin, self.adapt
        if twin is not None:
            model_mm = twin.step(p if p == p else self.last_command_bar)  # the pressure applied (or commanded)
            table = self._twin_table  # a table clamped to its range extrapolates: no residual then
            inside = table is None or not table.saturated
            # the residual judges the bundle itself: a leak the adaptation absorbs is still seen
            frame.twin_mm, frame.twin_residual_mm = model_mm, y - model_mm if inside else math.nan
            if adapt is not None:
                if inside:
                    adapt.update(model_mm, y)
                frame.adapt_offset_mm, frame.adapt_gain = adapt.offset_, adapt.gain_
        if self.inverse is None:
            feedforward = 0.0
        elif adapt is not None:
            feedforward = self.inverse.step((ahead - adapt.offset_) / adapt.gain_)
        else:
            feedforward = self.inverse.step(ahead)
        correction = 0.0
        if self.correction is not None:
            last = self._previous_reference
            rate = (reference - last) / dt if last == last and dt > 0 else 0.0
            correction = self.correction.step((reference, rate, feedforward, y, p, self.last_command_bar))
        self._previous_reference = self.last_reference = reference
        bias = self.last_bias = feedforward + correction
        if not math.isfinite(bias):  # the supervisor trips on it; keep the PID state clean
            frame.reference_mm, frame.u_ff_bar, frame.u_nn_bar, frame.u_fb_bar, frame.u_bar = (
                reference,
                feedforward,
                correction,
                0.0,
                math.nan,
            )
            return math.nan
        total = self.pid.step(reference, y, dt, bias)
        feedback = total - bias
        lim, last_bar = self.limits, self.last_command_bar
        step = lim.slew_bar_per_s * dt
        if total > last_bar + step:
            total = last_bar + step
        elif total < last_bar - step:
            total = last_bar - step
        command = min(max(total, lim.pressure_min_bar), lim.pressure_max_bar)
        self.last_command_bar = self.sweep_command_bar = command
        frame.reference_mm, frame.u_ff_bar, frame.u_nn_bar, frame.u_fb_bar, frame.u_bar = (
            reference,
            feedforward,
            correction,
            feedback,
            command,
        )
        return command
