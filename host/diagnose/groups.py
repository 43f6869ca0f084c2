"""Each cause of :data:`host.diagnose.rules.CAUSES` as a group of regressors.

The regressors are first-order directions in which the cause would move M0's output (several
forms pooled, tested together as one group: a grid of time constants or dead times costs
degrees of freedom, not a floor). All are computed per run (memory restarts at each run) and
pass through the baseline's output lag when the cause acts before the mechanics.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from host.diagnose.nuisance import Baseline, run_gradient, run_lowpass, through_stage
from host.diagnose.rules import CAUSES, Rules
from host.diagnose.runs import RunSet


def _scaled(v: NDArray[np.float64]) -> NDArray[np.float64]:
    centred = v - v.mean(axis=0)
    spread = np.std(centred, axis=0)
    return np.asarray(centred / np.where(spread > 0, spread, 1.0), dtype=np.float64)


def branch_of(rs: RunSet, share: float = 0.1) -> NDArray[np.float64]:
    """Which branch the input is on, -1 rising .. +1 falling: a play operator of ``share`` of
    the input range, minus the input, over its threshold; restarted at each run."""
    width = share * float(np.ptp(rs.u))
    out = np.empty_like(rs.u)
    for a, b in rs.bounds():
        z = float(rs.u[a])
        for i, v in enumerate(rs.u[a:b].tolist()):
            z = min(max(z, v - width), v + width)
            out[a + i] = (z - v) / width
    return out


def rate_group(rs: RunSet, base: Baseline, branch: NDArray[np.float64]) -> NDArray[np.float64]:
    speed = run_lowpass(rs, run_gradient(rs, rs.u), 2 * rs.dt)
    s = speed / (float(np.percentile(np.abs(speed), 95)) or 1.0)
    xc = _scaled(base.x)
    out_rate = run_gradient(rs, base.prediction)
    v = out_rate / (float(np.percentile(np.abs(out_rate), 95)) or 1.0)
    slow_speed = run_lowpass(rs, np.abs(s), 0.3)
    columns = [s * branch, s * xc, np.abs(s) * xc, np.abs(s) * branch, slow_speed * branch, slow_speed * xc]
    lagged = through_stage(rs, base, np.column_stack(columns))
    return np.column_stack([lagged, v * np.abs(v)])


def creep_group(rs: RunSet, base: Baseline, rules: Rules) -> NDArray[np.float64]:
    run_length = max(b - a for a, b in rs.bounds()) * rs.dt
    span = min(run_length, float(rs.clock[-1]))
    taus = [tau for tau in rules.creep_taus_s if tau <= 0.5 * span and tau >= 5 * max(base.lag_s, rs.dt)]
    if not taus:
        return np.zeros((rs.y.size, 0))
    columns = [run_lowpass(rs, base.x, tau) - base.x for tau in taus]
    return through_stage(rs, base, np.column_stack(columns))


def _shifted(rs: RunSet, x: NDArray[np.float64], samples: int) -> NDArray[np.float64]:
    out = np.empty_like(x)
    for a, b in rs.bounds():
        seg = x[a:b]
        k = min(samples, seg.size)
        out[a:b] = np.r_[np.full(k, seg[0]), seg[: seg.size - k]]
    return out


def delay_group(rs: RunSet, base: Baseline, rules: Rules) -> NDArray[np.float64]:
    """The lagged hysteresis output at shifted times (a dead time before the hysteresis equals
    one after it for a rate-independent core), plus its second derivative (where a dead time and a
    lag differ at second order), each split by the input's direction (a valve that opens and
    exhausts through different paths)."""
    lagged = through_stage(rs, base, base.x)
    shifts = sorted({int(round(d / rs.dt)) for d in rules.delays_s if d / rs.dt >= rules.min_delay_samples})
    columns = [_shifted(rs, lagged, k) - lagged for k in shifts]
    curvature = run_gradient(rs, run_gradient(rs, lagged)) * rs.dt**2
    rising = (run_gradient(rs, rs.u) > 0).astype(float)
    columns += [curvature, run_gradient(rs, lagged) * rs.dt * rising]
    return np.column_stack(columns)


def column_group(
    rs: RunSet, base: Baseline, values: NDArray[np.float64], rules: Rules, branch: NDArray[np.float64]
) -> NDArray[np.float64]:
    """A measured column ``values`` (load or temperature): level, square, products with the
    output and the branch, and its first-order lags (a thermal or creep lag) with their product
    with the output. Columns constant in every run drop their lags (a lag of a constant is it)."""
    c = _scaled(values)
    xc = _scaled(base.x)
    columns = [c, c**2 - np.mean(c**2), c * xc, c * xc**2, c * branch]
    moves_within = any(np.ptp(values[a:b]) > 1e-9 * (np.ptp(values) or 1.0) for a, b in rs.bounds())
    if moves_within:
        for tau in rules.column_lags_s:
            lagged = _scaled(run_lowpass(rs, values, tau))
            columns += [lagged, lagged * xc]
    return through_stage(rs, base, np.column_stack(columns))


def clock_hats(rs: RunSet, knots: int) -> list[NDArray[np.float64]]:
    """Hat functions (linear B-splines) of the campaign clock on ``knots`` equally spaced knots,
    the first left out (it is the offset)."""
    clock = rs.clock
    grid = np.linspace(clock[0], clock[-1], knots)
    width = grid[1] - grid[0]
    return [np.clip(1.0 - np.abs(clock - k) / width, 0.0, None) for k in grid[1:]]


def drift_group(rs: RunSet, base: Baseline, rules: Rules) -> NDArray[np.float64]:
    """Hat functions of the campaign clock (``drift_knots`` of them, :func:`clock_hats`) and their
    product with the output: a slow change in time no column explains."""
    hats = clock_hats(rs, rules.drift_knots)
    xc = _scaled(base.x)
    return np.column_stack(hats + [h * xc for h in hats])


def cause_groups(rs: RunSet, base: Baseline, rules: Rules) -> dict[str, NDArray[np.float64]]:
    """Every cause's regressors this record can carry (a column cause only when its column moves)."""
    branch = branch_of(rs)
    groups = {
        "rate_dependence": rate_group(rs, base, branch),
        "creep": creep_group(rs, base, rules),
        "transport_delay": delay_group(rs, base, rules),
    }
    for cause in CAUSES.values():
        if cause.column and cause.column in rs.columns and np.ptp(rs.columns[cause.column]) > 0:
            groups[cause.name] = column_group(rs, base, rs.columns[cause.column], rules, branch)
    groups["slow_drift"] = drift_group(rs, base, rules)
    return {name: g for name, g in groups.items() if g.shape[1]}
