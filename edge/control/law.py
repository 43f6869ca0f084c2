"""The contract between a control law and the supervisor that runs it.

A control law (:class:`~edge.control.tick.Controller` for one muscle,
:class:`~edge.control.joint.JointController` for the antagonistic joint, their open-loop
subclasses in :mod:`edge.control.openloop`) is driven by :class:`edge.runtime.safety.Supervisor`
through :class:`ControlLaw` alone: arm, fill the frame, hold on a failed read, vent, and a few
read-only values of the latest tick. The frame is typed by the fields each side uses
(:class:`TickFrame` for the supervisor, :class:`MuscleFrame` / :class:`JointFrame` for the law);
the runtime's ctypes row (:mod:`edge.runtime.frame`) and :class:`~edge.control.tick.ScratchFrame`
both satisfy them.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol, TypeVar


@dataclass(slots=True)
class Readings:
    """Sensor values at arming: the controlled output (contraction [mm], or a joint's angle
    [deg]) and the pressure [bar]."""

    contraction_mm: float
    pressure_bar: float = float("nan")


class TickFrame(Protocol):
    """The fields of a tick's frame every supervisor uses (units in the names; ``state`` and
    ``fault`` are codes, see :mod:`edge.runtime.frame`)."""

    t: float
    lateness_us: float
    u_bar: float
    pressure_bar: float
    estop: float
    valve_enable: float
    state: int
    fault: int


class MuscleFrame(TickFrame, Protocol):
    """A single muscle's frame: what :class:`~edge.control.tick.Controller` reads and fills."""

    contraction_mm: float
    reference_mm: float
    u_ff_bar: float
    u_nn_bar: float
    u_fb_bar: float
    twin_mm: float
    twin_residual_mm: float
    adapt_offset_mm: float
    adapt_gain: float


class JointFrame(TickFrame, Protocol):
    """An antagonistic joint's frame: what :class:`~edge.control.joint.JointController` fills
    (angles [deg]; ``u_bar`` is valve A, ``valve_b_bar`` valve B)."""

    reference_deg: float
    u_ff_deg: float
    u_fb_deg: float
    valve_b_bar: float


F_contra = TypeVar("F_contra", bound=TickFrame, contravariant=True)


class ControlLaw(Protocol[F_contra]):
    """What the supervisor needs of a control law; the law fills frames of type ``F_contra``.

    ``inverse`` and ``correction`` say which models run (the run summary and the mismatch
    monitor read them); ``twin`` is the forward model or None. The values of the latest tick
    are read-only through this protocol (mypy refuses an assignment); the laws keep them as
    plain attributes, which the supervisor reads every tick without a property call.
    """

    @property
    def inverse(self) -> object | None: ...

    @property
    def correction(self) -> object | None: ...

    @property
    def twin(self) -> object | None: ...

    def arm(self, readings: Readings, pressure_bar: float = 0.0) -> None:
        """Bumpless start from ``readings``; every model state back to its rest state."""

    def fill_from(self, frame: F_contra, dt: float, t: float, y: float, p: float) -> float:
        """Fill the command fields of ``frame`` for time ``t`` [s], output ``y`` and pressure
        ``p`` [bar] after a tick of ``dt`` [s]; returns the valve command [bar] (NaN when the
        model's output is not finite)."""

    def hold(self, frame: F_contra, armed: bool) -> None:
        """The sensor could not be read this tick: put the latest valve commands (zero before
        the first run tick, ``armed``) in the frame, model states untouched."""

    def vent(self, frame: F_contra) -> None:
        """Set every valve command of ``frame`` to the vent state (0 bar)."""

    @property
    def last_command_bar(self) -> float:
        """The latest valve command [bar] (valve A on a joint)."""

    @property
    def sweep_command_bar(self) -> float:
        """The command whose sweep must move the output (the stuck-sensor check) [bar]: the
        valve command, or a joint's differential pressure (co-contraction moves no angle)."""

    @property
    def last_reference(self) -> float:
        """The reference of the latest tick (mm, or deg on a joint); NaN when there is none."""

    @property
    def last_bias(self) -> float:
        """Feedforward + correction of the latest tick (bar, or deg of commanded angle)."""
