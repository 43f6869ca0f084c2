"""Honest held-out comparison of the baseline and its extension by one cause group.

Folds are contiguous blocks of the campaign clock (long records) or whole runs (short runs), so
no held-out row's neighbours train its model. Per fold both models (the nuisance alone, and the
nuisance plus the cause's group) are fitted by ridge least squares on the other folds' rows and
predict the held-out rows from the input alone (output-error: the regressors never use measured
``y``). Reported: the pooled held-out RMS of each, the gain in ``y``'s units and as a fraction
with a 90 % block-bootstrap interval, and the Clark-West test of the nested improvement (HAC,
one-sided).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.stats import norm

from host.diagnose.nuisance import kept_rows, ridge_fit, whiten
from host.diagnose.rules import Rules
from host.diagnose.runs import RunSet


def holdout_folds(rs: RunSet, rules: Rules) -> tuple[list[NDArray[np.bool_]], str]:
    """Held-out masks and a sentence saying what they are; the number of folds adapts to the data."""
    lengths = [b - a for a, b in rs.bounds()]
    n = rs.y.size
    if rs.n_runs >= 3 and float(np.median(lengths)) < rules.short_run_samples:
        k = min(rules.max_folds, rs.n_runs)
        masks = [np.isin(rs.run, np.arange(i, rs.n_runs, k)) for i in range(k)]
        return (
            masks,
            f"{k} folds of whole runs ({rs.n_runs} runs dealt in turn), each predicted by a model fitted on the others",
        )
    k = int(max(2, min(rules.max_folds, n // rules.min_fold_samples)))
    edges = np.linspace(0, n, k + 1).astype(int)
    masks = []
    for i in range(k):
        held = np.zeros(n, dtype=bool)
        held[edges[i] : edges[i + 1]] = True
        masks.append(held)
    span = n * rs.dt / k
    return masks, f"{k} contiguous blocks of about {span:.3g} s, each predicted by a model fitted on the others"


def cluster_labels(rs: RunSet, rules: Rules) -> NDArray[np.int64] | None:
    """What the held-out statistics treat as independent units when ``rules.heldout_clusters``: the
    runs when the folds leave whole runs out, else contiguous blocks of a twentieth of the record
    (None: Newey-West per row and moving blocks, as before)."""
    if not rules.heldout_clusters:
        return None
    lengths = [b - a for a, b in rs.bounds()]
    if rs.n_runs >= 3 and float(np.median(lengths)) < rules.short_run_samples:
        return np.asarray(rs.run, dtype=np.int64)
    n = rs.y.size
    return np.minimum(np.arange(n) * 20 // max(n, 1), 19).astype(np.int64)


def scoring_name(clustered: bool, whitened: bool) -> str:
    """The name of one held-out scoring (``clusters`` or ``rows``, ``white`` or ``raw``), as the
    dumps of ``bench/diagnose_v3_dump.py`` key their trials."""
    return f"{'clusters' if clustered else 'rows'}/{'white' if whitened else 'raw'}"


# the fewest held-out rows a comparison scores before it falls back to every row
MIN_SCORED_ROWS = 10


@dataclass
class HeldOut:
    base_rmse: float  # [units of y]
    ext_rmse: float
    gain: float  # 1 - ext/base (fraction)
    gain_units: float  # base - ext [units of y]
    interval: tuple[float, float]  # 90 % block-bootstrap interval of ``gain``
    clark_west_t: float
    clark_west_p: float
    fold_gains: list[float]
    base_prediction: NDArray[np.float64]  # held-out predictions, every row held out once
    ext_prediction: NDArray[np.float64]
    scored: NDArray[np.bool_] | None = None  # the rows the scores use

    def as_json(self) -> dict[str, object]:
        return {
            "baseline_rmse": round(self.base_rmse, 6),
            "extended_rmse": round(self.ext_rmse, 6),
            "gain": round(self.gain, 4),
            "gain_units": round(self.gain_units, 6),
            "interval_90": [round(self.interval[0], 4), round(self.interval[1], 4)],
            "clark_west_t": round(self.clark_west_t, 3),
            "clark_west_p": round(self.clark_west_p, 6),
            "fold_gains": [round(g, 4) for g in self.fold_gains],
        }


def held_out(
    rs: RunSet,
    nuisance: NDArray[np.float64],
    smoothness: NDArray[np.float64],
    group: NDArray[np.float64],
    masks: list[NDArray[np.bool_]],
    ridge: float,
    rng: np.random.Generator,
    column: NDArray[np.float64] | None = None,
    clusters: NDArray[np.int64] | None = None,
    whitener: NDArray[np.float64] | None = None,
    penalised_tail: Sequence[int] = (),
) -> HeldOut:
    """Both models per fold (see module docstring). The last columns of ``nuisance``, in blocks of
    the widths ``penalised_tail`` (causes already named, tested beyond), carry the same ridge in
    both fits, each block scaled by itself as ``group`` is. With a measured ``column``, a fold scores only
    the held-out rows whose column value lies inside its training rows' range: a column term is
    not asked to extrapolate to loads or temperatures it never saw (such rows are left out of
    every score, the baseline's included). With ``clusters`` (a label per row,
    :func:`cluster_labels`) the Clark-West standard error and the gain's interval treat each
    cluster as one independent unit (cluster-robust; a run's errors are correlated as a whole).
    With ``whitener`` (AR coefficients of the noise model, :func:`host.diagnose.nuisance.ar_whitener`)
    the Clark-West test and the interval score the held-out errors after the AR filter (the
    innovations), so slow excursions of a structural misfit do not decide them; the reported RMS and
    gain stay those of the raw errors [units of y]."""
    y = rs.y
    base = np.empty_like(y)
    ext = np.empty_like(y)
    extended = np.hstack([nuisance, group])
    fold_gains = []
    for held in masks:
        train = ~held
        base[held] = nuisance[held] @ ridge_fit(nuisance[train], y[train], smoothness, ridge, penalised_tail)
        ext[held] = extended[held] @ ridge_fit(
            extended[train], y[train], smoothness, ridge, [*penalised_tail, group.shape[1]]
        )
        rows = fold_rows(held, column)
        if not rows.any():
            fold_gains.append(float("nan"))
            continue
        b = float(np.sqrt(np.mean((base[rows] - y[rows]) ** 2)))
        fold_gains.append(1.0 - float(np.sqrt(np.mean((ext[rows] - y[rows]) ** 2))) / (b or 1.0))
    scored = scored_rows(masks, column)
    eb, ee = (base[scored] - y[scored]) ** 2, (ext[scored] - y[scored]) ** 2
    base_rmse, ext_rmse = float(np.sqrt(eb.mean())), float(np.sqrt(ee.mean()))
    t_cw, interval = held_out_statistics(rs, base, ext, scored, rng, clusters, whitener)
    return HeldOut(
        base_rmse,
        ext_rmse,
        1.0 - ext_rmse / (base_rmse or 1.0),
        base_rmse - ext_rmse,
        interval,
        t_cw,
        float(norm.sf(t_cw)),
        fold_gains,
        base,
        ext,
        scored,
    )


def fold_rows(held: NDArray[np.bool_], column: NDArray[np.float64] | None) -> NDArray[np.bool_]:
    """The held-out rows one fold scores: all of them, or with a measured ``column`` those whose
    value lies inside the training rows' range (a column term is not asked to extrapolate)."""
    if column is None:
        return held.copy()
    train = column[~held]
    return np.asarray(held & (column >= train.min()) & (column <= train.max()), dtype=bool)


def scored_rows(masks: list[NDArray[np.bool_]], column: NDArray[np.float64] | None) -> NDArray[np.bool_]:
    """Every fold's :func:`fold_rows`; every row when fewer than :data:`MIN_SCORED_ROWS` are left
    (nothing inside the training ranges: score every row rather than none)."""
    scored = np.zeros(masks[0].size, dtype=bool)
    for held in masks:
        scored |= fold_rows(held, column)
    if scored.sum() < MIN_SCORED_ROWS:
        scored[:] = True
    return scored


def held_out_statistics(
    rs: RunSet,
    base: NDArray[np.float64],
    ext: NDArray[np.float64],
    scored: NDArray[np.bool_],
    rng: np.random.Generator,
    clusters: NDArray[np.int64] | None = None,
    whitener: NDArray[np.float64] | None = None,
) -> tuple[float, tuple[float, float]]:
    """(Clark-West t, 90 % interval of the gain) of the held-out predictions ``base`` and ``ext``
    on the ``scored`` rows; ``clusters`` and ``whitener`` as in :func:`held_out`."""
    rb, re = base - rs.y, ext - rs.y
    if whitener is not None and whitener.size:
        rb, re = whiten(rs, rb, whitener), whiten(rs, re, whitener)
        scored = scored & kept_rows(rs, whitener.size)
    eb, ee = rb[scored] ** 2, re[scored] ** 2
    cw = eb - ee + (rb[scored] - re[scored]) ** 2
    labels = None if clusters is None else np.unique(clusters[scored], return_inverse=True)[1]
    if labels is not None and labels.max() >= 4:
        return float(cw.mean() / _cluster_se(cw, labels)), _cluster_interval(eb, ee, labels, rng)
    return float(cw.mean() / _hac_se(cw)), _interval(eb, ee, rng)


def _hac_se(f: NDArray[np.float64]) -> float:
    """Newey-West standard error of the mean of ``f`` (Bartlett kernel, n^(1/3) lags)."""
    n = f.size
    d = f - f.mean()
    lags = int(np.ceil(n ** (1 / 3)))
    var = float(d @ d) / n
    for k in range(1, lags + 1):
        var += 2 * (1 - k / (lags + 1)) * float(d[k:] @ d[:-k]) / n
    return float(np.sqrt(max(var, 1e-300) / n))


def _interval(eb: NDArray[np.float64], ee: NDArray[np.float64], rng: np.random.Generator) -> tuple[float, float]:
    """90 % moving-block bootstrap interval of ``1 - sqrt(mean ee / mean eb)`` (blocks of n/20)."""
    n = eb.size
    size = max(1, n // 20)
    starts = rng.integers(0, max(1, n - size), (400, int(np.ceil(n / size))))
    idx = (starts[:, :, None] + np.arange(size)).reshape(400, -1)[:, :n]
    gains = 1.0 - np.sqrt(ee[idx].mean(axis=1) / np.maximum(eb[idx].mean(axis=1), 1e-300))
    lo, hi = np.percentile(gains, [5, 95])
    return float(lo), float(hi)


def _cluster_se(f: NDArray[np.float64], labels: NDArray[np.intp]) -> float:
    """Cluster-robust standard error of the mean of ``f`` (one independent unit per label, with the
    small-sample factor C / (C - 1))."""
    sums = np.bincount(labels, weights=f - f.mean())
    c = sums.size
    return float(np.sqrt(max(float(sums @ sums) * c / (c - 1), 1e-300)) / f.size)


def _cluster_interval(
    eb: NDArray[np.float64], ee: NDArray[np.float64], labels: NDArray[np.intp], rng: np.random.Generator
) -> tuple[float, float]:
    """90 % cluster-bootstrap interval of ``1 - sqrt(sum ee / sum eb)`` (clusters drawn with replacement)."""
    sb, se = np.bincount(labels, weights=eb), np.bincount(labels, weights=ee)
    draws = rng.integers(0, sb.size, (400, sb.size))
    gains = 1.0 - np.sqrt(se[draws].sum(axis=1) / np.maximum(sb[draws].sum(axis=1), 1e-300))
    lo, hi = np.percentile(gains, [5, 95])
    return float(lo), float(hi)
