"""Diagnosis v3 as ``report.md`` and figures a person reads: the verdict in plain words, where in
time and in which runs the model fails before and after the extension (one panel per group of
runs when there are many), the evidence table per cause, the held-out check, a line per run, and
the method's own reason."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from host.diagnose.report_figures import error_by_run_group, number, p_value, short_names  # noqa: E402
from host.diagnose.rules import CAUSES  # noqa: E402
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
        names = short_names(rs.names)
        ax.set_xticks(index[::step], names[::step], rotation=60, fontsize=7)
        ax.set_ylabel(f"RMS error per run [{units}]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


# what each verdict means for the rig, in a lab user's words
PLAIN = {
    "rate_dependence": "the loop's width and stroke change with how fast the input moves",
    "creep": "the output keeps creeping for seconds after each move",
    "transport_delay": "the output responds a dead time after the input, beyond what a lag explains",
    "load_dependence": "the relation changes with the load column",
    "temperature_drift": "the relation changes with the temperature column",
    "slow_drift": "the relation drifts slowly over the campaign, and no recorded column explains it",
}


def _words(cause: str) -> str:
    """A cause's name as words (``load_dependence`` -> ``load dependence``)."""
    return cause.replace("_", " ")


def _resolution(d: DiagnosisV3, cause: str) -> float:
    """The smallest p a resampling test can give for ``cause`` (1 / (draws + 1))."""
    draws = d.rules.column_surrogates if CAUSES[cause].kind == "column" else d.rules.bootstrap_draws
    return 1.0 / (draws + 1)


def _role(d: DiagnosisV3, cause: str) -> str:
    if cause == d.cause:
        return "**named**"
    if cause in d.rejected:
        return "failed held out" if cause in d.trials else "faded with a richer baseline"
    if cause in {g for g, _ in d.further}:
        return "also confirmed held out"
    if cause in d.also:
        return "also significant"
    if cause in d.cannot_tell:
        return "only jointly"
    return "-"


def _meaning(d: DiagnosisV3, units: str) -> str:
    """The reason in one paragraph a lab user reads."""
    if d.cause != "none" and d.heldout is not None:
        h = d.heldout
        text = (
            f"The measured data show that {PLAIN[d.cause]}. Adding this to the model lowers the error on data it "
            f"was not fitted to from {number(h.base_rmse)} to {number(h.ext_rmse)} {units} RMS "
            f"({h.gain:.0%} less; 90 % interval {h.interval[0]:.0%} to {h.interval[1]:.0%})."
        )
        named = [d.cause]
        for g, hf in d.further:
            text += (
                f" Beyond {' and '.join(map(_words, named))}, {PLAIN[g]}: adding it too lowers the held-out error "
                f"from {number(hf.base_rmse)} to {number(hf.ext_rmse)} {units} RMS ({hf.gain:.0%} less; 90 % "
                f"interval {hf.interval[0]:.0%} to {hf.interval[1]:.0%}; on the rows this comparison scores)."
            )
            named.append(g)
        unchecked = [g for g in d.also if g not in named]
        if unchecked:
            text += (
                " Also significant on their own, but not confirmed on held-out data beyond "
                f"{' and '.join(map(_words, named))}: {', '.join(map(_words, unchecked))}."
            )
        return text + f" To confirm it, record {CAUSES[d.cause].to_record}."
    if d.cannot_tell:
        record = "; ".join(f"{c}: {CAUSES[c].to_record}" for c in d.cannot_tell)
        return (
            f"The model misses something that {' or '.join(d.cannot_tell)} explain together, but the data cannot "
            f"tell which. To separate them, record ({record})."
        )
    first = d.rejected[0] if d.rejected else "a cause"
    if d.class_mismatch:
        text = (
            f"No cause is named: {first} passed its test, but faded when the hysteresis model was given more "
            "levels, so the hysteresis model's class does not fit this actuator (a structural misfit, not a cause)."
        )
    elif d.not_confirmed:
        text = (
            f"No cause is named: {first} passed its test on the whole record but did not predict data the fit "
            "had not seen, so what it fits is most likely a misfit of the hysteresis model, not this cause."
        )
    else:
        text = "No cause is significant: the model explains these data as well as they can tell."
    smallest = min(d.tests.values(), key=lambda g: g.mde) if d.tests else None
    if smallest is not None:
        text += (
            f" An effect would have to move the output by about {number(smallest.mde)} {units} RMS to be found "
            f"(the {smallest.name} test, the most sensitive on this record); smaller effects may be present."
        )
    return text


def _per_run_table(d: DiagnosisV3, units: str, limit: int = 40) -> str:
    """RMS error per run, held out, before and after the extension; the worst runs first when many."""
    rs = d.runset
    if rs.n_runs < 2 or d.heldout is None:
        return ""
    h = d.heldout
    after = d.cause != "none"
    lines = []
    for (a, b), name in zip(rs.bounds(), short_names(rs.names)):
        base = float(np.sqrt(np.mean((h.base_prediction[a:b] - rs.y[a:b]) ** 2)))
        ext = float(np.sqrt(np.mean((h.ext_prediction[a:b] - rs.y[a:b]) ** 2)))
        lines.append((base, f"| {name} | {b - a} | {number(base)} |" + (f" {number(ext)} |" if after else "")))
    shown = lines if len(lines) <= limit else sorted(lines, reverse=True)[:limit]
    head = f"| run | samples | baseline [{units}] |" + (f" + {d.cause} [{units}] |" if after else "")
    rule = "|---|---:|---:|" + ("---:|" if after else "")
    title = "Per run" if len(lines) <= limit else f"The {limit} runs the baseline fits worst (of {len(lines)})"
    return (
        f"\n## {title}\n\nHeld-out RMS error of each run (each predicted by a model fitted on other folds).\n\n"
        + "\n".join([head, rule] + [line for _, line in shown])
        + "\n"
    )


def write_report_v3(d: DiagnosisV3, directory: str | Path, source: str, units: str = "units of y") -> Path:
    """``report.md``, ``failure.png`` and (several runs) ``failure_by_run.png`` in ``directory``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    _where_it_fails(d, out / "failure.png", units)
    by_run = ""
    if d.runset.n_runs > 1 and d.heldout is not None:
        after = d.heldout.ext_prediction if d.cause != "none" else None
        labels = ("baseline", f"+ {d.cause}")
        error_by_run_group(d.runset, d.heldout.base_prediction, after, out / "failure_by_run.png", units, labels)
        by_run = "\n![where in each run the model fails](failure_by_run.png)\n"
    nulls = list(dict.fromkeys(t.null for t in d.tests.values()))
    rows = "\n".join(
        f"| {g} | {t.df} | {number(t.unique_stat)} | {p_value(t.unique_p, _resolution(d, g))} | "
        f"{p_value(t.marginal_p, _resolution(d, g))} | {t.level:.2g} | {t.unique_share:.1%} | {number(t.mde)} | "
        f"{nulls.index(t.null) + 1} | {_role(d, g)} |"
        for g, t in d.tests.items()
    )
    legend = "\n".join(f"{i + 1}. {n}" for i, n in enumerate(nulls))
    held = ""
    if d.heldout is not None:
        h = d.heldout
        of = d.cause if d.cause != "none" else (d.rejected[0] if d.rejected else "the first candidate")
        held = (
            f"\n## Held-out check of {of}\n\nRMS error on held-out rows: baseline {number(h.base_rmse)} {units}, "
            f"with {of} {number(h.ext_rmse)} {units}: {number(h.gain_units)} {units} less ({h.gain:.1%}, 90 % "
            f"interval {h.interval[0]:.1%} to {h.interval[1]:.1%}). Clark-West test of the improvement: t = "
            f"{h.clark_west_t:.2f}, one-sided p {_p_phrase(h.clark_west_p)}. Gain per fold: "
            f"{', '.join(f'{g:+.0%}' for g in h.fold_gains)}.\n"
        )
    notes = "".join(f"- {n}\n" for n in d.notes)
    rs = d.runset
    runs = ", ".join(f"`{n}`" for n in short_names(rs.names)[:8]) + (
        f" and {rs.n_runs - 8} more" if rs.n_runs > 8 else ""
    )
    verdict = "none" if d.cause == "none" else f"`{d.cause}`"
    text = f"""# Diagnosis of {source}

**Verdict: {verdict}.** {_meaning(d, units)}

- Data: {rs.n_runs} run(s), {rs.y.size} samples at {1 / rs.dt:.3g} Hz ({rs.clock[-1]:.3g} s in all): {runs}.
- Held-out data: {d.holdout}.
- Method {d.rules.version}: calibrated tests, family-wise {100 * d.rules.alpha:g} % false-alarm rate per record;
  every threshold is in `host/diagnose/rules.py`.

![where the model fails](failure.png)
{by_run}
## Evidence per cause

Each cause is a group of regressors tested beyond the baseline (hysteresis, output lag, static
map) in the regression whitened by the residual's noise model. *Unique*: beyond the baseline and
every other cause; *marginal*: beyond the baseline only. The statistic is a Wald chi-square
with the given degrees of freedom. *Unique share*: of the whitened residual's variance. *MDE*:
the smallest RMS of an effect's own part [{units}] this record finds with 80 % power at the
cause's level. A p shown as "<= x" is the smallest the resampling can give.

| cause | df | unique statistic | unique p | marginal p | level | unique share | MDE [{units}] | null | verdict |
|---|---:|---:|---:|---:|---:|---:|---:|---:|---|
{rows}

Nulls: {legend}
{held}{_per_run_table(d, units)}
## The method's reason

{d.reason}.

## Notes

{notes or "- none"}
"""
    path = out / "report.md"
    path.write_text(text)
    return path


def _p_phrase(p: float) -> str:
    return "< 0.001" if p < 0.001 else f"= {p:.2g}"
