"""The figures ``pmactl demo`` writes (measured vs model loops, the closed-loop tracking) and
``pmactl fit --plot``'s loops of the user's own tests.

Axes carry units and legends sit outside the data. The tracking figures (the muscle's and the
joint's) overlay every controller on one reference, fit the error axis to the scored part (the
unscored settle window is shaded), draw the output range the bundle can reach and show the valve
command beside the measured pressure.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:
    from host.data import Measurement
    from host.workflow import TestResult


def _pyplot() -> ModuleType:  # matplotlib.pyplot
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
    fig.suptitle("Held-out test: measured loops (grey) and each identified model (red)")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=2, frameon=False)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _legend_outside(ax: object) -> None:
    """Legend to the right of the axes, never over the data."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)  # type: ignore[attr-defined]


def _scored_limits(values: list[NDArray[np.float64]], margin: float = 0.1) -> tuple[float, float]:
    """y-limits that fit the scored samples (the unscored start may run far off them)."""
    low = min(float(v.min()) for v in values)
    high = max(float(v.max()) for v in values)
    pad = margin * max(high - low, 1e-9)
    return low - pad, high + pad


def plot_tracking(
    path: Path,
    runs: dict[str, dict[str, NDArray[np.float64]]],
    settle_s: float,
    reachable: tuple[float, float],
    rms: dict[str, float],
    *,
    quantity: str = "contraction",
    unit: str = "mm",
) -> Path:
    """The closed loop in three panels sharing time, as a system-identification ``compare`` plot:
    reference and each controller's output; the tracking error (its axis fitted to the scored
    part, after ``settle_s``); the valve command and the measured pressure.

    ``runs``: controller -> columns ``t`` [s], ``reference``, ``output`` (in ``unit``),
    ``command_bar``, ``pressure_bar`` and, for a joint, ``command_b_bar`` (the antagonist's valve).
    ``rms``: controller -> RMS error after ``settle_s``.
    """
    plt = _pyplot()
    fig, (top, middle, bottom) = plt.subplots(
        3, 1, figsize=(11, 8.5), sharex=True, gridspec_kw={"height_ratios": [2.2, 1.4, 1.4]}
    )
    first = next(iter(runs.values()))
    top.plot(first["t"], first["reference"], color="k", lw=1.2, ls="--", label="reference")
    for level in reachable:
        top.axhline(level, color="0.4", lw=0.7, ls=":")
    top.plot([], [], color="0.4", lw=0.7, ls=":", label="reachable by the bundle")
    scored_errors = []
    for index, (name, run) in enumerate(runs.items()):
        colour = f"C{index}"
        label = f"{name} (RMS {rms[name]:.2f} {unit})"
        top.plot(run["t"], run["output"], color=colour, lw=1.0, label=label)
        error = run["output"] - run["reference"]
        middle.plot(run["t"], error, color=colour, lw=0.9, label=name)
        scored_errors.append(error[run["t"] >= settle_s])
        bottom.plot(run["t"], run["command_bar"], color=colour, lw=0.9, label=f"{name}: command")
        if "command_b_bar" in run:  # the antagonist's valve (joint)
            bottom.plot(run["t"], run["command_b_bar"], color=colour, lw=0.9, ls="--", label=f"{name}: muscle B")
        bottom.plot(run["t"], run["pressure_bar"], color=colour, lw=0.7, ls=":", alpha=0.8)
    bottom.plot([], [], color="0.3", lw=0.7, ls=":", label="measured pressure (dotted)")
    middle.set_ylim(*_scored_limits(scored_errors))
    middle.axhline(0.0, color="k", lw=0.6)
    top.set_ylabel(f"{quantity} [{unit}]")
    middle.set_ylabel(f"error y - reference [{unit}]")
    bottom.set_ylabel("pressure [bar]")
    bottom.set_xlabel("t [s]")
    for ax in (top, middle, bottom):
        ax.axvspan(0.0, settle_s, color="0.9", zorder=0)
        ax.grid(alpha=0.3)
        _legend_outside(ax)
    middle.text(
        settle_s / 2, 0.04, "settling: not scored", transform=middle.get_xaxis_transform(),
        ha="center", va="bottom", fontsize=7, color="0.35",
    )  # fmt: skip
    fig.suptitle(f"Closed loop on the emulated rig: {quantity} tracking, scored after {settle_s:g} s")
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
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
        _legend_outside(ax)
    for ax in axes.ravel()[len(tests) :]:
        ax.set_visible(False)
    fig.suptitle(f"pmactl fit --model {model}: held-out loops, scored part")
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path
