"""What every trainer shares: seeding, the held-out tail, early stopping, progress, the curve.

A training record is split in time: the first ``1 - tail_fraction`` trains the net, the last
``tail_fraction`` (default 20 %) is held out for its early stopping. The hysteresis operator
under the net is identified on the whole record, as ``pmactl fit`` identifies the baselines. Training starts where the
hysteresis memory is known (:func:`host.identify.common.memory_start`), as ``pmactl fit`` does.
"""

from __future__ import annotations

import random
import sys
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError

MIN_TRAIN_SAMPLES = 400
MIN_TAIL_SAMPLES = 100


def seed_everything(seed: int) -> None:
    """Seed Python, numpy and torch, and make torch deterministic on one thread."""
    import torch

    random.seed(seed)
    np.random.seed(seed)
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True)
    torch.set_num_threads(1)


@dataclass
class Split:
    """Index ranges of one record: training ``[start, tail)``, early-stopping tail ``[tail, end)``."""

    start: int
    tail: int
    end: int


def split_record(n_samples: int, start: int, tail_fraction: float, source: str) -> Split:
    """Training part and held-out tail after the memory start; refuses records too short."""
    usable = n_samples - start
    tail = start + int(round((1.0 - tail_fraction) * usable))
    if tail - start < MIN_TRAIN_SAMPLES or n_samples - tail < MIN_TAIL_SAMPLES:
        raise DataError(
            f"{source}: too short to train on: {usable} samples after the hysteresis memory is known "
            f"(sample {start}); need at least {MIN_TRAIN_SAMPLES} to train plus {MIN_TAIL_SAMPLES} for the "
            f"early-stopping tail ({tail_fraction:.0%}). Record longer or pass more --train files"
        )
    return Split(start, tail, n_samples)


@dataclass
class Curve:
    """Training history: one row per epoch (phase name, training loss, held-out tail RMSE)."""

    rows: list[tuple[str, int, float, float]] = field(default_factory=list)

    def add(self, phase: str, epoch: int, train_loss: float, tail_rmse: float) -> None:
        self.rows.append((phase, epoch, train_loss, tail_rmse))

    def as_dict(self) -> dict[str, list[object]]:
        return {
            "phase": [r[0] for r in self.rows],
            "epoch": [r[1] for r in self.rows],
            "train_loss": [r[2] for r in self.rows],
            "tail_rmse": [r[3] for r in self.rows],
        }

    def save_png(self, path: str | Path, title: str) -> Path:
        """Training loss and held-out-tail RMSE against epoch, one colour per phase."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        x = np.arange(len(self.rows))
        for phase in dict.fromkeys(r[0] for r in self.rows):
            mask = np.array([r[0] == phase for r in self.rows])
            top.semilogy(x[mask], np.array([r[2] for r in self.rows])[mask], ".-", label=phase)
            bottom.plot(x[mask], np.array([r[3] for r in self.rows])[mask], ".-", label=phase)
        top.set_ylabel("training loss (normalised MSE)")
        bottom.set_ylabel("held-out tail RMSE [output units]")
        bottom.set_xlabel("epoch (all phases in order)")
        top.legend()
        top.set_title(title)
        figure.tight_layout()
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        figure.savefig(path, dpi=100)
        plt.close(figure)
        return path


class EarlyStopping:
    """Keep the best state seen on the held-out tail; stop after ``patience`` epochs without a gain.

    With ``smoothing`` (0 < s <= 1) the stop decision follows the exponentially smoothed score
    ``s * score + (1 - s) * previous``: one lucky epoch neither resets the patience nor, since the
    kept state must also be best on its own score, decides alone what is kept. ``smoothing=1``
    (the default) is the raw score.
    """

    def __init__(self, patience: int, smoothing: float = 1.0) -> None:
        if not 0 < smoothing <= 1:
            raise ValueError(f"smoothing {smoothing} must be in (0, 1]")
        self.patience = patience
        self.smoothing = smoothing
        self.best = float("inf")
        self.best_state: dict[str, object] | None = None
        self.stale = 0
        self.smoothed = float("inf")
        self.best_smoothed = float("inf")

    def update(self, score: float, state: dict[str, object]) -> bool:
        """Record ``score`` (lower is better); True when training should stop."""
        import copy

        finite = bool(np.isfinite(score))
        if finite and score < self.best * (1.0 - 1e-4):
            self.best, self.best_state = score, copy.deepcopy(state)
        if finite:
            s = self.smoothing
            self.smoothed = score if not np.isfinite(self.smoothed) else s * score + (1 - s) * self.smoothed
        if finite and self.smoothed < self.best_smoothed * (1.0 - 1e-4):
            self.best_smoothed, self.stale = self.smoothed, 0
        else:
            self.stale += 1
        return self.stale >= self.patience

    def restart(self) -> None:
        """A new phase: the patience and the smoothed score start again; the best state is kept."""
        self.stale = 0
        self.smoothed = self.best_smoothed = float("inf")


def progress(total: int, description: str, quiet: bool) -> Iterator[int]:
    """``range(total)`` with a tqdm bar on stderr unless ``quiet`` or stderr is not a terminal."""
    if quiet or not sys.stderr.isatty():
        yield from range(total)  # no tqdm object at all: it would start its monitor thread
        return
    from tqdm import tqdm

    yield from tqdm(range(total), desc=description, file=sys.stderr, leave=False)


def normaliser(x: NDArray[np.float64]) -> tuple[float, float]:
    """Mean and standard deviation (1 for a constant signal)."""
    std = float(np.std(x))
    return float(np.mean(x)), std if std > 1e-12 else 1.0
