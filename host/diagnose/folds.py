"""Held-out folds, the rows each fold may be scored on, and the record's noise floor.

A fold is scored only where the model is inside its identified range: held-out rows whose input
lies outside the range the training rows cover ask the hysteresis for cells no training row
visited (a record that starts vented and then stays high puts the only low-pressure data in one
block), so their error says nothing about any candidate.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError

BLOCKS_PER_FOLD = 3
MIN_BLOCK_SAMPLES = 50
# a held-out row is in range when its input is inside the training input range, shrunk by this
# share of the whole range on each side (the Everett grid's cells near the edge need visits too)
RANGE_MARGIN = 0.01
CELL_TOLERANCE = 0.02  # of a cell's regressor (0..1 for a cell fully switched)


def check_folds(folds: int, n: int, blocks_per_fold: int = BLOCKS_PER_FOLD) -> None:
    """Refuse fold counts that cannot work, naming the range that can."""
    most = max(2, n // (blocks_per_fold * MIN_BLOCK_SAMPLES))
    if folds < 2:
        raise DataError(
            f"--folds {folds}: a held-out comparison needs at least 2 folds; use 2-{min(most, 10)} (default 4)"
        )
    if folds > most:
        raise DataError(
            f"--folds {folds}: {n} samples allow at most {most} folds of {blocks_per_fold} blocks of "
            f"{MIN_BLOCK_SAMPLES}+ samples; use 2-{min(most, 10)} (default 4)"
        )


def holdout_masks(n: int, folds: int, blocks_per_fold: int = BLOCKS_PER_FOLD) -> list[NDArray[np.bool_]]:
    """Held-out rows of each fold: ``folds * blocks_per_fold`` contiguous blocks in time, block
    ``j`` held out in fold ``j % folds``, so each fold is spread over the record."""
    blocks = folds * blocks_per_fold
    edges = np.linspace(0, n, blocks + 1).astype(int)
    masks = [np.zeros(n, dtype=bool) for _ in range(folds)]
    for j in range(blocks):
        masks[j % folds][edges[j] : edges[j + 1]] = True
    return masks


def in_range(
    u: NDArray[np.float64], rows: NDArray[np.float32], train: NDArray[np.bool_], held: NDArray[np.bool_]
) -> NDArray[np.bool_]:
    """Held-out rows inside the identified range: the input inside the training input range, and
    every Everett cell's regressor inside the values training saw for it (a cell that stayed
    switched on throughout training, e.g. below the lowest training input, has an unidentified mass)."""
    margin = RANGE_MARGIN * float(np.ptp(u))
    lo, hi = float(u[train].min()) - margin, float(u[train].max()) + margin
    ok = held & (u >= lo) & (u <= hi)
    cell_lo = rows[train].min(axis=0) - CELL_TOLERANCE
    cell_hi = rows[train].max(axis=0) + CELL_TOLERANCE
    candidates = np.flatnonzero(ok)
    for start in range(0, candidates.size, 8192):  # in chunks: rows are (n, cells)
        idx = candidates[start : start + 8192]
        block = rows[idx]
        ok[idx] = np.all((block >= cell_lo) & (block <= cell_hi), axis=1)
    return ok


def noise_floor(y: NDArray[np.float64]) -> float:
    """Robust estimate of the white measurement noise [units of y]: the median absolute third
    difference (a smooth signal's vanishes; white noise's has variance 20 sigma^2)."""
    d3 = np.diff(y, 3)
    if d3.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0))
