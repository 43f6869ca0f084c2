"""A measured column's held-out gain against the held-out gains of surrogate copies of it.

The in-sample surrogate test (:func:`host.diagnose.conditional.group_tests`) asks whether the
column explains more of the whitened residual than copies of it do. A column term has a dozen
flexible columns (level, square, products with the output and branch, lags), so on a record whose
baseline misfits, a slow copy fits that misfit in-sample nearly as well as the real column, and
a real load or temperature effect is lost (measured on the plant families: held-out gains of
19-86 % with in-sample surrogate p of 0.2-0.6). Out of sample a copy cannot do that: fitted on
the other folds, a copy that is not aligned with the effect predicts the held-out fold no better
than the baseline, while the real column does.

So the test here is the held-out comparison of :func:`host.diagnose.heldout.held_out` repeated
for every copy (:func:`host.diagnose.conditional.column_copies`: runs permuted, or reflected
circular shifts), its statistic the held-out gain, and its p the rank of the real column's gain
among the copies'. Each copy meets the same structural misfit, so the misfit alone does not make
the real column win; the test is exact when the copies are exchangeable with the column (runs
permuted, one value per run). Reflected shifts of a slow column that trends are not (a copy
contains the trend reversed), and slow decoys are named more often than the level says (measured
in docs/methods/diagnosis.md), which is why ``Rules.column_heldout_surrogates`` is off. Every
copy's fit is assembled from per-fold Gram blocks: the nuisance's blocks are computed once, a
copy adds only its own columns' products.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from host.diagnose.heldout import scored_rows
from host.diagnose.nuisance import ridge_penalty

Matrix = NDArray[np.float64]


@dataclass
class HeldOutSurrogates:
    """The real column's held-out gain and where it ranks among its copies'."""

    gain: float  # the real column's held-out gain (fraction)
    p: float  # (1 + copies whose gain >= it) / (1 + copies)
    copies: int
    median_copy_gain: float
    kind: str  # how the copies were made

    def as_json(self) -> dict[str, object]:
        """The JSON of a verdict's ``heldout_surrogates`` entry (fractions, not percent)."""
        return {
            "gain": round(self.gain, 4),
            "p": round(self.p, 6),
            "copies": self.copies,
            "median_copy_gain": round(self.median_copy_gain, 4),
            "copies_made_by": self.kind,
        }


class _FoldBlocks:
    """The nuisance's per-fold Gram blocks, and held-out fits of nuisance + a group from them."""

    def __init__(
        self,
        nuisance: Matrix,
        y: NDArray[np.float64],
        masks: list[NDArray[np.bool_]],
        smoothness: Matrix,
        ridge: float,
    ) -> None:
        self.nuisance, self.y, self.masks = nuisance, y, masks
        self.smoothness, self.ridge = smoothness, ridge
        self.gram_nn = [nuisance[m].T @ nuisance[m] for m in masks]
        self.moment_n = [nuisance[m].T @ y[m] for m in masks]

    def predictions(self, group: Matrix) -> NDArray[np.float64]:
        """Held-out predictions of nuisance + ``group`` (every row predicted by the other folds),
        the same fit as :func:`host.diagnose.nuisance.ridge_fit` on the training rows."""
        p, q = self.nuisance.shape[1], group.shape[1]
        blocks = []
        for m, g_nn, b_n in zip(self.masks, self.gram_nn, self.moment_n):
            c = group[m]
            blocks.append((g_nn, self.nuisance[m].T @ c, c.T @ c, b_n, c.T @ self.y[m]))
        out = np.empty_like(self.y)
        for i, held in enumerate(self.masks):
            train = [blocks[j] for j in range(len(blocks)) if j != i]
            gram = np.empty((p + q, p + q))
            gram[:p, :p] = sum(b[0] for b in train)
            gram[:p, p:] = sum(b[1] for b in train)
            gram[p:, :p] = gram[:p, p:].T
            gram[p:, p:] = sum(b[2] for b in train)
            moment = np.concatenate([sum(b[3] for b in train), sum(b[4] for b in train)])
            beta = np.linalg.solve(gram + ridge_penalty(gram, self.smoothness, self.ridge, q), moment)
            out[held] = self.nuisance[held] @ beta[:p] + group[held] @ beta[p:]
        return out


def held_out_gain(
    y: NDArray[np.float64],
    base: NDArray[np.float64],
    ext: NDArray[np.float64],
    values: NDArray[np.float64],
    masks: list[NDArray[np.bool_]],
) -> float:
    """1 - RMS(ext - y) / RMS(base - y) over the held-out rows whose column value lies inside the
    training folds' range (:func:`host.diagnose.heldout.scored_rows`, as ``held_out`` scores a column)."""
    rows = scored_rows(masks, values)
    eb = float(np.mean((base[rows] - y[rows]) ** 2))
    ee = float(np.mean((ext[rows] - y[rows]) ** 2))
    return 1.0 - float(np.sqrt(ee / eb)) if eb > 0 else 0.0


def held_out_surrogates(
    y: NDArray[np.float64],
    nuisance: Matrix,
    smoothness: Matrix,
    group_of: Callable[[NDArray[np.float64]], Matrix],
    values: NDArray[np.float64],
    copies: list[NDArray[np.float64]],
    kind: str,
    masks: list[NDArray[np.bool_]],
    ridge: float,
) -> HeldOutSurrogates:
    """The held-out gain of the column ``values`` (its regressors ``group_of(values)``) beyond
    ``nuisance`` and of every copy, each scored on its own in-range rows."""
    folds = _FoldBlocks(nuisance, y, masks, smoothness, ridge)
    base_prediction = folds.predictions(np.zeros((y.size, 0)))
    real = held_out_gain(y, base_prediction, folds.predictions(group_of(values)), values, masks)
    gains = np.array(
        [held_out_gain(y, base_prediction, folds.predictions(group_of(c)), c, masks) for c in copies], dtype=float
    )
    # a copy whose fit fails (a non-finite gain) counts as beating the column: never in its favour
    hits = int(np.sum(~np.isfinite(gains) | (gains >= real))) if np.isfinite(real) else len(copies)
    return HeldOutSurrogates(
        real,
        (1 + hits) / (len(copies) + 1),
        len(copies),
        float(np.median(gains)) if gains.size else float("nan"),
        kind,
    )
