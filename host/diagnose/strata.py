"""Rate-independent state strata and the conditional permutation test (CPT) they allow.

Under "no effect" the baseline's structural error, whatever its form, is rate independent: a
function of the hysteresis state (the input, the direction of its last move and where it last
turned), not of the speed, the time since a move or the clock. So the residual is exchangeable
between samples of the same state, and a cause's regressors permuted among such samples give
the null distribution of its statistic *with the structural error included* (Berrett, Wang,
Barber & Samworth, JRSS-B 82:175, 2020: the error is bounded by how well the strata capture
the state). A record whose speed never varies within a state has no power here, by design.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from host.diagnose.runs import RunSet


def state_strata(rs: RunSet, input_bins: int, turn_bins: int, reversal_share: float = 0.02) -> NDArray[np.int64]:
    """A stratum label per sample: the input's quantile bin, the direction of its last move and
    the quantile bin of the input where it last turned (a reversal larger than ``reversal_share``
    of the range, so noise does not turn it); restarted at each run."""
    u = rs.u
    threshold = reversal_share * float(np.ptp(u))
    direction = np.zeros(u.size, dtype=np.int64)
    turned = np.zeros(u.size)
    for a, b in rs.bounds():
        going, turn, extreme = 1, float(u[a]), float(u[a])
        for i in range(a, b):
            v = float(u[i])
            if going > 0:
                if v > extreme:
                    extreme = v
                elif extreme - v > threshold:
                    going, turn, extreme = -1, extreme, v
            else:
                if v < extreme:
                    extreme = v
                elif v - extreme > threshold:
                    going, turn, extreme = 1, extreme, v
            direction[i] = going
            turned[i] = turn
    u_bin = _quantile_bins(u, input_bins)
    turn_bin = _quantile_bins(turned, turn_bins)
    return (u_bin * 2 + (direction > 0)) * turn_bins + turn_bin


def _quantile_bins(v: NDArray[np.float64], bins: int) -> NDArray[np.int64]:
    edges = np.unique(np.quantile(v, np.linspace(0, 1, bins + 1)[1:-1]))
    return np.searchsorted(edges, v, side="right").astype(np.int64)


def within_strata_permutations(strata: NDArray[np.int64], draws: int, rng: np.random.Generator) -> NDArray[np.intp]:
    """``draws`` index permutations (draws x n), each shuffling samples only within their stratum."""
    order = np.argsort(strata, kind="stable")
    sorted_strata = strata[order]
    starts = np.flatnonzero(np.r_[True, sorted_strata[1:] != sorted_strata[:-1]])
    stops = np.r_[starts[1:], strata.size]
    out = np.empty((draws, strata.size), dtype=np.intp)
    for d in range(draws):
        perm = np.empty(strata.size, dtype=np.intp)
        for a, b in zip(starts, stops):
            members = order[a:b]
            perm[members] = rng.permutation(members)
        out[d] = perm
    return out
