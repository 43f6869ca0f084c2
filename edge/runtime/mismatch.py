"""Does the bundle match this rig? The share of the command the feedback carries, on average
over a window, while the feedforward runs.

With a model that matches the rig, the feedforward supplies the command and the PID only
corrects what the model leaves. With a model of another muscle the PID carries a steady part
of it: negative when the model drives too hard, positive when it drives too little. The
measure is ``mean(feedback) / mean(|feedforward + feedback|)`` over ``window_s``: dimensionless,
so one limit serves any rig and operating point. On the emulated muscle tracking sines of 10-70
mm at 0.2-0.5 Hz (mean command 0.7-2.5 bar) a matching bundle gives 0.01-0.17 (0.17 only where
the reference leaves the bundle's reach), bundles of muscles needing 1.5x / 0.7x the pressure
-0.23..-0.47 / +0.30..+0.41, and 2x / 0.5x -0.60..-0.96 / +0.50..+0.58. A share beyond
``limit`` is reported once, as a warning line and event, or as a fault when the config asks
(``[safety] mismatch_*``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass
class MismatchMonitor:
    """Block averages of the feedback and the command (see the module docstring); pure, per tick."""

    limit: float  # share of the command; 0 disables
    window_s: float
    unit: str = "bar"
    warning: str | None = None
    _feedback: float = 0.0
    _command: float = 0.0
    _count: int = 0
    _end: float = math.nan

    def reset(self) -> None:
        self.warning, self._feedback, self._command, self._count, self._end = None, 0.0, 0.0, 0, math.nan

    def add(self, t: float, feedforward: float, feedback: float) -> str | None:
        """Feed one tick; the warning text when a window ends beyond the limit (the first time)."""
        if self._end != self._end:
            self._end = t + self.window_s
        self._feedback += feedback
        total = feedforward + feedback
        self._command += total if total >= 0.0 else -total
        self._count += 1
        if t < self._end:
            return None
        feedback_mean, command_mean = self._feedback / self._count, self._command / self._count
        self._feedback, self._command, self._count, self._end = 0.0, 0.0, 0, t + self.window_s
        if self.warning is not None or command_mean <= 1e-9:
            return None
        share = feedback_mean / command_mean
        if abs(share) <= self.limit:
            return None
        way = "drives too hard (the PID takes some off)" if share < 0 else "drives too little (the PID adds)"
        self.warning = (
            f"the bundle may not match this rig: over {self.window_s:g} s the feedback carried {share:+.0%} of the "
            f"command ({feedback_mean:+.2f} of {command_mean:.2f} {self.unit} on average; limit {self.limit:.0%}), "
            f"the model {way}; record and fit on this rig (pmactl edge record, pmactl fit)"
        )
        return self.warning
