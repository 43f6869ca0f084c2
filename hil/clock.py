"""A simulated clock for lockstep runs: waiting advances time instead of sleeping."""

from __future__ import annotations


class SimClock:
    """Implements :class:`edge.hal.clock.Clock`; deterministic, never sleeps."""

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)

    def now(self) -> float:
        return self._now

    def sleep_until(self, deadline: float) -> None:
        self._now = max(self._now, float(deadline))

    def advance(self, seconds: float) -> None:
        """Let ``seconds`` pass (bus latency, conversion waits)."""
        self._now += max(0.0, float(seconds))
