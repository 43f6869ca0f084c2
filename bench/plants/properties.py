"""Property checks shared by the plant contract (:mod:`bench.plants.contract`) and the families' own tests.

Each family has its own cores, effects and protocols; what a record of any of them must satisfy
(built the same for the same seed, any duration, a core's loop a plausible muscle loop) is
checked here once.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.family import Case
from bench.plants.visibility import EFFECT_MAX_OVER_SPAN, EFFECT_MIN_OVER_NOISE
from host.data import Measurement

Measure = Callable[[Case], tuple[Measurement, dict[str, Any]]]
Core = Callable[[NDArray[np.float64], float, dict[str, float]], NDArray[np.float64]]


def assert_deterministic_by_seed(cases: list[Case], measure: Measure, stride: int = 11) -> None:
    """Every ``stride``-th case recorded twice is the same record (output, input, columns,
    truth); the next seed gives another."""
    for case in cases[::stride]:
        a, ta = measure(case)
        b, tb = measure(case)
        assert np.array_equal(a.y, b.y) and np.array_equal(a.u, b.u) and str(ta) == str(tb)
        assert np.array_equal(a.extras["temperature"], b.extras["temperature"])
        assert np.array_equal(a.extras["load"], b.extras["load"])
    other = Case(**{**cases[0].__dict__, "seed": cases[0].seed + 1})
    assert not np.array_equal(measure(cases[0])[0].y, measure(other)[0].y)


def assert_any_duration_builds(cases_for: Callable[[float], list[Case]], measure: Measure, duration_s: float) -> None:
    """An effect record of ``duration_s`` has its length, finite samples and a visible, modest effect."""
    case = [c for c in cases_for(duration_s) if c.effect != "none"][7]
    m, truth = measure(case)
    assert len(m) == int(round(duration_s * case.rate_hz)) and np.all(np.isfinite(m.y))
    assert EFFECT_MIN_OVER_NOISE * truth["noise"] <= truth["effect_size"] <= EFFECT_MAX_OVER_SPAN * truth["span"]


def assert_closed_loop_3_to_20_percent_wide(
    core: Core,
    draw: Callable[[np.random.Generator, float], dict[str, float]],
    cycles: int = 4,
    settled_share: float = 0.02,
) -> None:
    """Over three parameter draws (``draw(rng, peak)``), ``core`` driven by 30 s triangles between
    5 % and 95 % of the peak pressure: a stroke of 10-50 mm, the last cycle within
    ``settled_share`` of the span of the one before (closed), and the descending branch above
    the ascending one between 30 % and 70 % of the peak, 3-20 % of the span apart."""
    for seed in range(3):
        rng = np.random.default_rng(100 + seed)
        peak = float(rng.uniform(3.0, 6.0))
        params = draw(rng, peak)
        dt, period = 0.01, 30.0
        t = np.arange(int(round(cycles * period / dt))) * dt
        u = peak * (0.05 + 0.9 * (1.0 - np.abs(2.0 * ((t / period) % 1.0) - 1.0)))
        y = core(u, dt, params)
        per = int(round(period / dt))
        span = float(np.ptp(y[-per:]))
        assert 10.0 <= span <= 50.0
        assert np.max(np.abs(y[-per:] - y[-2 * per : -per])) < settled_share * span  # settled into its cycle
        grid = np.linspace(0.3, 0.7, 9) * peak
        cu, cy, half = u[-per:], y[-per:], per // 2
        up = np.interp(grid, cu[:half], cy[:half])
        down = np.interp(grid, cu[half:][::-1], cy[half:][::-1])
        width = float(np.max(down - up)) / span
        assert np.all(down - up > 0.0) and 0.03 <= width <= 0.2, width


def step_and_hold(peak: float, dt: float) -> NDArray[np.float64]:
    """60 s of input [bar]: vented for 2 s, a step to 70 % of ``peak`` held until 30 s, then a
    step down to 30 % held: where creep shows and a rate-independent core settles."""
    t = np.arange(int(round(60.0 / dt)), dtype=np.float64) * dt
    return np.where(t < 2.0, 0.0, np.where(t < 30.0, 0.7 * peak, 0.3 * peak))


def triangles(peak: float, dt: float, period_s: float, cycles: int) -> NDArray[np.float64]:
    """``cycles`` triangles of ``period_s`` between 10 % and 90 % of ``peak`` [bar], sampled every ``dt``."""
    t = np.arange(int(round(cycles * period_s / dt)), dtype=np.float64) * dt
    return np.asarray(peak * (0.1 + 0.8 * (1.0 - np.abs(2.0 * ((t / period_s) % 1.0) - 1.0))), dtype=np.float64)


def slow_and_fast_triangles(
    peak: float, dt: float, periods_s: tuple[float, ...] = (40.0, 4.0)
) -> list[NDArray[np.float64]]:
    """Two :func:`triangles` at each period: the same loop slow and fast, for checking that a
    rate effect grows with the input speed."""
    return [triangles(peak, dt, period, 2) for period in periods_s]
