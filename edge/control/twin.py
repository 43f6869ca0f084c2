"""The forward twin: the bundle's forward model run beside the muscle, and a watch on its residual.

Each tick the twin predicts the contraction [mm] from the pressure actually applied (the
measured pressure when the rig reads one, else the previous command after limits) and the
residual ``measured - predicted`` goes into the frame (``twin_mm``, ``twin_residual_mm``).
A model that fits the muscle leaves a residual of its own fit error (a few percent of its
output span); a bundle of another muscle, a position sensor that slipped off the muscle, or a
leaking muscle (it contracts less than the pressure at the valve says) leave a residual that
stays large. :class:`TwinWatch` takes the RMS of the residual over consecutive windows of
``window_s`` and reports once when one window's RMS exceeds the warning bound, and a fault
when a fault bound is set (``[safety] twin_mismatch_mm``) and exceeded. It does not wait for
the window's end when the squares summed so far already put its RMS above the bound (a large
residual is reported in a fraction of the window). A tick whose pressure lies outside the
forward table's range has no residual (NaN): the table would only extrapolate there.

:class:`ForwardModel` is the whole contract a forward model meets (the lookup table,
:class:`edge.hysteresis.lut.CompiledModel`, does; so may a trained net).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

TWIN_OK, TWIN_WARN, TWIN_FAULT = 0, 1, 2


@runtime_checkable
class ForwardModel(Protocol):
    """A forward model with memory: pressure [bar] in, contraction [mm] out, one tick at a time."""

    def reset(self) -> None:
        """Back to the rest state the model was exported in (the vented muscle)."""

    def step(self, pressure_bar: float) -> float:
        """The contraction [mm] after this tick's pressure [bar]."""


@dataclass
class TwinWatch:
    """Block RMS of the twin residual [mm] over ``window_s`` [s] (pure, per tick).

    Args:
        warn_mm: a window RMS above this is reported once as a warning (0 disables).
        fault_mm: a window RMS above this is a fault (0 disables).
        window_s: the length of one window [s].
        period_s: the tick period [s] (how many ticks a window holds).
    """

    warn_mm: float
    fault_mm: float = 0.0
    window_s: float = 2.0
    period_s: float = 0.001
    warning: str | None = None
    fault: str | None = None
    worst_rms_mm: float = 0.0  # the largest window RMS so far (the run's summary shows it)
    warned_at_s: float | None = None  # the tick time [s] of the warning
    _sum_sq: float = 0.0
    _count: int = 0
    _end: float = math.nan

    def reset(self) -> None:
        self.warning = self.fault = self.warned_at_s = None
        self.worst_rms_mm, self._sum_sq, self._count, self._end = 0.0, 0.0, 0, math.nan

    def add(self, t: float, residual_mm: float) -> int:
        """Feed one tick's residual at ``t`` [s]; ``TWIN_WARN`` the first time a window's RMS
        passes the warning bound, ``TWIN_FAULT`` when it passes the fault bound, else ``TWIN_OK``."""
        if self._end != self._end:
            self._end = t + self.window_s
        if residual_mm == residual_mm:  # a held tick has no reading
            self._sum_sq += residual_mm * residual_mm
            self._count += 1
        if t < self._end:
            # the window's RMS counting its remaining ticks as zero: past a bound already, do not wait
            rms = math.sqrt(self._sum_sq / (self.window_s / self.period_s))
            if not (self.fault_mm > 0.0 and rms > self.fault_mm) and not (
                self.warning is None and self.warn_mm > 0.0 and rms > self.warn_mm
            ):
                return TWIN_OK
        else:
            rms = math.sqrt(self._sum_sq / self._count) if self._count else 0.0
            self._sum_sq, self._count, self._end = 0.0, 0, t + self.window_s
            if rms > self.worst_rms_mm:
                self.worst_rms_mm = rms
        if self.fault_mm > 0.0 and rms > self.fault_mm:
            self.fault = (
                f"the forward twin's residual RMS over {self.window_s:g} s reached {rms:.2f} mm "
                f"> twin_mismatch_mm {self.fault_mm:g} mm: {CAUSES}"
            )
            return TWIN_FAULT
        if self.warning is None and self.warn_mm > 0.0 and rms > self.warn_mm:
            self.warning = (
                f"the forward twin's residual RMS over {self.window_s:g} s reached {rms:.2f} mm "
                f"(bound {self.warn_mm:.2f} mm): {CAUSES}"
            )
            self.warned_at_s = t
            return TWIN_WARN
        return TWIN_OK


CAUSES = (
    "the muscle no longer moves as the bundle predicts from its pressure (a bundle of another muscle, "
    "a position sensor off the muscle, or a leak); check the sensor mount and the tubing, then record and "
    "fit on this rig (pmactl edge record, pmactl fit)"
)
