"""The actuator before the hysteresis: what drives the muscle is the recorded input through a lag.

A pneumatic muscle's pressure follows the recorded command through the valve and the chamber (a
first-order lag), or the recorded pressure is read through a snubber or filter of its own so that
the muscle leads it (the inverse of a lag). Either acts *before* the hysteresis, where an output
lag cannot stand in for it: a lag before a hysteresis widens the loop with the input's speed,
which the rate group would otherwise take for its own. The lag is part of the rig, not an effect:
it is chosen per record from :attr:`host.diagnose.rules.Rules.input_lags_s` (0 among them) by
the least squares of the baseline *and every cause's group* (chosen under the alternative, so an
effect pulls it less than it would pull a choice on the baseline alone), before any cause is
tested, and everything after works on the actuator's output. Inverse lags are not in the default
grid (see the rules' comment).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
from numpy.typing import NDArray

from host.diagnose.features import actuator_input
from host.diagnose.groups import cause_groups
from host.diagnose.nuisance import PROFILE_ROWS, fit_baseline, ridge_fit
from host.diagnose.rules import Rules
from host.diagnose.runs import RunSet, preisach_basis


def usable_lags(rs: RunSet, rules: Rules) -> list[float]:
    """The lags of ``rules.input_lags_s`` [s] this sampling can show (at least half a sample either
    way, as the output lags); 0 always."""
    return sorted({0.0, *(lag for lag in rules.input_lags_s if abs(lag) >= 0.5 * rs.dt)})


def _per_run(rs: RunSet, through: Callable[[NDArray[np.float64]], NDArray[np.float64]], lag_s: float) -> RunSet:
    """``rs`` with each run's input passed through ``through`` from its own first sample, recorded
    as the actuator lag ``lag_s`` [s]."""
    u = np.empty_like(rs.u)
    for a, b in rs.bounds():
        u[a:b] = through(rs.u[a:b])
    return replace(rs, u=u, input_lag_s=lag_s)


def driven(rs: RunSet, lag_s: float) -> RunSet:
    """``rs`` with its input through the actuator lag ``lag_s`` [s] (negative: the inverse of a lag),
    each run from its own first sample."""
    if lag_s == 0:
        return rs
    return _per_run(rs, lambda u: actuator_input(u, rs.dt, lag_s), lag_s)


def unrestricted_error(rs: RunSet, rules: Rules) -> float:
    """Sum of squared errors [units of y squared] of the baseline M0 fitted on ``rs`` together
    with every cause's group: the actuator is chosen under the alternative, so an effect the
    baseline lacks pulls the lag less than a choice on M0 alone (which chose 0.1 s on synthetic
    creep campaigns where no lag acts); it can still move it."""
    nodes, smoothness, _ = preisach_basis(rs, rules.preisach_levels, rules.preisach_pad_levels)
    base = fit_baseline(rs, nodes, smoothness, rules.output_lags_s, rules.node_ridge, rules.nuisance_lags_s)
    groups = cause_groups(rs, base, rules)
    rows = slice(None, None, -(-rs.y.size // PROFILE_ROWS))  # the choice, not the fit: every k-th row
    design = np.hstack([base.nuisance, *groups.values()])[rows]
    widths = [g.shape[1] for g in groups.values()]
    fitted = design @ ridge_fit(design, rs.y[rows], base.smoothness, rules.node_ridge, widths)
    return float(np.sum((rs.y[rows] - fitted) ** 2))


def fill_vent_lagged(u: NDArray[np.float64], dt: float, fill_s: float, vent_s: float) -> NDArray[np.float64]:
    """``u`` through a first-order lag of ``fill_s`` >= 0 [s] while the output rises towards it and
    ``vent_s`` >= 0 while it falls (a valve that fills and exhausts through different paths),
    starting settled at the first sample (0: that direction follows at once)."""
    a_fill = 1.0 - np.exp(-dt / fill_s) if fill_s > 0 else 1.0
    a_vent = 1.0 - np.exp(-dt / vent_s) if vent_s > 0 else 1.0
    out = np.empty_like(u)
    p = float(u[0])
    for i, v in enumerate(u.tolist()):
        p += (a_fill if v > p else a_vent) * (v - p)
        out[i] = p
    return out


def driven_asymmetric(rs: RunSet, fill_s: float, vent_s: float) -> RunSet:
    """``rs`` with its input through :func:`fill_vent_lagged`, each run from its own first sample
    (``input_lag_s`` holds the fill lag; the note names both)."""
    return _per_run(rs, lambda u: fill_vent_lagged(u, rs.dt, fill_s, vent_s), fill_s)


def with_actuator(rs: RunSet, rules: Rules) -> RunSet:
    """``rs`` driven through the actuator lag whose baseline fits best (:func:`driven`), with a note
    when it is not 0; with ``rules.asymmetric_actuator`` a pair of fill and vent lags
    (:func:`driven_asymmetric`) with one of them at that lag, when a pair fits better still."""
    lags = usable_lags(rs, rules)
    if len(lags) == 1:
        return rs
    # every choice is a (fill, vent) pair; the symmetric ones first, so a pair must fit strictly better
    errors = {(lag, lag): unrestricted_error(driven(rs, lag), rules) for lag in lags}
    best = min(errors, key=errors.__getitem__)[0]
    if rules.asymmetric_actuator and best >= 0:  # an inverse lag (a snubbed reading) has no fill or vent
        positive = [lag for lag in lags if lag >= 0]
        pairs = sorted({(best, v) for v in positive if v != best} | {(f, best) for f in positive if f != best})
        errors.update({pair: unrestricted_error(driven_asymmetric(rs, *pair), rules) for pair in pairs})
    fill, vent = min(errors, key=errors.__getitem__)
    if fill == vent == 0:
        return rs
    out = driven(rs, fill) if fill == vent else driven_asymmetric(rs, fill, vent)
    return replace(out, notes=[*out.notes, _note(fill, vent, len(lags))])


def _note(fill_s: float, vent_s: float, tried: int) -> str:
    """What the record's notes say of the chosen actuator (lags [s]; ``tried``: symmetric lags tried)."""
    if fill_s != vent_s:
        return (
            f"the hysteresis is driven by the input through a lag of {fill_s * 1000:.0f} ms while it fills and "
            f"{vent_s * 1000:.0f} ms while it vents (the actuator, chosen by least squares with every cause's terms)"
        )
    kind = "a lag of" if fill_s > 0 else "the inverse of a lag of"
    return (
        f"the hysteresis is driven by the input through {kind} {abs(fill_s) * 1000:.0f} ms (the actuator, chosen "
        f"by least squares with every cause's terms from {tried} lags, 0 among them); the causes are tested "
        "beyond it"
    )
