"""Wire time of a device per tick, and the fastest period a rig can meet."""

from __future__ import annotations

from dataclasses import dataclass

COMPUTE_BUDGET_S = 50e-6  # whole-tick compute budget (bench/edge_bench.py measures it)


@dataclass(frozen=True)
class WireTime:
    """What one device costs a tick: ``seconds`` on its wires and waits, the shortest period
    it allows on its own (a DAQ's sample interval, a pipelined conversion) [s], and how."""

    seconds: float
    min_period_s: float
    text: str


def fastest_period(times: list[WireTime]) -> tuple[float, str]:
    """The sum over devices plus the compute budget, or the slowest device's own minimum."""
    total = sum(w.seconds for w in times) + COMPUTE_BUDGET_S
    floor = max((w.min_period_s for w in times), default=0.0)
    text = "; ".join(w.text for w in times) + f"; plus {COMPUTE_BUDGET_S * 1e6:.0f} us compute"
    return max(total, floor), text
