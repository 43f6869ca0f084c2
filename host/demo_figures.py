"""The figures ``pmactl demo`` writes (measured vs model loops, the closed-loop tracking) and
``pmactl fit --plot``'s loops of the user's own tests.

Axes carry units; the tracking figure shades the settle window (not scored), draws the output
range the bundle can reach, and states the RMS errors in mm and the cut in percent.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from host.data import Measurement
    from host.workflow import TestResult


def _pyplot():  # noqa: ANN202 - matplotlib's module
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_loops(
    path: Path,
    u_bar: NDArray[np.float64],
    y_mm: NDArray[np.float64],
    predictions: dict[str, tuple[NDArray[np.float64], int, float]],
) -> Path:
    """One panel per model: measured contraction against pressure, and the model's, on the scored part.

    ``predictions``: model name -> (predicted y [mm], first scored sample, RMSE as % of p-p).
    """
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(10, 8), sharex=True, sharey=True)
    for ax, (name, (y_hat, start, pct)) in zip(axes.ravel(), predictions.items()):
        ax.plot(u_bar[start:], y_mm[start:], color="0.6", lw=1.0, label="measured")
        ax.plot(u_bar[start:], y_hat[start:], color="C3", lw=0.8, label="model")
        ax.set_title(f"{name}: RMSE {pct:.2f} % of peak-to-peak")
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel("input u: pressure [bar]")
    for ax in axes[:, 0]:
        ax.set_ylabel("output y: contraction [mm]")
    axes[0, 0].legend(loc="upper left")
    fig.suptitle("Held-out test: measured loops (grey) and each identified model (red)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_tracking(
    path: Path,
    runs: dict[str, dict[str, NDArray[np.float64]]],
    settle_s: float,
    reachable_mm: tuple[float, float],
    rms_mm: dict[str, float],
) -> Path:
    """Reference and measured contraction over time for each controller, and the tracking error.

    ``runs``: controller -> columns ``t`` [s], ``reference_mm``, ``contraction_mm``.
    """
    plt = _pyplot()
    fig, axes = plt.subplots(len(runs) + 1, 1, figsize=(10, 3 + 2.4 * len(runs)), sharex=True)
    for ax, (name, run) in zip(axes, runs.items()):
        ax.plot(run["t"], run["reference_mm"], color="k", lw=1.0, ls="--", label="reference")
        ax.plot(run["t"], run["contraction_mm"], color="C0", lw=1.0, label="measured")
        ax.set_ylabel("contraction [mm]")
        ax.set_title(f"{name}: RMS error {rms_mm[name]:.2f} mm after {settle_s:g} s")
    for name, run in runs.items():
        axes[-1].plot(run["t"], run["contraction_mm"] - run["reference_mm"], lw=0.9, label=name)
    axes[-1].set_ylabel("error y - reference [mm]")
    axes[-1].set_xlabel("t [s]")
    for ax in axes:
        ax.axvspan(0.0, settle_s, color="0.85", zorder=0, label="settling (not scored)")
        ax.grid(alpha=0.3)
    for ax in axes[:-1]:
        for level in reachable_mm:
            ax.axhline(level, color="C3", lw=0.7, ls=":")
        ax.plot([], [], color="C3", lw=0.7, ls=":", label="reachable by the bundle")
        ax.legend(loc="upper right", fontsize=8, ncol=2)
    axes[-1].legend(loc="upper right", fontsize=8)
    names = list(rms_mm)
    if len(names) == 2 and rms_mm[names[0]] > 0:
        cut = 100.0 * (1.0 - rms_mm[names[1]] / rms_mm[names[0]])
        fig.suptitle(f"Closed loop on the emulated rig: {names[1]} cuts the RMS error by {cut:.0f} %")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_test_loops(
    path: Path,
    model: str,
    tests: Sequence[Measurement],
    results: Sequence[TestResult],
    u_unit: str,
    y_unit: str,
) -> Path:
    """``pmactl fit --plot``: measured and model output against the input, one panel per test.

    Only the scored part of each test is drawn (after its calibration window), as in the table.
    """
    plt = _pyplot()
    columns = min(2, len(tests))
    rows = -(-len(tests) // columns)
    fig, axes = plt.subplots(rows, columns, figsize=(5.5 * columns, 4.5 * rows), squeeze=False)
    for ax, test, result in zip(axes.ravel(), tests, results):
        start = result.prediction.window_end
        ax.plot(test.u[start:], test.y[start:], color="0.55", lw=1.0, label="measured")
        ax.plot(test.u[start:], result.prediction.y[start:], color="C3", lw=0.8, label=model)
        score = result.prediction.score
        ax.set_title(f"{result.name}: RMSE {score.rmse:.3g} {y_unit} ({score.rmse_pct_pp:.2f} % p-p)", fontsize=10)
        ax.set_xlabel(f"input u [{u_unit}]")
        ax.set_ylabel(f"output y [{y_unit}]")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8, framealpha=0.9)
    for ax in axes.ravel()[len(tests) :]:
        ax.set_visible(False)
    fig.suptitle(f"pmactl fit --model {model}: held-out loops, scored part")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
