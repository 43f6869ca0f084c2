"""The composite structural null of diagnosis v3: a parametric bootstrap from effect-free model
classes other than the baseline's (a simulation-based Cox test; anchors A8).

The block bootstrap treats the baseline's structural error as noise and the within-state
permutation ignores its serial dependence; neither says how much a rate-independent plant of a
*different* class projects on a cause's directions when the 16-level Preisach baseline is fitted
to it. Here each of three effect-free, rate-independent classes is fitted to the record:

* ``preisach_24``: the smooth-density Preisach at the richer level count;
* ``generalised_pi``: play operators on a uniform threshold grid, then a cubic output map;
* ``bouc_wen``: the Bouc-Wen differential model (n = 1, shape on a grid), then a cubic map;

each followed by the baseline's first-order output lag. Each is simulated on the record's own
input plus noise drawn from the residual of the *unrestricted* regression (the baseline and
every cause group: what no model of the pipeline explains), AR-whitened, resampled by the
stationary block bootstrap and re-coloured by the same AR filter (input-locked structure broken,
spectrum kept). The classes' own residuals are not used: they hold the effect under test, whose
slow excursions would then inflate the null and take the test's power (measured: a hidden creep
whose statistic is 60 times its degrees of freedom had p = 0.13 against them).
The default baseline's design is fixed by the input (same ``u``, same nodes, lag and
whitener), so every simulated record's statistics are projections on precomputed bases: a draw
costs a filter and a few matrix products, not a refit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from edge.hysteresis.pi import play_outputs
from host.diagnose.nuisance import Baseline, ar_whitener, ridge_fit, run_lowpass, whiten
from host.diagnose.rules import Rules
from host.diagnose.runs import RunSet, preisach_basis

Matrix = NDArray[np.float64]

# Bouc-Wen shape grid (n = 1, A = 1, input scaled to [-1, 1]): saturation 1/(beta+gamma) of the
# input's half range, and the share of beta (loop fatness) in beta+gamma
_BW_STIFFNESS = (0.5, 1.0, 2.0, 4.0, 8.0)
_BW_BETA_SHARE = (0.25, 0.5, 0.75)
_PI_THRESHOLDS = 10


@dataclass
class NullClass:
    """One effect-free class fitted to the record."""

    name: str
    fit: NDArray[np.float64]  # its noise-free output on the record's input [units of y]
    rms_error: float  # RMS of y minus ``fit`` [units of y]


def _through_lag(rs: RunSet, features: Matrix, lag_s: float) -> NDArray[np.float64]:
    """Least-squares fit of y on ``features`` (plus a constant) after the output lag."""
    design = np.column_stack([run_lowpass(rs, features, lag_s), np.ones(rs.y.size)])
    coef = np.linalg.lstsq(design, rs.y, rcond=None)[0]
    return np.asarray(design @ coef)


def _cubic_map(rs: RunSet, core: Matrix, lag_s: float) -> NDArray[np.float64]:
    """A hysteresis core's columns fitted to y, then a cubic map of that single output."""
    first = _through_lag(rs, core, 0.0)
    h = (first - first.mean()) / (np.std(first) or 1.0)
    return _through_lag(rs, np.column_stack([core, h**2, h**3]), lag_s)


def _scaled_input(rs: RunSet) -> NDArray[np.float64]:
    mid, half = 0.5 * (rs.u.max() + rs.u.min()), 0.5 * (float(np.ptp(rs.u)) or 1.0)
    return np.asarray((rs.u - mid) / half)


def pi_plays(rs: RunSet) -> Matrix:
    """Play operators on a uniform threshold grid of the scaled input, each run starting relaxed
    at its first input (n x thresholds)."""
    u = _scaled_input(rs)
    thresholds = np.arange(_PI_THRESHOLDS) * 1.0 / _PI_THRESHOLDS
    return np.vstack([play_outputs(u[a:b], thresholds, np.full(thresholds.size, u[a])) for a, b in rs.bounds()])


def generalised_pi(rs: RunSet, lag_s: float) -> NDArray[np.float64]:
    """Plays on a uniform threshold grid, then a cubic output map and the lag."""
    return _cubic_map(rs, pi_plays(rs), lag_s)


def _bouc_wen_state(u: list[float], stiffness: float, beta_share: float) -> list[float]:
    beta, gamma = beta_share * stiffness, (1.0 - beta_share) * stiffness
    z, previous, out = 0.0, u[0], []
    for v in u:
        du = v - previous
        z += du - beta * abs(du) * z - gamma * du * abs(z)
        previous = v
        out.append(z)
    return out


def bouc_wen_core(rs: RunSet, lag_s: float) -> tuple[Matrix, NDArray[np.float64]]:
    """The Bouc-Wen model (n = 1) whose shape on the grid fits best: its [input, state] columns
    and its fit (through a cubic map and the lag)."""
    u = _scaled_input(rs)
    best: tuple[float, Matrix, NDArray[np.float64]] = (np.inf, np.zeros((rs.y.size, 0)), rs.y)
    for stiffness in _BW_STIFFNESS:
        for share in _BW_BETA_SHARE:
            z = np.concatenate([_bouc_wen_state(u[a:b].tolist(), stiffness, share) for a, b in rs.bounds()])
            core = np.column_stack([u, z])
            fit = _cubic_map(rs, core, lag_s)
            sse = float(np.sum((rs.y - fit) ** 2))
            if sse < best[0]:
                best = (sse, core, fit)
    return best[1], best[2]


def bouc_wen(rs: RunSet, lag_s: float) -> NDArray[np.float64]:
    """The best-fitting Bouc-Wen model's output (see :func:`bouc_wen_core`)."""
    return bouc_wen_core(rs, lag_s)[1]


def null_classes(rs: RunSet, base: Baseline, rules: Rules) -> list[NullClass]:
    """The effect-free classes of the composite null, fitted to the record."""
    nodes, smoothness, _ = preisach_basis(rs, rules.richer_levels, rules.preisach_pad_levels)
    lagged = np.column_stack([run_lowpass(rs, nodes, base.lag_s), np.ones(rs.y.size)])
    richer = lagged @ ridge_fit(lagged, rs.y, smoothness, rules.node_ridge)
    fits = {
        "preisach_24": richer,
        "generalised_pi": generalised_pi(rs, base.lag_s),
        "bouc_wen": bouc_wen(rs, base.lag_s),
    }
    return [NullClass(k, v, float(np.sqrt(np.mean((rs.y - v) ** 2)))) for k, v in fits.items()]


def unrestricted_residual(rs: RunSet, base: Baseline, groups: dict[str, Matrix]) -> NDArray[np.float64]:
    """y minus its least-squares fit on the baseline's nuisance and every cause group [units of y]."""
    design = np.hstack([base.nuisance, *groups.values()])
    coef = np.linalg.lstsq(design, rs.y, rcond=1e-10)[0]
    return np.asarray(rs.y - design @ coef)


def simulated_records(
    rs: RunSet,
    fit: NDArray[np.float64],
    residual: NDArray[np.float64],
    count: int,
    rules: Rules,
    rng: np.random.Generator,
) -> Matrix:
    """``count`` records (n x count): ``fit`` plus ``residual`` whitened, block-resampled and
    re-coloured per run."""
    from host.diagnose.conditional import block_length, stationary_draws

    ar = ar_whitener(residual, rules.max_ar_order)
    innovations = whiten(rs, residual, ar)
    innovations = innovations - innovations.mean()
    drawn = innovations[stationary_draws(innovations.size, block_length(innovations), count, rng)]
    if ar.size:
        for a, b in rs.bounds():
            drawn[a:b] = lfilter([1.0], np.r_[1.0, -ar], drawn[a:b], axis=0)
    return np.asarray(fit[:, None] + drawn)


def class_nuisance(rs: RunSet, base: Baseline, rules: Rules) -> Matrix:
    """The other effect-free classes as NUISANCE directions (``Rules.class_nuisance``): the
    generalised-PI plays, the best Bouc-Wen core's state and the richer-level Preisach fit, each
    through the baseline's output lag, with the cubic output map of the PI and Bouc-Wen fits and
    the lag tangent (a longer lag) of each class's fit. All are functions of the input's
    rate-independent history only, so a class difference is partialled out of every test while a
    timing, time or column effect keeps its own part (only its rate-independent projection, which
    no record can attribute, is absorbed)."""
    lag = base.lag_s
    plays = pi_plays(rs)
    bw_core, bw_fit = bouc_wen_core(rs, lag)
    pi_fit = _cubic_map(rs, plays, lag)
    nodes, smoothness, _ = preisach_basis(rs, rules.richer_levels, rules.preisach_pad_levels)
    lagged = np.column_stack([run_lowpass(rs, nodes, lag), np.ones(rs.y.size)])
    richer = lagged @ ridge_fit(lagged, rs.y, smoothness, rules.node_ridge)
    columns = [run_lowpass(rs, plays, lag), run_lowpass(rs, bw_core, lag)]
    longer = 0.5 * lag + rs.dt
    for fit in (pi_fit, bw_fit, richer):
        h = (fit - fit.mean()) / (np.std(fit) or 1.0)
        columns.append(np.column_stack([fit, h**2, h**3, run_lowpass(rs, fit, longer) - fit]))
    return np.hstack(columns)
