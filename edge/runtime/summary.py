"""What a run measured: the running tracking-error sums and the summary ``pmactl edge run``
prints (``--json``: :meth:`RunSummary.as_dict`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class ErrorStats:
    """Running tracking-error sums [mm] over the scored ticks."""

    count: int = 0
    sum_sq: float = 0.0
    sum_abs: float = 0.0
    max_abs: float = 0.0

    def add(self, error: float) -> None:
        self.count += 1
        self.sum_sq += error * error
        self.sum_abs += abs(error)
        self.max_abs = max(self.max_abs, abs(error))

    def summary(self) -> dict[str, float | None]:
        if not self.count:
            return {"rms_error": None, "mean_abs_error": None, "max_error": None}
        return {
            "rms_error": math.sqrt(self.sum_sq / self.count),
            "mean_abs_error": self.sum_abs / self.count,
            "max_error": self.max_abs,
        }


@dataclass
class RunSummary:
    """What ``pmactl edge run --json`` prints (errors in ``unit``: mm, deg on a joint)."""

    errors: ErrorStats
    lateness: dict[str, float]
    faults: list[str]
    notes: list[str] = field(default_factory=list)
    extra: dict[str, object] = field(default_factory=dict)

    unit: str = "mm"

    def as_dict(self) -> dict[str, object]:
        return {
            **self.errors.summary(),
            "ticks": self.lateness["ticks"],
            "overruns": self.lateness["overruns"],
            "lateness_p99_us": self.lateness["lateness_p99_us"],
            "faults": self.faults,
            "unit": self.unit,
            "scored_ticks": self.errors.count,
            "lateness": self.lateness,
            "realtime": self.notes,
            **self.extra,
        }
