"""The baseline of diagnosis v3: what is *not* an effect, as a linear nuisance space.

``M0``: rate-independent Preisach hysteresis (Everett nodes on a grid padded beyond the input's
range, smoothness-regularised; :func:`host.diagnose.runs.preisach_nodes`) after which one
first-order output lag acts (the rig's mechanics, its time constant chosen from
:attr:`host.diagnose.rules.Rules.output_lags_s` by profile least squares), plus the directions
in which M0's own settings could move it: the lag's tangent, an input lead (a snubber on the
pressure reading), a static output map (the square and cube of the hysteresis output). Nothing
in it depends on the input's speed, on time, or on a measured column, so a timing or column
effect keeps its own part (an actuator lag, :mod:`host.diagnose.actuator`, acts on the input
before it). The AR model of M0's residual (order by BIC) whitens every statistic.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from host.diagnose.runs import RunSet


def lowpass(x: NDArray[np.float64], dt: float, tau_s: float) -> NDArray[np.float64]:
    """``x`` (1-D or column by column) through a unit-gain first-order lag of ``tau_s`` [s],
    starting settled at its first sample (0: unchanged)."""
    if tau_s <= 0:
        return x
    a = 1.0 - np.exp(-dt / tau_s)
    return np.asarray(lfilter([a], [1.0, a - 1.0], x, axis=0, zi=x[:1] * (1 - a))[0])


def run_lowpass(rs: RunSet, x: NDArray[np.float64], tau_s: float) -> NDArray[np.float64]:
    """:func:`lowpass` restarted at each run."""
    out = np.empty_like(x, dtype=np.float64)
    for a, b in rs.bounds():
        out[a:b] = lowpass(x[a:b], rs.dt, tau_s)
    return out


def run_resonance(rs: RunSet, x: NDArray[np.float64], f_hz: float, zeta: float) -> NDArray[np.float64]:
    """``x`` through a unit-gain second-order stage ``y'' + 2 zeta w y' + w^2 y = w^2 x``
    (``w = 2 pi f_hz``; a payload mass on the muscle's stiffness), zero-order hold, settled at
    each run's first sample (``f_hz`` 0: unchanged)."""
    if f_hz <= 0:
        return x
    from scipy.signal import cont2discrete, lfilter_zi

    w = 2.0 * np.pi * f_hz
    num, den, _ = cont2discrete(([w * w], [1.0, 2.0 * zeta * w, w * w]), rs.dt, method="zoh")
    b, a = np.ravel(num), np.ravel(den)
    zi = lfilter_zi(b, a)
    out = np.empty_like(x, dtype=np.float64)
    for lo, hi in rs.bounds():
        seg = x[lo:hi]
        start = np.multiply.outer(zi, seg[0]) if seg.ndim > 1 else zi * seg[0]
        out[lo:hi] = lfilter(b, a, seg, axis=0, zi=start)[0]
    return out


def run_gradient(rs: RunSet, x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Time derivative per run [units / s] (one-sided at each run's ends)."""
    out = np.empty_like(x, dtype=np.float64)
    for a, b in rs.bounds():
        out[a:b] = np.gradient(x[a:b], rs.dt, axis=0) if b - a > 1 else 0.0
    return out


def ridge_fit(
    design: NDArray[np.float64],
    y: NDArray[np.float64],
    smoothness: NDArray[np.float64],
    strength: float,
    tail_cols: int | Sequence[int] = 0,
) -> NDArray[np.float64]:
    """Penalised least squares: ``strength`` x the block's mean diagonal x ``smoothness`` (a
    k x k matrix, D^T D of neighbouring-node differences) on the first k columns (the Preisach
    nodes: smooth, so cells no training row visits take their neighbours' values), and a ridge
    of ``strength`` x its own mean diagonal on each block of the last columns (``tail_cols``: the
    blocks' widths in order, or one width; a cause's group: collinear with the nuisance's lags, it
    must not cancel them in training and fail held out). Each block is scaled by itself, so a
    group carries the same ridge whatever other groups sit beside it."""
    gram = design.T @ design
    return np.asarray(np.linalg.solve(gram + ridge_penalty(gram, smoothness, strength, tail_cols), design.T @ y))


def ridge_penalty(
    gram: NDArray[np.float64],
    smoothness: NDArray[np.float64],
    strength: float,
    tail_cols: int | Sequence[int] = 0,
) -> NDArray[np.float64]:
    """The penalty :func:`ridge_fit` adds to ``gram`` (the design's X^T X): see there; for fits
    assembled from Gram blocks (:mod:`host.diagnose.heldout_surrogates`)."""
    diag = np.diag(gram)
    k = smoothness.shape[0]
    penalty = np.diag(np.full(gram.shape[0], 1e-10 * (float(diag.mean()) or 1.0)))
    if k:
        penalty[:k, :k] += strength * (float(diag[:k].mean()) or 1.0) * (smoothness + 1e-4 * np.eye(k))
    blocks = [tail_cols] if isinstance(tail_cols, int) else list(tail_cols)
    stop = gram.shape[0]
    for width in reversed([w for w in blocks if w]):
        block = slice(stop - width, stop)
        penalty[block, block] += strength * (float(diag[block].mean()) or 1.0) * np.eye(width)
        stop -= width
    return penalty


@dataclass
class Baseline:
    """M0 fitted to every row, and the nuisance columns the tests partial out."""

    nuisance: NDArray[np.float64]  # n x p: lagged nodes, tangents, output map, constant
    smoothness: NDArray[np.float64]  # D^T D over the first columns of ``nuisance`` (the Preisach nodes)
    x: NDArray[np.float64]  # the hysteresis output (static, before the lag) [units of y]
    prediction: NDArray[np.float64]  # M0's output on every row [units of y]
    lag_s: float
    resonance: tuple[float, float] = (0.0, 0.0)  # (f [Hz], zeta) of the second-order stage; f 0: none
    second_lag_s: float = 0.0  # a second first-order lag in series with ``lag_s`` [s]; 0: none

    @property
    def residual_scale(self) -> float:
        return float(np.std(self.prediction))


def linear_stage(
    rs: RunSet, v: NDArray[np.float64], lag_s: float, resonance: tuple[float, float], second_lag_s: float
) -> NDArray[np.float64]:
    """``v`` through an output lag [s], a second lag in series [s] (0: none), then a second-order
    stage (f [Hz], zeta; f 0: none), each run from its own first sample."""
    return run_resonance(rs, run_lowpass(rs, run_lowpass(rs, v, lag_s), second_lag_s), *resonance)


def through_stage(rs: RunSet, base: Baseline, v: NDArray[np.float64]) -> NDArray[np.float64]:
    """``v`` through the baseline's linear dynamics: its output lag(s), then its second-order stage."""
    return linear_stage(rs, v, base.lag_s, base.resonance, base.second_lag_s)


# rows the profile choice of the output lag in :func:`fit_baseline` uses at most (every k-th row)
PROFILE_ROWS = 2_000


def fit_baseline(
    rs: RunSet,
    nodes: NDArray[np.float64],
    smoothness: NDArray[np.float64],
    lags_s: tuple[float, ...],
    ridge: float,
    extra_lags_s: tuple[float, ...] = (),
    resonances_hz: tuple[float, ...] = (),
    resonance_zetas: tuple[float, ...] = (),
    series_lags_s: tuple[float, ...] = (),
) -> Baseline:
    """M0 (see module docstring): the output lag by profile least squares (the masses refitted
    through every candidate of ``lags_s``), then the masses through it. With a second-order stage
    the lag and stage are chosen on the lagged output of a static fit instead (one alternation).

    ``series_lags_s`` (empty: off) adds a second first-order lag in series, chosen with the first
    from pairs of the two grids (second <= first, 0 = none) by the same least squares: a valve
    and the mechanics in series give an S-shaped step response that one lag or a sum of parallel
    lags cannot make and that a dead-time or rate test would otherwise take for its own. Both lags
    are minimum-phase, so a pure delay stays out of the baseline; the second lag's tangent (a
    longer second lag) joins the nuisance."""
    y = rs.y
    ones = np.ones((y.size, 1))
    usable = [tau for tau in lags_s if tau == 0 or tau >= 0.5 * rs.dt]
    # the lag and the second-order stage are chosen together (a lag alone would stand in for a
    # resonance and leave the stage a wrong one)
    stages = [(0.0, 0.0)] + [(f, z) for f in resonances_hz if f < 0.2 / rs.dt for z in resonance_zetas]
    seconds = [0.0] + [tau for tau in series_lags_s if tau >= 0.5 * rs.dt]
    pairs = [(tau, tau2) for tau in usable for tau2 in seconds if tau2 == 0 or 0 < tau2 <= tau]

    def masses_through(
        pair: tuple[float, float], resonance: tuple[float, float]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(lagged nodes, hysteresis output x) with the masses fitted through these dynamics."""
        lagged = linear_stage(rs, nodes, pair[0], resonance, pair[1])
        theta = ridge_fit(np.hstack([lagged, ones]), y, smoothness, ridge)
        return lagged, nodes @ theta[:-1]

    if len(stages) == 1:
        # the lag(s) by profile least squares, the masses refitted through every candidate (on every
        # k-th row, at most PROFILE_ROWS: the choice, not the fit); choosing on a static fit's output
        # picks too short a lag (it lags the wrong way: 0.02 s for a 0.05 s lag on a generalised-play
        # plant, the rest left to the rate and delay tests), and alternating never leaves that choice
        rows = slice(None, None, -(-y.size // PROFILE_ROWS))

        def profile_error(pair: tuple[float, float]) -> float:
            lagged = np.hstack([linear_stage(rs, nodes, pair[0], (0.0, 0.0), pair[1]), ones])[rows]
            coef = ridge_fit(lagged, y[rows], smoothness, ridge)
            return float(np.sum((lagged @ coef - y[rows]) ** 2))

        (lag, second), resonance = min(pairs, key=profile_error), (0.0, 0.0)
    else:
        # with a second-order stage the pairs are chosen on the lagged output of the masses: a
        # static fit's, then once more on the masses refitted through the first choice when two lags
        # are in series

        def stage_error(choice: tuple[tuple[float, float], tuple[float, float]]) -> float:
            z = np.column_stack([run_resonance(rs, lagged_by[choice[0]], *choice[1]), ones])
            coef = np.linalg.lstsq(z, y, rcond=None)[0]
            return float(np.sum((z @ coef - y) ** 2))

        theta = ridge_fit(np.hstack([nodes, ones]), y, smoothness, ridge)
        x = nodes @ theta[:-1]
        for step in range(2 if series_lags_s else 1):
            if step:
                x = masses_through((lag, second), resonance)[1]
            lagged_by = {pair: run_lowpass(rs, run_lowpass(rs, x, pair[0]), pair[1]) for pair in pairs}
            (lag, second), resonance = min(((pair, fz) for pair in pairs for fz in stages), key=stage_error)
    lagged_nodes, x = masses_through((lag, second), resonance)
    xc = (x - x.mean()) / (np.std(x) or 1.0)
    lagged_x = linear_stage(rs, x, lag, resonance, second)
    columns = [
        linear_stage(rs, x, 1.5 * lag + rs.dt, resonance, second) - lagged_x,  # a longer output lag
        linear_stage(rs, run_gradient(rs, x), lag, resonance, second) * rs.dt,  # an input lead (snubber on the reading)
        linear_stage(rs, xc**2, lag, resonance, second),  # the static output map
        linear_stage(rs, xc**3, lag, resonance, second),
    ] + [linear_stage(rs, x, tau, resonance, second) - lagged_x for tau in extra_lags_s if tau != lag]
    if resonance[0] > 0:  # the stage's own tangents: a stiffer or softer payload, more or less damping
        f, z = resonance
        columns += [
            linear_stage(rs, x, lag, (1.25 * f, z), second) - lagged_x,
            linear_stage(rs, x, lag, (f, z + 0.15), second) - lagged_x,
        ]
    if series_lags_s:  # the second lag's tangent (a longer one; from none: the shortest of its grid)
        longer = 1.5 * second + rs.dt if second > 0 else min(seconds[1:], default=rs.dt)
        columns.append(linear_stage(rs, x, lag, resonance, longer) - lagged_x)
    nuisance = np.hstack([lagged_nodes, np.column_stack(columns), ones])
    coef = ridge_fit(nuisance, y, smoothness, ridge)
    return Baseline(nuisance, smoothness, x, nuisance @ coef, lag, resonance, second)


def with_nuisance(rs: RunSet, base: Baseline, extra: NDArray[np.float64], ridge: float) -> Baseline:
    """``base`` with ``extra`` nuisance columns inserted before its constant, and M0's prediction
    refitted (the hysteresis output ``x`` and the lag stay those of the Preisach fit)."""
    nuisance = np.hstack([base.nuisance[:, :-1], extra, base.nuisance[:, -1:]])
    coef = ridge_fit(nuisance, rs.y, base.smoothness, ridge)
    return Baseline(nuisance, base.smoothness, base.x, nuisance @ coef, base.lag_s, base.resonance, base.second_lag_s)


def ar_whitener(residual: NDArray[np.float64], max_order: int) -> NDArray[np.float64]:
    """AR coefficients ``a`` (``e_k = sum a_i e_{k-i} + w_k``) of ``residual``, order 0..``max_order``
    by BIC, fitted by least squares (stable by construction when the roots are checked)."""
    n = residual.size
    max_order = int(min(max_order, n // 20))
    best = (n * np.log(float(np.var(residual)) or 1e-300), np.zeros(0))
    if max_order < 1:
        return best[1]
    lagged = np.column_stack([np.r_[np.zeros(i), residual[: n - i]] for i in range(1, max_order + 1)])
    target = residual[max_order:]
    for p in range(1, max_order + 1):
        z = lagged[max_order:, :p]
        a = np.linalg.lstsq(z, target, rcond=None)[0]
        if np.any(np.abs(np.roots(np.r_[1.0, -a])) >= 0.999):
            continue
        rss = float(np.sum((target - z @ a) ** 2))
        bic = target.size * np.log(rss / target.size or 1e-300) + p * np.log(target.size)
        if bic < best[0]:
            best = (bic, a)
    return best[1]


def whiten(rs: RunSet, values: NDArray[np.float64], ar: NDArray[np.float64]) -> NDArray[np.float64]:
    """``values`` (1-D or columns) through ``1 - sum a_i q^-i``, restarted at each run."""
    if ar.size == 0:
        return values
    out = np.empty_like(values, dtype=np.float64)
    for a, b in rs.bounds():
        seg = values[a:b]
        # the filter starts as if the run's first value had been there for ever
        zi_scale = np.cumsum(ar[::-1])[::-1]
        zi = -np.outer(zi_scale, seg[0]) if seg.ndim > 1 else -zi_scale * seg[0]
        out[a:b] = lfilter(np.r_[1.0, -ar], [1.0], seg, axis=0, zi=zi)[0]
    return out


def kept_rows(rs: RunSet, order: int) -> NDArray[np.bool_]:
    """Rows a whitened statistic uses: each run without its first ``order`` samples."""
    keep = np.ones(rs.y.size, dtype=bool)
    for a, b in rs.bounds():
        keep[a : min(b, a + order)] = False
    return keep
