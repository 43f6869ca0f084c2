"""The diagnosis as a Markdown report with PNG figures a person reads at a glance."""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from host.diagnose.run import CAUSES, Diagnosis  # noqa: E402


def _loops(d: Diagnosis, path: Path) -> None:
    ctx = d.context
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, model, title in ((axes[0], d.baseline_full, "baseline"), (axes[1], d.extended_full, "extended")):
        ax.plot(ctx.u, ctx.y, lw=0.5, color="0.3", label="measured")
        if model is not None:
            ax.plot(ctx.u, model.prediction, lw=0.5, color="tab:red", label=f"simulated ({model.name})")
        ax.set_title(f"{title}: loops" if model is not None else "no extension chosen")
        ax.set_xlabel("input u")
        ax.legend(loc="upper left", fontsize=8)
    axes[0].set_ylabel("output y")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _residuals(d: Diagnosis, path: Path) -> None:
    ctx = d.context
    residual = d.baseline_full.prediction - ctx.y
    panels = [("time [s]", ctx.t), ("input rate [u/s]", ctx.rate)] + [
        (f"{name}", values) for name, values in ctx.extras.items() if np.ptp(values) > 0
    ]
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.6), sharey=True)
    for ax, (label, values) in zip(np.atleast_1d(axes), panels):
        ax.plot(values, residual, ",", alpha=0.4, color="tab:blue") if label != "time [s]" else ax.plot(
            values, residual, lw=0.4, color="tab:blue", label="baseline"
        )
        if label == "time [s]" and d.extended_full is not None:
            ax.plot(values, d.extended_full.prediction - ctx.y, lw=0.4, color="tab:red", label="extended")
            ax.legend(fontsize=8)
        ax.set_xlabel(label)
    np.atleast_1d(axes)[0].set_ylabel("residual (simulated - measured)")
    fig.suptitle("where the baseline is wrong")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def _scores(d: Diagnosis, path: Path) -> None:
    fig, ax = plt.subplots(figsize=(7, 3.4))
    names = list(CAUSES)
    for i, name in enumerate(names):
        gains = [g for g in d.fold_gains[name] if np.isfinite(g) and g > -1.0]
        ax.bar(i, d.scores[name], color="tab:red" if name == d.cause else "0.6")
        ax.plot([i] * len(gains), gains, "k.", ms=4)
    ax.axhline(0.0, color="k", lw=0.6)
    ax.set_xticks(range(len(names)), [n.replace("_", "\n") for n in names], fontsize=8)
    ax.set_ylabel("held-out RMSE reduction")
    ax.set_title("held-out gain of each extension (bars: mean, dots: folds; failed fits left out)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def write_report(d: Diagnosis, directory: str | Path, source: str) -> Path:
    """``report.md`` plus ``loops.png``, ``residuals.png``, ``scores.png`` in ``directory``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    _loops(d, out / "loops.png")
    _residuals(d, out / "residuals.png")
    _scores(d, out / "scores.png")
    rows = "\n".join(
        f"| {c} | {d.scores[c]:+.1%} | {', '.join(f'{g:+.1%}' for g in d.fold_gains[c])} |" for c in d.fold_gains
    )
    notes = "".join(f"\nNote: {note}\n" for note in d.notes)
    baseline = {"na": d.baseline_full.na, "ar": [float(a) for a in d.baseline_full.ar], **d.baseline_full.extra}
    text = f"""# Diagnosis of `{source}`

**Cause: `{d.cause}`.** {d.reason}.

Decided by: {d.decided_by}. Confidence: {json.dumps(d.confidence)}.

Held-out RMSE: baseline {d.baseline_rmse:.4g}, extended {d.extended_rmse:.4g} (gain {d.gain:.0%}).
Held-out data: {d.holdout}.
{notes}
![loops](loops.png)

## Candidates

| cause | mean held-out gain | per fold |
|---|---:|---|
{rows}

![scores](scores.png)

## Where the baseline is wrong

![residuals](residuals.png)

```json
{json.dumps(d.evidence, indent=2)}
```

## Extended model

```json
{json.dumps(d.extended_model, indent=2)}
```

Baseline: {json.dumps(baseline)}
"""
    path = out / "report.md"
    path.write_text(text)
    return path
