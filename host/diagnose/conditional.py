"""Conditional group tests on whitened data, calibrated per record.

For each cause group ``g`` (:mod:`host.diagnose.groups`), in the AR-whitened regression of the
output on [baseline nuisance, every group]:

* *marginal*: the Wald statistic of ``g`` conditional on the nuisance only;
* *unique*: conditional on the nuisance and every other group (Frisch-Waugh-Lovell: ``g``'s
  columns are partialled out against the others, then projected on the residual).

The statistics are calibrated by a stationary block bootstrap of the whitened null residual
(Politis-Romano; block length by Politis-White, :func:`arch.bootstrap.optimal_block_length`),
family-wise over the dynamic groups by single-step max-T (Westfall-Young) on chi-square
standardised statistics; a measured column's statistics against surrogate copies of the column
(circular shifts and mirrors, or its per-run values permuted across runs), since a slow or
input-locked structural error is what a column can fit by chance.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2, ncx2

from host.diagnose.nuisance import Baseline, ar_whitener, kept_rows, whiten
from host.diagnose.rules import CAUSES, Rules
from host.diagnose.runs import RunSet
from host.diagnose.strata import state_strata, within_strata_permutations

Matrix = NDArray[np.float64]

# surrogate regressors whitened and partialled out together: at most this many float64 values
# (n x columns x copies) per batch, 16 MB (a few temporaries of that size live at once)
SURROGATE_BATCH_VALUES = 2_000_000
# a surrogate's Gram matrix is trusted when every eigenvalue is above this share of its largest
# before partialling: the statistic is then within ~1e-8 (relative) of the exact projection
GRAM_TRUST = 1e-8


def orthonormal(m: Matrix, tol: float = 1e-8) -> Matrix:
    """An orthonormal basis of ``m``'s column space (directions below ``tol`` x the largest dropped)."""
    if m.shape[1] == 0:
        return m
    u, s, _ = np.linalg.svd(m, full_matrices=False)
    return np.asarray(u[:, s > tol * (s[0] if s.size else 0.0)])


def partial_out(q: Matrix, m: Matrix) -> Matrix:
    """``m`` minus its projection on the orthonormal columns ``q``."""
    return m - q @ (q.T @ m) if q.shape[1] else m


@dataclass
class GroupTest:
    """One cause group's evidence on one record."""

    name: str
    df: int  # directions of the group left after the nuisance and the other groups
    unique_stat: float
    unique_p: float  # family-wise adjusted (dynamic groups) or surrogate (columns)
    marginal_stat: float
    marginal_p: float
    unique_share: float  # share of the whitened residual's variance the group explains on its own
    identifiable: float  # share of the group's norm left after partialling out the nuisance
    mde: float  # minimal detectable RMS of the effect's own part [units of y], 80 % power at its level
    level: float  # the significance level this cause is tested at (alpha split over the causes)
    null: str  # which null calibrated it
    # unique and marginal p under each null separately (the p above combines them), for replays
    p_by_null: dict[str, tuple[float, float]] = field(default_factory=dict)

    def as_json(self) -> dict[str, object]:
        out: dict[str, object] = {k: (round(v, 6) if isinstance(v, float) else v) for k, v in self.__dict__.items()}
        out["p_by_null"] = {k: [round(a, 6), round(b, 6)] for k, (a, b) in self.p_by_null.items()}
        return out


@dataclass
class Whitened:
    """The whitened regression shared by every test of one record."""

    rs: RunSet
    ar: NDArray[np.float64]
    keep: NDArray[np.bool_]
    q_nuisance: Matrix
    residual: Matrix  # whitened output after the nuisance (the null residual), 1-D
    to_units: float  # RMS of the raw null residual / RMS of the whitened one

    def prepare(self, columns: Matrix) -> Matrix:
        """Columns whitened, kept, and partialled out against the nuisance."""
        return partial_out(self.q_nuisance, whiten(self.rs, columns, self.ar)[self.keep])


def whitened(rs: RunSet, base: Baseline, rules: Rules) -> Whitened:
    raw = rs.y - base.prediction
    ar = ar_whitener(raw, rules.max_ar_order)
    keep = kept_rows(rs, ar.size)
    q = orthonormal(whiten(rs, base.nuisance, ar)[keep])
    residual = partial_out(q, whiten(rs, rs.y, ar)[keep][:, None])[:, 0]
    scale = float(np.sqrt(np.mean(raw**2)) / (np.sqrt(np.mean(residual**2)) or 1.0))
    return Whitened(rs, ar, keep, q, residual, scale)


def block_length(residual: NDArray[np.float64]) -> float:
    """Mean block length of the stationary bootstrap (Politis-White with Patton's correction)."""
    from arch.bootstrap import optimal_block_length

    length = float(optimal_block_length(residual)["stationary"].iloc[0])
    return float(np.clip(length if np.isfinite(length) else 1.0, 1.0, residual.size / 10))


def stationary_draws(n: int, mean_block: float, draws: int, rng: np.random.Generator) -> NDArray[np.intp]:
    """Indices of ``draws`` stationary-bootstrap resamples (n x draws): geometric blocks, wrapped.

    Row ``i`` continues the block of the last fresh start at or before ``i`` (row 0 starts one):
    ``idx[i] = (start[j] + i - j) mod n`` with ``j`` that row, found by a running maximum."""
    first = rng.integers(0, n, draws)
    fresh = rng.random((n, draws)) < 1.0 / mean_block
    starts = rng.integers(0, n, (n, draws))
    fresh[0] = True
    starts[0] = first
    rows = np.arange(n, dtype=np.intp)[:, None]
    last = np.where(fresh, rows, 0).astype(np.intp, copy=False)
    np.maximum.accumulate(last, axis=0, out=last)
    idx = np.take_along_axis(starts, last, axis=0).astype(np.intp, copy=False)
    idx += rows  # in place: three n x draws arrays at most, as the row recursion held
    idx -= last
    idx %= n
    return idx


def _stat(basis: Matrix, e: Matrix, sigma2: NDArray[np.float64] | float) -> NDArray[np.float64]:
    return np.asarray(np.sum((basis.T @ e) ** 2, axis=0) / sigma2)


def _z(stat: NDArray[np.float64] | float, df: int) -> NDArray[np.float64]:
    """Chi-square standardised statistic: -log of its chi2 p (max-T over groups of unequal df)."""
    return np.asarray(-chi2.logsf(stat, max(df, 1)))


def mde(df: int, level: float, sigma2: float, n: int, to_units: float) -> float:
    """Smallest RMS of an effect's own part [units of y] its test finds with 80 % power."""
    if df < 1:
        return float("inf")
    critical = chi2.isf(level, df)
    lo, hi = 0.0, 1.0
    while ncx2.sf(critical, df, hi) < 0.8:
        hi *= 2
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if ncx2.sf(critical, df, mid) < 0.8 else (lo, mid)
    return float(np.sqrt(hi * sigma2 / n) * to_units)


def group_tests(
    w: Whitened,
    groups: dict[str, Matrix],
    rules: Rules,
    surrogate_group: Callable[[str, NDArray[np.float64]], Matrix],
    rng: np.random.Generator,
    null_records: dict[str, Matrix] | None = None,
) -> dict[str, GroupTest]:
    """Every group's marginal and unique tests (see module docstring). ``surrogate_group(cause,
    column_copy)`` builds a column cause's regressors from a surrogate copy of its column.
    ``null_records`` (class name -> n x draws simulated outputs, :mod:`host.diagnose.composite`)
    adds the composite structural null: a dynamic group's p is then at least its max-T p against
    the least favourable class."""
    names = list(groups)
    partialled = {g: w.prepare(groups[g]) for g in names}
    e = w.residual[:, None]
    n = e.shape[0]
    q_all = orthonormal(np.hstack([partialled[g] for g in names]))
    full = partial_out(q_all, e)
    dof = max(n - w.q_nuisance.shape[1] - q_all.shape[1], 1)
    sigma2 = float(full[:, 0] @ full[:, 0]) / dof
    marginal = {g: orthonormal(partialled[g]) for g in names}
    others = {g: orthonormal(np.hstack([partialled[h] for h in names if h != g] or [np.zeros((n, 0))])) for g in names}
    unique = {g: orthonormal(partial_out(others[g], partialled[g])) for g in names}
    t_m = {g: float(_stat(marginal[g], e, sigma2)[0]) for g in names}
    t_u = {g: float(_stat(unique[g], e, sigma2)[0]) for g in names}
    dynamic = [g for g in names if CAUSES[g].kind != "column"]
    columns = [g for g in names if CAUSES[g].kind == "column"]
    level_dynamic = rules.alpha * len(dynamic) / len(names)
    level_column = rules.alpha / len(names)
    by_null = _max_t(w, dynamic, marginal, unique, t_m, t_u, rules, rng)
    p_u = {g: max(p[0][g] for p in by_null.values()) for g in dynamic}
    p_m = {g: max(p[1][g] for p in by_null.values()) for g in dynamic}
    p_by = {g: {k: (p[0][g], p[1][g]) for k, p in by_null.items()} for g in dynamic}
    kinds = "block bootstrap" + (" and within-state permutations" if rules.within_state_null else "")
    nulls = {g: f"max-T over {len(dynamic)} groups: {kinds} ({rules.bootstrap_draws} each)" for g in dynamic}
    if null_records:
        n_sims = next(iter(null_records.values())).shape[1]
        for name, sims in null_records.items():
            c_u, c_m = _composite(w, sims, dynamic, marginal, unique, q_all, dof, t_m, t_u)
            for g in dynamic:
                p_by[g][f"composite:{name}"] = (c_u[g], c_m[g])
                if c_u[g] > p_u[g]:
                    nulls[g] = (
                        f"max-T over {len(dynamic)} groups against {n_sims} simulated effect-free "
                        f"records per class ({', '.join(null_records)}; least favourable: {name})"
                    )
                p_u[g], p_m[g] = max(p_u[g], c_u[g]), max(p_m[g], c_m[g])
    for g in columns:
        raw = float(chi2.sf(t_u[g], max(unique[g].shape[1], 1)))
        p_u[g], p_m[g] = (raw, float(chi2.sf(t_m[g], max(marginal[g].shape[1], 1))))
        nulls[g] = f"chi-square screen (p > {rules.surrogate_screen_p:g}: surrogates skipped)"
        if min(p_u[g], p_m[g]) <= rules.surrogate_screen_p:
            p_u[g], p_m[g], nulls[g] = _surrogates(w, g, others[g], t_u[g], t_m[g], sigma2, surrogate_group, rules, rng)
        p_by[g] = {"surrogates" if "surrogate columns" in nulls[g] else "chi-square": (p_u[g], p_m[g])}
    out = {}
    for g in names:
        level = level_dynamic if g in dynamic else level_column
        norm = float(np.sum(w.prepare(groups[g]) ** 2))
        whole = float(np.sum((whiten(w.rs, groups[g], w.ar)[w.keep] - groups[g][w.keep].mean(0)) ** 2)) or 1.0
        out[g] = GroupTest(
            g,
            int(unique[g].shape[1]),
            t_u[g],
            float(p_u[g]),
            t_m[g],
            float(p_m[g]),
            float(t_u[g] * sigma2 / float(e[:, 0] @ e[:, 0])),
            norm / whole,
            mde(int(unique[g].shape[1]), level, sigma2, n, w.to_units),
            level,
            nulls[g],
            p_by[g],
        )
    return out


def _max_t(
    w: Whitened,
    dynamic: list[str],
    marginal: dict[str, Matrix],
    unique: dict[str, Matrix],
    t_m: dict[str, float],
    t_u: dict[str, float],
    rules: Rules,
    rng: np.random.Generator,
) -> dict[str, tuple[dict[str, float], dict[str, float]]]:
    """Single-step max-T adjusted p-values of the dynamic groups, (unique, marginal), per null:
    the block bootstrap (noise as the null) and, when the rules ask for it, the within-state
    permutation (the rate-independent structural error as the null, :mod:`host.diagnose.strata`).
    The p a test uses is the larger."""
    e = w.residual
    n = e.size
    length = block_length(e)
    strata = state_strata(w.rs, rules.strata_input_bins, rules.strata_turn_bins)[w.keep]
    boot = _adjusted(
        lambda count: e[stationary_draws(n, length, count, rng)], dynamic, marginal, unique, t_m, t_u, rules
    )
    if not rules.within_state_null:
        return {"bootstrap": boot}
    perm = _adjusted(
        lambda count: e[within_strata_permutations(strata, count, rng).T], dynamic, marginal, unique, t_m, t_u, rules
    )
    return {"bootstrap": boot, "permutation": perm}


def _composite(
    w: Whitened,
    sims: Matrix,
    dynamic: list[str],
    marginal: dict[str, Matrix],
    unique: dict[str, Matrix],
    q_all: Matrix,
    dof: int,
    t_m: dict[str, float],
    t_u: dict[str, float],
) -> tuple[dict[str, float], dict[str, float]]:
    """Max-T adjusted p-values of the observed statistics against simulated records of one
    effect-free class, each scored with the observed record's design (whitener, nuisance, bases:
    fixed by the input), its own variance estimated after every group as for the observed one."""
    if not dynamic:
        return {}, {}
    e = partial_out(w.q_nuisance, whiten(w.rs, sims, w.ar)[w.keep])
    sigma2 = (np.sum(e**2, axis=0) - np.sum((q_all.T @ e) ** 2, axis=0)) / dof
    max_u = np.max([_z(_stat(unique[g], e, sigma2), unique[g].shape[1]) for g in dynamic], axis=0)
    max_m = np.max([_z(_stat(marginal[g], e, sigma2), marginal[g].shape[1]) for g in dynamic], axis=0)
    count = e.shape[1]

    def adjusted(maxima: NDArray[np.float64], stat: float, df: int) -> float:
        return float((1 + np.sum(maxima >= _z(stat, df))) / (count + 1))

    return (
        {g: adjusted(max_u, t_u[g], unique[g].shape[1]) for g in dynamic},
        {g: adjusted(max_m, t_m[g], marginal[g].shape[1]) for g in dynamic},
    )


def _adjusted(
    resample: Callable[[int], Matrix],
    dynamic: list[str],
    marginal: dict[str, Matrix],
    unique: dict[str, Matrix],
    t_m: dict[str, float],
    t_u: dict[str, float],
    rules: Rules,
) -> tuple[dict[str, float], dict[str, float]]:
    """Max-T adjusted p-values against residuals drawn by ``resample(count)`` (n x count)."""
    n = next(iter(marginal.values())).shape[0] if marginal else 1
    z_u = {g: [] for g in dynamic}  # type: dict[str, list[NDArray[np.float64]]]
    z_m = {g: [] for g in dynamic}  # type: dict[str, list[NDArray[np.float64]]]
    # every group's unique and marginal basis stacked: one product per chunk of draws
    bases = [unique[g] for g in dynamic] + [marginal[g] for g in dynamic]
    stacked = np.hstack(bases) if bases else np.zeros((n, 0))
    cuts = np.cumsum([b.shape[1] for b in bases], dtype=np.intp)[:-1]
    remaining = rules.bootstrap_draws
    while remaining > 0:
        chunk = min(remaining, max(1, 4_000_000 // n))
        draws = resample(chunk)
        sigma2 = np.einsum("ij,ij->j", draws, draws) / draws.shape[0]
        parts = np.split(stacked.T @ draws, cuts, axis=0)
        for i, g in enumerate(dynamic):
            z_u[g].append(_z(np.sum(parts[i] ** 2, axis=0) / sigma2, unique[g].shape[1]))
            z_m[g].append(_z(np.sum(parts[len(dynamic) + i] ** 2, axis=0) / sigma2, marginal[g].shape[1]))
        remaining -= chunk
    if not dynamic:
        return {}, {}
    max_u = np.max([np.concatenate(z_u[g]) for g in dynamic], axis=0)
    max_m = np.max([np.concatenate(z_m[g]) for g in dynamic], axis=0)
    draws_total = max_u.size

    def adjusted(maxima: NDArray[np.float64], stat: float, df: int) -> float:
        return float((1 + np.sum(maxima >= _z(stat, df))) / (draws_total + 1))

    p_u = {g: adjusted(max_u, t_u[g], unique[g].shape[1]) for g in dynamic}
    p_m = {g: adjusted(max_m, t_m[g], marginal[g].shape[1]) for g in dynamic}
    return p_u, p_m


def column_copies(
    rs: RunSet, values: NDArray[np.float64], count: int, rng: np.random.Generator
) -> tuple[list[NDArray[np.float64]], str]:
    """Surrogate copies of a measured column: its per-run values permuted across runs when it is
    constant within every run (one load per run) and there are at least 4 runs; otherwise windows
    of the series followed by its mirror image, starting 10-90 % of the way around that loop.

    The loop (series, then series reversed) is continuous at every join, so each copy keeps the
    column's smoothness and spectrum. A plain circular shift jumps where the series wraps: on a slow
    column the real series, which has no jump, then fits a smooth misfit in time better than every
    copy and a wandering decoy temperature was named (bench/diagnose_decoy.py: 4/48 decoys named
    on the real campaigns with plain shifts, 1/48 with reflected ones)."""
    bounds = rs.bounds()
    constant = all(np.ptp(values[a:b]) <= 1e-9 * (np.ptp(values) or 1.0) for a, b in bounds)
    out = []
    if constant and len(bounds) >= 4:
        levels = np.array([values[a] for a, _ in bounds])
        for _ in range(count):
            perm = rng.permutation(levels)
            out.append(np.concatenate([np.full(b - a, v) for (a, b), v in zip(bounds, perm)]))
        return out, "its per-run values permuted across runs"
    n = values.size
    loop = np.concatenate([values, values[::-1]])
    for _ in range(count):
        start = int(rng.integers(int(0.2 * n), max(int(1.8 * n), int(0.2 * n) + 1)))
        out.append(np.take(loop, np.arange(start, start + n), mode="wrap"))
    return out, "reflected circular shifts (as smooth as the column)"


def projected_stat(m: Matrix, e: NDArray[np.float64], tol: float = 1e-8) -> float:
    """``|orthonormal(m, tol).T @ e|^2`` without forming the n x k basis: the R factor of ``[m | e]``
    holds ``m = Q R`` and ``Q.T @ e`` in its last column, and ``R``'s SVD has ``m``'s singular values,
    so the same directions are dropped (the basis is ``Q @ U_R``)."""
    if m.shape[1] == 0:
        return 0.0
    r: Matrix = np.asarray(np.linalg.qr(np.column_stack([m, e]), mode="r"))
    k = m.shape[1]
    u, s, _ = np.linalg.svd(r[:k, :k])
    return float(np.sum((u[:, s > tol * s[0]].T @ r[:k, k]) ** 2))


def _surrogates(
    w: Whitened,
    g: str,
    q_others: Matrix,
    t_u: float,
    t_m: float,
    sigma2: float,
    surrogate_group: Callable[[str, NDArray[np.float64]], Matrix],
    rules: Rules,
    rng: np.random.Generator,
) -> tuple[float, float, str]:
    """Surrogate p-values (unique, marginal) of column cause ``g``.

    Every copy's statistic is ``b^T G^+ b`` with ``G`` its whitened regressors' Gram matrix after
    the nuisance (and the other groups) and ``b`` their product with the residual, both from one
    product of the nuisance's and the other groups' bases with a whole batch of copies: a quarter
    of the passes over those n x k bases that partialling out every copy needs. A copy whose Gram
    matrix is near singular (a direction below :data:`GRAM_TRUST` of its whole norm squared,
    where the subtraction loses digits) is scored exactly (:func:`projected_stat`)."""
    column = CAUSES[g].column
    assert column is not None
    e = w.residual
    others_e = q_others.T @ e  # the residual is orthogonal to the nuisance already
    hits_u = hits_m = 0
    copies, kind = column_copies(w.rs, w.rs.columns[column], rules.column_surrogates, rng)
    # regressors built batch by batch: all copies at once would hold copies x n x width values
    width = surrogate_group(g, copies[0]).shape[1] if copies else 1
    per_batch = max(1, SURROGATE_BATCH_VALUES // max(e.size * width, 1))
    for first in range(0, len(copies), per_batch):
        batch = [surrogate_group(g, copy) for copy in copies[first : first + per_batch]]
        widths = [b.shape[1] for b in batch]  # a copy may move within runs where the column does not
        stacked = np.hstack(batch)
        del batch
        x = whiten(w.rs, stacked, w.ar)[w.keep]
        del stacked
        # two products rather than one on the bases stacked: stacking copies an n x k matrix
        on_nuisance, on_others = w.q_nuisance.T @ x, q_others.T @ x
        x_e = x.T @ e
        for start, stop in zip(np.cumsum([0, *widths[:-1]]), np.cumsum(widths)):
            cols = slice(int(start), int(stop))
            gram = x[:, cols].T @ x[:, cols]
            scale = float(np.max(np.linalg.eigvalsh(gram))) if gram.size else 0.0
            p_n, p_o = on_nuisance[:, cols], on_others[:, cols]
            g_m = gram - p_n.T @ p_n
            b_m = x_e[cols]
            g_u = g_m - p_o.T @ p_o
            b_u = b_m - p_o.T @ others_e
            stat_m, stat_u = _gram_stat(g_m, b_m, scale), _gram_stat(g_u, b_u, scale)
            if stat_m is None or stat_u is None:
                alone = partial_out(w.q_nuisance, x[:, cols])
                stat_m = projected_stat(alone, e)
                stat_u = projected_stat(partial_out(q_others, alone), e)
            hits_m += stat_m / sigma2 >= t_m
            hits_u += stat_u / sigma2 >= t_u
    count = len(copies)
    return (1 + hits_u) / (count + 1), (1 + hits_m) / (count + 1), f"{count} surrogate columns ({kind})"


def _gram_stat(gram: Matrix, b: NDArray[np.float64], scale: float) -> float | None:
    """``b^T gram^-1 b``, or None when an eigenvalue of ``gram`` is below ``GRAM_TRUST x scale``
    (``scale``: the largest eigenvalue before partialling, so the cancellation is accounted for)."""
    if gram.size == 0:
        return 0.0
    values, vectors = np.linalg.eigh(gram)
    if scale <= 0.0 or values[0] <= GRAM_TRUST * scale:
        return None
    return float(np.sum((vectors.T @ b) ** 2 / values))
