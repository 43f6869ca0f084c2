"""A cross-run diagnosis over lists of runs as ``report.md`` and two figures a person reads:
the verdict and its reason, the corrections tried with their held-out gains, a line per test run,
and where in time and in which runs the training model fails before and after the correction."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from host.diagnose.crossrun_runs import OFFSET, CrossRunsResult  # noqa: E402
from host.diagnose.report_figures import error_by_run_group, number, p_value, short_names  # noqa: E402

MEANING = {
    "session_drift": "an offset: the relation moved as a whole (a re-zeroed sensor, a new rest length)",
    "gain_change": "a gain: stiffer or softer (another load, a new muscle)",
    "input_drift": "an input shift: the same output needs another input (a transducer zero, a supply change)",
    "rate_dependence": "loop width and stroke that change with the input speed",
    "creep": "slow relaxations of the output after each move",
    "transport_delay": "a dead time before the hysteresis",
    "load_dependence": "the load column's level and its products with the output",
    "temperature_drift": "the temperature column's level, lags and products with the output",
    "hysteresis_change": "the whole hysteresis identified again on the test runs (the yardstick, not a cause)",
}


def _per_run_bars(result: CrossRunsResult, path: Path, units: str) -> None:
    lines = result.per_run
    index = np.arange(len(lines))
    fig, ax = plt.subplots(figsize=(10, 3.6))
    ax.bar(index - 0.27, [r.model_rmse for r in lines], width=0.27, color="0.75", label="model as identified")
    ax.bar(index, [r.offset_rmse for r in lines], width=0.27, color="0.45", label="+ offset (held out)")
    if result.cause not in ("none", OFFSET):
        ax.bar(index + 0.27, [r.corrected_rmse for r in lines], width=0.27, color="tab:red", label=f"+ {result.cause}")
    step = max(1, len(lines) // 25)
    names = short_names(result.test.names)
    ax.set_xticks(index[::step], names[::step], rotation=60, fontsize=7)
    ax.set_ylabel(f"RMS error per test run [{units}]")
    ax.set_title("which test runs the training runs' model gets wrong", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def write_report_crossrun(result: CrossRunsResult, directory: str | Path, units: str = "units of y") -> Path:
    """``report.md``, ``runs.png`` and ``failure_by_run.png`` in ``directory``."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    _per_run_bars(result, out / "runs.png", units)
    offset = result.corrections[OFFSET]
    before = result.model_prediction + offset.ext_prediction
    after = result.corrected_prediction if result.cause not in ("none", OFFSET) else None
    error_by_run_group(
        result.test, before, after, out / "failure_by_run.png", units, ("model + offset", f"+ {result.cause}")
    )
    rows = "\n".join(
        f"| {'**' + name + '**' if name == result.cause else name} | {MEANING.get(name, '')} | "
        f"{h.gain:+.1%} | {h.interval[0]:+.1%} to {h.interval[1]:+.1%} | {number(h.gain_units)} | "
        f"{p_value(h.clark_west_p)} | {'yes' if h.clark_west_p <= result.level and h.interval[0] > 0 else 'no'} |"
        for name, h in result.corrections.items()
    )
    per_run = "\n".join(
        f"| {r.name} | {r.samples} | {number(r.model_rmse)} | {number(r.offset_rmse)} | {number(r.corrected_rmse)} |"
        for r in result.per_run
    )
    notes = "".join(f"- {n}\n" for n in result.notes) or "- none\n"
    train = _listed(result.train_names)
    test = _listed(result.test.names)
    verdict = "nothing the tests can show" if result.cause == "none" else f"`{result.cause}`"
    text = f"""# What the model of the training runs gets wrong on the test runs

**Verdict: {verdict}.** {_meaning(result, units)}

- Training runs ({len(result.train_names)}): {train}. The model (Preisach hysteresis, an output lag of
  {number(result.lag_s)} s, its tangents and a static output map) fits them with an RMS error of
  {number(result.train_rmse)} {units}.
- Test runs ({result.test.n_runs}, {result.test.y.size} samples at {1 / result.test.dt:.3g} Hz): {test}.
- Held-out data: {result.holdout}. A correction counts when the Clark-West test of its held-out
  improvement over the offset has p <= {result.level:.2g} (family-wise 5 % over
  {len(result.corrections)} corrections) and its 90 % interval of the gain lies above 0.

![which test runs fail](runs.png)

![where in each run the model fails](failure_by_run.png)

## The corrections tried

Each is fitted beside an offset on the other folds' test rows and scored on held-out rows; the
gain is the fall of the held-out RMS error relative to the training model plus an offset (the
offset's own row: relative to the training model as it is).

| correction | what it stands for | held-out gain | 90 % interval | gain [{units}] | Clark-West p | counts |
|---|---|---:|---|---:|---:|---|
{rows}

## Per test run

RMS error [{units}] of the training runs' model as it is, held out with an offset, and held out
with the named correction.

| run | samples | model | + offset | {"+ " + result.cause if result.cause != "none" else "nothing named"} |
|---|---:|---:|---:|---:|
{per_run}

## The method's reason

{result.reason}.

## Notes

{notes}"""
    path = out / "report.md"
    path.write_text(text)
    return path


def _meaning(result: CrossRunsResult, units: str) -> str:
    """The verdict in one paragraph a lab user reads, with the errors in the output's units."""
    offset = result.corrections[OFFSET]
    alone = (
        f"an offset alone takes it from {number(offset.base_rmse)} to {number(offset.ext_rmse)} {units} "
        f"({offset.gain:.0%})"
    )
    if result.cause == "none":
        return (
            "The training runs' model predicts the test runs as well as any correction tried: none improves the "
            f"error on held-out test runs reliably ({alone}). Nothing measurable changed between the sessions."
        )
    h = result.corrections[result.cause]
    if result.cause == OFFSET:
        return (
            f"The test runs differ from the training runs by {MEANING[OFFSET]}: {alone}, with a 90 % interval of "
            f"{h.interval[0]:.0%} to {h.interval[1]:.0%}; no richer correction adds to it."
        )
    return (
        f"The test runs differ from the training runs by {MEANING[result.cause]}. Correcting for it lowers the "
        f"error on held-out test runs from {number(h.base_rmse)} to {number(h.ext_rmse)} {units} RMS beyond an "
        f"offset ({h.gain:.0%} less; 90 % interval {h.interval[0]:.0%} to {h.interval[1]:.0%}); {alone}."
    )


def _listed(names: list[str], first: int = 6) -> str:
    shown = ", ".join(f"`{n}`" for n in short_names(names)[:first])
    return shown + (f" and {len(names) - first} more" if len(names) > first else "")
