"""Figures shared by the diagnosis reports: where in time, and in which runs, a model fails.

``error_by_run_group``: one panel per group of consecutive runs (one per run when there are
few), the error of each run against the time within its run, before (grey) and after (red) the
correction, so a lab user sees at which point of the cycle and in which runs the model fails.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from host.diagnose.runs import RunSet  # noqa: E402

MAX_PANELS = 8
ONE_PANEL_PER_RUN_UP_TO = 6


def run_groups(n_runs: int) -> list[range]:
    """Consecutive runs split into at most :data:`MAX_PANELS` groups (one run each when few)."""
    if n_runs <= ONE_PANEL_PER_RUN_UP_TO:
        return [range(i, i + 1) for i in range(n_runs)]
    size = int(np.ceil(n_runs / MAX_PANELS))
    return [range(a, min(a + size, n_runs)) for a in range(0, n_runs, size)]


def short_names(names: list[str]) -> list[str]:
    """File stems; with the folder's first characters when stems repeat across folders (campaigns)."""
    stems = [Path(n).stem for n in names]
    if len(set(stems)) < len(stems):
        return [f"{Path(n).parent.name[:10]}/{Path(n).stem}" for n in names]
    return stems


def error_by_run_group(
    rs: RunSet,
    before: NDArray[np.float64],
    after: NDArray[np.float64] | None,
    path: Path,
    units: str,
    labels: tuple[str, str],
) -> None:
    """Save the figure (module docstring) to ``path``; ``labels``: the before and after curves' names."""
    groups = run_groups(rs.n_runs)
    cols = 1 if len(groups) == 1 else 2
    rows = int(np.ceil(len(groups) / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(10, 2.4 * rows + 0.6), squeeze=False, sharey=True)
    bounds = rs.bounds()
    names = short_names(rs.names)
    for ax, group in zip(axes.flat, groups):
        for k, i in enumerate(group):
            a, b = bounds[i]
            t = rs.t[a:b]
            ax.plot(t, before[a:b] - rs.y[a:b], lw=0.7, color="0.55", label=labels[0] if k == 0 else None)
            if after is not None:
                ax.plot(t, after[a:b] - rs.y[a:b], lw=0.7, color="tab:red", label=labels[1] if k == 0 else None)
        ax.axhline(0.0, color="0.8", lw=0.5)
        first, last = names[group[0]], names[group[-1]]
        ax.set_title(first if first == last else f"{first} to {last} ({len(group)} runs)", fontsize=8)
        ax.tick_params(labelsize=7)
    for ax in axes.flat[len(groups) :]:
        ax.axis("off")
    for ax in axes[-1, :]:
        ax.set_xlabel("time within the run [s]", fontsize=8)
    for ax in axes[:, 0]:
        ax.set_ylabel(f"model - measured [{units}]", fontsize=8)
    axes.flat[0].legend(fontsize=7)
    fig.suptitle("error in each run, against the time within the run (held out)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def number(value: float, digits: int = 3) -> str:
    """``value`` with ``digits`` significant digits, or '-' when it is not finite."""
    return f"{value:.{digits}g}" if np.isfinite(value) else "-"


def p_value(p: float, resolution: float | None = None) -> str:
    """A p-value for a reader: '< 0.001' below a thousandth, '<= r' at a resampling test's resolution ``r``."""
    if not np.isfinite(p):
        return "-"
    if resolution is not None and p <= resolution * 1.000001:
        return f"<= {resolution:.2g}"
    return "< 0.001" if p < 0.001 else f"{p:.2g}"
