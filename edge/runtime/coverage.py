"""Does a run's reference stay where the bundle's correction was trained? (numpy only)

``pmactl train --model correction`` records in the manifest's correction entry which
references its training data covered (``coverage``: ``reference_mm`` [lo, hi] and
``reference_rate_mm_s`` [lo, hi]). The correction is a small net of (reference, rate,
feedforward): outside that box it extrapolates, and what it adds there is a guess. Before
arming, :func:`outside_coverage` samples the reference like the reach check
(:func:`edge.control.reference.beyond_reach`) and returns one warning line with the share of
the run outside the box, by range and by rate.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from edge.errors import BundleError

SAMPLE_S = 0.01  # the reference is sampled every 10 ms, as for the reach check
# a reference may pass each covered bound by this share of the covered span before it counts as
# outside: the recorded extremes come from a smoothed, noisy measurement, not an exact bound
MARGIN = 0.02
RECORD_COMMAND = "pmactl edge record --protocol sines --range LOW:HIGH"


@dataclass(frozen=True)
class Coverage:
    """What the correction's training data covered: contraction [mm] and its rate [mm/s]."""

    reference_mm: tuple[float, float]
    rate_mm_s: tuple[float, float]


def _pair(value: object, name: str, where: str) -> tuple[float, float]:
    if (
        not isinstance(value, list)
        or len(value) != 2
        or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in value)
        or value[0] > value[1]
    ):
        raise BundleError(
            f"{where}: correction coverage {name} is {value!r}, not [low, high] in finite numbers; "
            "retrain the correction with pmactl train --model correction"
        )
    return float(value[0]), float(value[1])


def read_coverage(spec: dict[str, object] | None, where: str) -> Coverage | None:
    """The coverage in a manifest's correction entry; ``None`` when it records none (a
    correction trained before coverage was recorded); one :class:`BundleError` line when it is
    malformed. ``where`` names the bundle in that line."""
    if spec is None or "coverage" not in spec:
        return None
    coverage = spec["coverage"]
    if not isinstance(coverage, dict):
        raise BundleError(
            f"{where}: correction coverage is a {type(coverage).__name__}, not an object; "
            "retrain the correction with pmactl train --model correction"
        )
    return Coverage(
        _pair(coverage.get("reference_mm"), "reference_mm", where),
        _pair(coverage.get("reference_rate_mm_s"), "reference_rate_mm_s", where),
    )


def _outside(values: np.ndarray, bounds: tuple[float, float]) -> np.ndarray:
    margin = MARGIN * (bounds[1] - bounds[0])
    return (values < bounds[0] - margin) | (values > bounds[1] + margin)


def outside_coverage(
    reference: Callable[[float], float], duration_s: float, coverage: Coverage, unit: str = "mm"
) -> str | None:
    """A warning line when ``reference`` leaves ``coverage`` over ``duration_s`` [s], else None.

    The rate is the reference's finite difference on the 10 ms grid (the tick's own rate feature
    is the same difference per tick, and a reference is smooth on that scale).
    """
    t = np.arange(0.0, duration_s, SAMPLE_S)
    if t.size < 2:
        return None
    wanted = np.array([reference(float(ti)) for ti in t])
    rate = np.gradient(wanted, SAMPLE_S)
    off_range, off_rate = _outside(wanted, coverage.reference_mm), _outside(rate, coverage.rate_mm_s)
    share = float(np.mean(off_range | off_rate))
    if share == 0.0:
        return None
    (lo, hi), (rlo, rhi) = coverage.reference_mm, coverage.rate_mm_s
    return (
        f"the reference leaves what the correction was trained on for {share:.0%} of the run "
        f"(range {wanted.min():.1f}..{wanted.max():.1f} {unit}, trained {lo:.1f}..{hi:.1f}: "
        f"{float(np.mean(off_range)):.0%} outside; rate {rate.min():.1f}..{rate.max():.1f} {unit}/s, "
        f"trained {rlo:.1f}..{rhi:.1f}: {float(np.mean(off_rate)):.0%} outside); the correction extrapolates "
        f"there: record sines that cover it ({RECORD_COMMAND}), retrain it (pmactl train --model correction) "
        "or run with --no-correction"
    )
