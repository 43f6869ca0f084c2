"""Diagnosis v3 as ``report.md`` and one figure a person reads: where in time (and in which
runs) the model fails before and after the extension, the evidence table per cause, the reason."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from host.diagnose.v3 import DiagnosisV3  # noqa: E402


def _rolling_rms(e: NDArray[np.float64], width: int) -> NDArray[np.float64]:
    kernel = np.ones(max(1, width)) / max(1, width)
    return np.asarray(np.sqrt(np.convolve(e**2, kernel, mode="same")))


def _where_it_fails(d: DiagnosisV3, path: Path, units: str) -> None:
    """Rolling RMS error over the campaign clock and, for several runs, the RMS error per run."""
    rs = d.runset
    width = max(1, rs.y.size // 200)
    panels = 2 if rs.n_runs > 1 else 1
    fig, axes = plt.subplots(panels, 1, figsize=(10, 3.4 * panels), squeeze=False)
    ax = axes[0, 0]
    before = d.heldout.base_prediction if d.heldout else d.baseline.prediction
    after = d.heldout.ext_prediction if d.heldout else None
    ax.plot(rs.clock, _rolling_rms(before - rs.y, width), lw=0.8, color="0.35", label="baseline")
    if after is not None:
        ax.plot(rs.clock, _rolling_rms(after - rs.y, width), lw=0.8, color="tab:red", label=f"+ {d.cause}")
    for a, _b in rs.bounds()[1:]:
        ax.axvline(rs.clock[a], color="0.85", lw=0.5)
    ax.set_xlabel("time since the first run started [s] (grey lines: run boundaries)" if rs.n_runs > 1 else "time [s]")
    ax.set_ylabel(f"rolling RMS error [{units}]")
    kind = "held-out prediction" if d.heldout else "baseline fitted on every row"
    ax.set_title(f"where the model fails ({kind})", fontsize=10)
    ax.legend(fontsize=8)
    if panels == 2:
        ax = axes[1, 0]
        index = np.arange(rs.n_runs)
        per_run = [float(np.sqrt(np.mean((before[a:b] - rs.y[a:b]) ** 2))) for a, b in rs.bounds()]
        ax.bar(index - 0.2, per_run, width=0.4, color="0.55", label="baseline")
        if after is not None:
            fixed = [float(np.sqrt(np.mean((after[a:b] - rs.y[a:b]) ** 2))) for a, b in rs.bounds()]
            ax.bar(index + 0.2, fixed, width=0.4, color="tab:red", label=f"+ {d.cause}")
        step = max(1, rs.n_runs // 20)
        names = [Path(n).stem for n in rs.names]
        if len(set(names)) < len(names):  # the same file names in several folders (campaigns)
            names = [f"{Path(n).parent.name[:10]}/{Path(n).stem}" for n in rs.names]
        ax.set_xticks(index[::step], names[::step], rotation=60, fontsize=7)
        ax.set_ylabel(f"RMS error per run [{units}]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _g(value: float) -> str:
    return f"{value:.3g}" if np.isfinite(value) else "-"


def write_report_v3(d: DiagnosisV3, directory: str | Path, source: str, units: str = "units of y") -> Path:
    """``report.md`` and ``failure.png`` in ``directory``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    _where_it_fails(d, out / "failure.png", units)
    rows = "\n".join(
        f"| {g} | {t.df} | {_g(t.unique_stat)} | {t.unique_p:.3g} | {t.marginal_p:.3g} | {t.level:.3g} | "
        f"{t.unique_share:.2%} | {_g(t.mde)} | {t.null} |"
        for g, t in d.tests.items()
    )
    held = ""
    if d.heldout is not None:
        h = d.heldout
        held = (
            f"\n## Held-out gain of the extension\n\nHeld-out RMS error: baseline {h.base_rmse:.4g}, extended "
            f"{h.ext_rmse:.4g} [{units}]; gain {h.gain_units:.3g} [{units}] = {h.gain:.1%} (90 % interval "
            f"{h.interval[0]:.1%} to {h.interval[1]:.1%}); Clark-West t = {h.clark_west_t:.2f}, one-sided p = "
            f"{h.clark_west_p:.3g}. Per fold: {', '.join(f'{g:+.1%}' for g in h.fold_gains)}.\n"
        )
    notes = "".join(f"- {n}\n" for n in d.notes)
    runs = ", ".join(f"`{Path(n).name}`" for n in d.runset.names[:8]) + (" ..." if d.runset.n_runs > 8 else "")
    text = f"""# Diagnosis of {source}

**Cause: `{d.cause}`.** {d.reason}.

Runs: {runs} ({d.runset.y.size} samples at {1 / d.runset.dt:.4g} Hz). Held-out data: {d.holdout}.
Method {d.rules.version} (rules in `host/diagnose/rules.py`), family-wise alpha {d.rules.alpha:g} per record.

![where the model fails](failure.png)

## Evidence per cause

Statistic: Wald chi-square of the cause's regressors in the AR-whitened regression, unique =
beyond the baseline and every other cause, marginal = beyond the baseline only. Unique share:
of the whitened residual's variance. MDE: the smallest RMS of an effect's own part [{units}]
this record finds with 80 % power at the cause's level.

| cause | df | unique statistic | unique p | marginal p | level | unique share | MDE | null |
|---|---:|---:|---:|---:|---:|---:|---:|---|
{rows}
{held}
## Notes

{notes or "- none"}
"""
    path = out / "report.md"
    path.write_text(text)
    return path
