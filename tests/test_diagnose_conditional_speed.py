"""The fast paths of the conditional tests give what the plain definitions give: the vectorised
stationary bootstrap draws the same indices as its row-by-row recursion, the QR statistic equals the
projection on an explicit orthonormal basis, and the batched Gram-matrix surrogates reach the same
p-values as partialling out and orthonormalising every copy (including copies that fall back)."""

from __future__ import annotations

import numpy as np
import pytest

from host.diagnose.conditional import (
    Whitened,
    _stat,
    _surrogates,
    column_copies,
    orthonormal,
    partial_out,
    projected_stat,
    stationary_draws,
)
from host.diagnose.nuisance import kept_rows, whiten
from host.diagnose.rules import RULES
from host.diagnose.runs import RunSet


def draws_by_rows(n: int, mean_block: float, draws: int, rng: np.random.Generator) -> np.ndarray:
    """The stationary bootstrap's definition, one row after the other."""
    idx = np.empty((n, draws), dtype=np.intp)
    idx[0] = rng.integers(0, n, draws)
    fresh = rng.random((n, draws)) < 1.0 / mean_block
    starts = rng.integers(0, n, (n, draws))
    for i in range(1, n):
        idx[i] = np.where(fresh[i], starts[i], (idx[i - 1] + 1) % n)
    return idx


@pytest.mark.parametrize(("n", "block", "draws"), [(1, 1.0, 3), (7, 1.0, 5), (300, 12.5, 40), (2000, 80.0, 9)])
def test_stationary_draws_follow_the_recursion(n: int, block: float, draws: int) -> None:
    fast = stationary_draws(n, block, draws, np.random.default_rng(n))
    assert np.array_equal(fast, draws_by_rows(n, block, draws, np.random.default_rng(n)))
    assert fast.dtype == np.intp and fast.shape == (n, draws)


def test_projected_stat_drops_the_directions_orthonormal_drops() -> None:
    rng = np.random.default_rng(0)
    e = rng.normal(size=500)
    m = rng.normal(size=(500, 4))
    for columns in (m, np.column_stack([m, m[:, 0] - 2 * m[:, 1]]), np.zeros((500, 2)), m[:, :0]):
        explicit = float(_stat(orthonormal(columns), e[:, None], 1.0)[0]) if columns.shape[1] else 0.0
        assert projected_stat(columns, e) == pytest.approx(explicit, rel=1e-10, abs=1e-12)


def two_runs_with_temperature(seed: int) -> tuple[Whitened, np.ndarray]:
    rng = np.random.default_rng(seed)
    n_run = 400
    run = np.repeat([0, 1, 2], n_run)
    t = np.tile(np.arange(n_run) * 0.02, 3)
    u = np.sin(2 * np.pi * 0.3 * t + run) + 0.1 * rng.normal(size=run.size)
    y = np.tanh(u) + 0.05 * rng.normal(size=run.size)
    temperature = 25 + np.cumsum(rng.normal(size=run.size)) * 0.05
    rs = RunSet(t, np.arange(run.size) * 0.02, u, y, run, 0.02, ["a", "b", "c"], {"temperature": temperature})
    ar = np.array([0.4])
    keep = kept_rows(rs, ar.size)
    nuisance = np.column_stack([np.ones_like(u), u, u**2, np.tanh(u), (run == 1).astype(float)])
    q = orthonormal(whiten(rs, nuisance, ar)[keep])
    residual = partial_out(q, whiten(rs, y, ar)[keep][:, None])[:, 0]
    return Whitened(rs, ar, keep, q, residual, 1.0), nuisance


def per_copy_p(w: Whitened, q_others, t_u, t_m, sigma2, build, rng) -> tuple[float, float]:
    """The surrogate p-values by partialling out and orthonormalising every copy on its own."""
    e = w.residual[:, None]
    copies, _ = column_copies(w.rs, w.rs.columns["temperature"], RULES.column_surrogates, rng)
    hits_u = hits_m = 0
    for copy in copies:
        partialled = w.prepare(build("temperature_drift", copy))
        hits_m += float(_stat(orthonormal(partialled), e, sigma2)[0]) >= t_m
        hits_u += float(_stat(orthonormal(partial_out(q_others, partialled)), e, sigma2)[0]) >= t_u
    return (1 + hits_u) / (len(copies) + 1), (1 + hits_m) / (len(copies) + 1)


@pytest.mark.parametrize("degenerate", [False, True])
def test_batched_surrogates_reach_the_per_copy_p_values(degenerate: bool) -> None:
    w, nuisance = two_runs_with_temperature(1)
    u = w.rs.u

    def build(cause: str, copy: np.ndarray) -> np.ndarray:
        c = (copy - copy.mean()) / (copy.std() or 1.0)
        columns = [c, c**2 - np.mean(c**2), c * u]
        if degenerate:  # a copy nearly inside the nuisance: its Gram matrix cannot be trusted
            columns.append(nuisance[:, 3] + 1e-7 * c)
        return np.column_stack(columns)

    others = orthonormal(w.prepare(np.column_stack([np.sin(3 * u), np.cos(2 * u) * w.rs.t])))
    observed = w.prepare(build("temperature_drift", w.rs.columns["temperature"]))
    e = w.residual[:, None]
    sigma2 = float(e[:, 0] @ e[:, 0]) / e.shape[0]
    for quantile in (0.3, 0.7):  # observed statistics that some copies beat and others do not
        t_m = float(_stat(orthonormal(observed), e, sigma2)[0]) * quantile * 2
        t_u = float(_stat(orthonormal(partial_out(others, observed)), e, sigma2)[0]) * quantile * 2
        fast = _surrogates(w, "temperature_drift", others, t_u, t_m, sigma2, build, RULES, np.random.default_rng(5))
        plain = per_copy_p(w, others, t_u, t_m, sigma2, build, np.random.default_rng(5))
        assert (fast[0], fast[1]) == plain
        assert "surrogate columns" in fast[2]
