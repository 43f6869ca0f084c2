"""Fixed-period scheduling on absolute deadlines, lateness accounting and real-time settings.

Tick ``k`` is due at ``origin + k * period`` on the clock, never "period after the last one", so
errors do not accumulate. The wait sleeps until ``spin_s`` before the deadline and then polls
the clock (the kernel's sleep overshoots by 50-100 us on a stock kernel). A tick that starts
more than a period late is an overrun; the missed slots are skipped, not run in a burst.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import math
import os
from dataclasses import dataclass, field

import numpy as np

from edge.hal.clock import Clock

HISTOGRAM_LIMIT_US = 10_000  # 1 us bins up to 10 ms, one overflow bin beyond
MCL_CURRENT, MCL_FUTURE = 1, 2


@dataclass
class LatenessStats:
    """Distribution of tick start lateness [us] (1 us bins), overruns and the worst case."""

    ticks: int = 0
    overruns: int = 0
    skipped_ticks: int = 0
    worst_us: float = 0.0
    histogram: np.ndarray = field(default_factory=lambda: np.zeros(HISTOGRAM_LIMIT_US + 1, dtype=np.int64))

    def add(self, lateness_us: float) -> None:
        self.ticks += 1
        self.worst_us = max(self.worst_us, lateness_us)
        self.histogram[min(int(lateness_us), HISTOGRAM_LIMIT_US) if lateness_us > 0 else 0] += 1

    def percentile_us(self, q: float) -> float:
        """Upper edge of the bin holding the ``q``-th percentile (0..100) [us]."""
        if not self.ticks:
            return 0.0
        cumulative = np.cumsum(self.histogram)
        index = int(np.searchsorted(cumulative, math.ceil(q / 100.0 * self.ticks)))
        return float(min(index + 1, self.worst_us)) if index < HISTOGRAM_LIMIT_US else self.worst_us

    def summary(self) -> dict[str, float]:
        return {
            "ticks": self.ticks,
            "overruns": self.overruns,
            "skipped_ticks": self.skipped_ticks,
            "lateness_median_us": self.percentile_us(50),
            "lateness_p99_us": self.percentile_us(99),
            "lateness_p999_us": self.percentile_us(99.9),
            "lateness_max_us": self.worst_us,
            "overruns_per_10k": 1e4 * self.overruns / self.ticks if self.ticks else 0.0,
        }


class TickScheduler:
    """Waits for each tick's absolute deadline on ``clock``.

    Args:
        clock: the clock port (wall clock or the HIL's lockstep clock).
        period_s: tick period [s].
        spin_s: poll the clock for this long before a deadline instead of sleeping (0 for a
            simulated clock, where sleeping is exact).
    """

    def __init__(self, clock: Clock, period_s: float, spin_s: float = 0.0) -> None:
        self.clock, self.period_s, self.spin_s = clock, period_s, spin_s
        self.stats = LatenessStats()
        self.index = 0
        self._origin = clock.now()

    def start(self) -> None:
        """Tick 0 is due now."""
        self._origin = self.clock.now()
        self.index = 0

    @property
    def deadline(self) -> float:
        return self._origin + self.index * self.period_s

    def wait(self) -> tuple[float, float]:
        """Wait for the next tick; returns ``(t, lateness_s)`` with ``t`` the tick's due time
        relative to the start [s]. Counts an overrun and skips missed slots when late by more
        than a period."""
        clock, deadline = self.clock, self.deadline
        if self.spin_s > 0:
            clock.sleep_until(deadline - self.spin_s)
            while clock.now() < deadline:
                pass
        else:
            clock.sleep_until(deadline)
        lateness = clock.now() - deadline
        self.stats.add(lateness * 1e6)
        if lateness > self.period_s:
            self.stats.overruns += 1
            missed = int(lateness // self.period_s)
            self.stats.skipped_ticks += missed
            self.index += missed
        t = self.index * self.period_s
        self.index += 1
        return t, lateness


@dataclass
class RealtimeSettings:
    """What :func:`apply_realtime` managed to set, and why not where it failed."""

    notes: list[str] = field(default_factory=list)
    fifo: bool = False
    memory_locked: bool = False
    _previous_policy: int | None = None
    _previous_affinity: set[int] | None = None

    def restore(self) -> None:
        """Back to the scheduling policy and affinity from before (for in-process runs)."""
        if self._previous_policy is not None:
            try:
                os.sched_setscheduler(0, self._previous_policy, os.sched_param(0))
            except OSError:
                pass
        if self._previous_affinity is not None:
            os.sched_setaffinity(0, self._previous_affinity)
        if self.memory_locked:
            _libc().munlockall()


def _libc() -> ctypes.CDLL:
    return ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)


def apply_realtime(priority: int, cpu: int = -1, lock_memory: bool = True) -> RealtimeSettings:
    """SCHED_FIFO at ``priority``, pinned to ``cpu`` (-1: any), memory locked; each only where
    permitted, with a note saying what was done or what to change."""
    settings = RealtimeSettings()
    try:
        settings._previous_policy = os.sched_getscheduler(0)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        settings.fifo = True
        settings.notes.append(f"SCHED_FIFO priority {priority}")
    except (OSError, AttributeError) as exc:
        settings._previous_policy = None
        settings.notes.append(
            f"SCHED_FIFO not permitted ({exc}); grant CAP_SYS_NICE or an rtprio limit (see the systemd unit)"
        )
    if cpu >= 0:
        try:
            settings._previous_affinity = os.sched_getaffinity(0)
            os.sched_setaffinity(0, {cpu})
            settings.notes.append(f"pinned to CPU {cpu}")
        except OSError as exc:
            settings._previous_affinity = None
            settings.notes.append(f"CPU affinity {cpu} refused ({exc})")
    if lock_memory:
        if _libc().mlockall(MCL_CURRENT | MCL_FUTURE) == 0:
            settings.memory_locked = True
            settings.notes.append("memory locked (mlockall)")
        else:
            code = ctypes.get_errno()
            settings.notes.append(
                f"mlockall refused ({errno.errorcode.get(code, code)}); raise LimitMEMLOCK or run with CAP_IPC_LOCK"
            )
    return settings
