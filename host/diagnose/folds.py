"""Held-out folds and the record's noise floor.

Which held-out rows a model is judged on is the model's business
(:meth:`host.diagnose.candidates.Design.scored`): every model's hysteresis is identified on the
whole record, so the input range no longer limits the rows; a term of a measured column is
judged only where the column lies inside its training range.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError

BLOCKS_PER_FOLD = 3
MIN_BLOCK_SAMPLES = 50


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
            f"{MIN_BLOCK_SAMPLES}+ samples; use 2-{most} (default 4)"
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


def noise_floor(y: NDArray[np.float64]) -> float:
    """Robust estimate of the white measurement noise [units of y]: the median absolute third
    difference (a smooth signal's vanishes; white noise's has variance 20 sigma^2)."""
    d3 = np.diff(y, 3)
    if d3.size == 0:
        return 0.0
    return float(1.4826 * np.median(np.abs(d3 - np.median(d3))) / np.sqrt(20.0))
