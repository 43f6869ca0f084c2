"""``pmactl diagnose``: name what the simulation gets wrong on a recording and measure the fix.

``pmactl diagnose DATA.csv``: one record, blocked held-out folds. ``pmactl diagnose --train
A.csv --test B.csv [--test C.csv]``: what a model identified on A gets wrong on B.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, cast

from edge.errors import DataError


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``diagnose`` subcommand (imported lazily: ``--help`` needs only the standard library)."""
    diag = sub.add_parser(
        "diagnose", help="what the simulation gets wrong on a recording: name the cause, extend, measure the gain"
    )
    diag.add_argument("data", nargs="?", metavar="DATA.csv", help="measured data (t, u, y; optional load, temperature)")
    diag.add_argument("--train", metavar="A.csv", help="cross-run: identify on this recording ...")
    diag.add_argument("--test", action="append", default=[], metavar="B.csv", help="... and check it here (repeatable)")
    diag.add_argument("--report", metavar="DIR", help="write report.md and PNG figures here")
    diag.add_argument("--json", metavar="OUT.json", help="write the result as JSON ('-' for stdout)")
    diag.add_argument("--folds", type=int, default=4, help="blocked held-out folds in time (default 4)")
    diag.add_argument(
        "--stability",
        action="store_true",
        help="repeat the diagnosis without the last 10%% and 20%% of the record and say whether the verdict holds "
        "(3x the time)",
    )

    def run_lazily(args: argparse.Namespace) -> int:
        return run(args)

    diag.set_defaults(run=run_lazily)


def _write_json(target: str, payload: object) -> None:
    """Strict JSON (no NaN or Infinity: non-finite numbers are written as null)."""
    from host.diagnose.run import finite_or_null

    text = json.dumps(finite_or_null(payload), indent=2, default=float, allow_nan=False) + "\n"
    if target == "-":
        sys.stdout.write(text)
        return
    Path(target).parent.mkdir(parents=True, exist_ok=True)
    Path(target).write_text(text)


def run(args: argparse.Namespace) -> int:
    if args.folds < 2:
        raise DataError(f"--folds {args.folds}: a held-out comparison needs at least 2 folds; use 2-10 (default 4)")
    to_stdout = args.json == "-"
    progress = False if to_stdout else None
    say = (lambda *a: print(*a, file=sys.stderr)) if to_stdout else print
    if args.train or args.test:
        if not (args.train and args.test) or args.data:
            raise DataError("cross-run diagnosis takes --train A.csv and at least one --test B.csv, and no DATA.csv")
        if args.stability:
            raise DataError(
                "--stability checks one recording (pmactl diagnose DATA.csv --stability), not --train/--test"
            )
        return _cross_run(args, say, progress)
    if not args.data:
        raise DataError("name a recording (pmactl diagnose DATA.csv) or use --train A.csv --test B.csv")
    from host.data import load_measurement
    from host.diagnose.run import diagnose
    from host.diagnose.stability import diagnose_with_stability

    measurement = load_measurement(args.data)
    run_diagnosis = diagnose_with_stability if args.stability else diagnose
    result = run_diagnosis(measurement, folds=args.folds, progress=progress)
    name = Path(args.data).name
    say(f"{name}: cause {result.cause}")
    say(f"  {result.reason}")
    say(f"  decided by: {result.decided_by}")
    conf = result.confidence
    undecided = cast("list[str] | None", conf.get("undecided_between"))
    if undecided:  # a tie: the margins of the leading cause would read as confidence in it
        tied = ", ".join(f"{c} {result.scores[c]:+.1%}" for c in undecided)
        say(f"  undecided between: {tied}")
    else:
        say(
            f"  confidence: {conf['over_threshold']:+.1%} over its threshold, {conf['over_runner_up']:+.1%} over "
            f"the runner-up ({conf['runner_up']})"
        )
    stability = cast("dict[str, object] | None", conf.get("stability"))
    if stability is not None:
        shortened = ", ".join(f"{k.replace('_', ' ')} -> {v}" for k, v in stability.items() if k != "holds")
        holds = stability["holds"]
        state = "not checked" if holds is None else "holds" if holds else "BORDERLINE"
        say(f"  stability: {state} ({shortened})")
    say(
        f"  held-out RMSE: baseline {result.baseline_rmse:.4g}, extended {result.extended_rmse:.4g} "
        f"(gain {result.gain:.0%}); noise floor {conf['noise_floor']:.3g}"
    )
    say(f"  {'candidate':<18} {'gain':>7}  per fold")
    for cause, gains in result.fold_gains.items():
        folds = " ".join(f"{g:+.1%}" for g in gains)
        say(f"  {cause:<18} {result.scores[cause]:>+7.1%}  {folds}")
    found = cast("dict[str, dict[str, Any]]", result.evidence.get("signatures") or {})
    for cause, sig in found.items():
        say(f"  signature {cause:<18} p = {sig['p_value']:.2g}: {sig['detail']}")
    for note in measurement.notes + result.notes:
        say(f"  note: {note}")
    try:
        if args.json:
            _write_json(args.json, result.as_json())
            if not to_stdout:
                say(f"  JSON written to {args.json}")
        if args.report:
            from host.diagnose.report import write_report

            say(f"  report written to {write_report(result, args.report, name)}")
    except OSError as exc:
        raise DataError(f"cannot write the results ({exc}); choose a writable --json / --report path") from exc
    return 0


def _cross_run(args: argparse.Namespace, say: Callable[..., None], progress: bool | None) -> int:
    from host.data import load_measurement
    from host.diagnose.crossrun import cross_run

    train = load_measurement(args.train)
    tests = [load_measurement(path) for path in args.test]
    results = cross_run(train, tests, progress=progress)
    for path, result in zip(args.test, results):
        say(f"{Path(args.train).name} -> {Path(path).name}: cause {result.cause}")
        say(f"  {result.reason}")
        say(f"  {'correction':<22} {'gain':>7}  per fold")
        for name, gains in result.fold_gains.items():
            say(f"  {name:<22} {result.scores[name]:>+7.1%}  {' '.join(f'{g:+.1%}' for g in gains)}")
        for note in result.notes:
            say(f"  note: {note}")
    if args.json:
        try:
            _write_json(args.json, [r.as_json() for r in results])
        except OSError as exc:
            raise DataError(f"cannot write the results ({exc}); choose a writable --json path") from exc
    return 0
