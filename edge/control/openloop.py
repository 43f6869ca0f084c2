"""Open-loop excitation for ``pmactl edge record``: the command follows a protocol
(:mod:`edge.control.protocols`), with no model and no feedback, inside the same limits as the
closed loop.

The controllers keep the interface the supervisor drives (:class:`~edge.control.tick.Controller`,
:class:`~edge.control.joint.JointController`), so every safety check of a closed-loop run runs
unchanged. There is no reference: ``last_reference`` (and the frame's reference field) is NaN,
so no tracking-error fault and no tracking score; the protocol's request goes into the
feedforward field (``u_ff_bar``; ``u_ff_deg`` on a joint) and the limited command into ``u_bar``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from edge.control.joint import COMMAND_LIMIT_DEG, JointController, JointModel
from edge.control.law import JointFrame, MuscleFrame
from edge.control.pid import PIDGains
from edge.control.tick import Controller, Limits

NO_FEEDBACK = PIDGains(0.0, 0.0, 0.0)


class OpenLoop(Controller):
    """A muscle's valve [bar] follows ``command(t)``, slew- and range-limited by ``limits``."""

    def __init__(self, command: Callable[[float], float], limits: Limits) -> None:
        super().__init__(command, NO_FEEDBACK, None, limits)

    def fill_from(self, frame: MuscleFrame, dt: float, t: float, y: float, p: float) -> float:
        wanted = self.last_bias = self.reference(t)
        lim, last = self.limits, self.last_command_bar
        step = lim.slew_bar_per_s * dt
        command = min(max(wanted, last - step), last + step)
        command = min(max(command, lim.pressure_min_bar), lim.pressure_max_bar)
        self.last_command_bar = self.sweep_command_bar = command
        self.last_reference = math.nan
        frame.reference_mm, frame.u_ff_bar, frame.u_nn_bar, frame.u_fb_bar, frame.u_bar = (
            math.nan,
            wanted,
            0.0,
            0.0,
            command,
        )
        return command


class OpenLoopJoint(JointController):
    """A joint commanded to the angle ``command(t)`` [deg] through its static inversion alone
    (what the joint's inverse Preisach model is identified on, :mod:`edge.control.joint`)."""

    def __init__(self, command: Callable[[float], float], model: JointModel, limits: Limits) -> None:
        super().__init__(command, NO_FEEDBACK, model, None, limits)

    def fill_from(self, frame: JointFrame, dt: float, t: float, y: float, p: float) -> float:
        wanted = self.last_bias = self.reference(t)
        commanded = min(max(wanted, -COMMAND_LIMIT_DEG), COMMAND_LIMIT_DEG)
        p_a, p_b = self.valves(commanded, dt)
        self.last_reference = math.nan
        frame.reference_deg, frame.u_ff_deg, frame.u_fb_deg = math.nan, commanded, 0.0
        frame.u_bar, frame.valve_b_bar = p_a, p_b
        return p_a
