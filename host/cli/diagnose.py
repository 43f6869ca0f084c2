"""``pmactl diagnose``: name what the simulation gets wrong on a recording and measure the fix.

``pmactl diagnose DATA.csv``: one record, blocked held-out folds (method v2 by default).
``pmactl diagnose RUN1.csv RUN2.csv ...`` or a glob (``'runs/*.csv'``): several runs of one rig
together, with the calibrated-test method v3 (``--method v3`` chooses it for one record too).
``pmactl diagnose --train 'A*.csv' --test 'B*.csv'``: what a model identified on the training runs
gets wrong on the test runs (both take globs and repeat). One training recording without ``--method
v3`` keeps the v2 cross-run (one verdict per test recording); several training runs, or ``--method
v3``, identify on every training run together and judge the test runs together, with a line per run.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

from edge.errors import DataError
from host.cli.options import add_data_options, expand_runs, read_measurement

if TYPE_CHECKING:
    from host.data import Measurement


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``diagnose`` subcommand (imported lazily: ``--help`` needs only the standard library)."""
    diag = sub.add_parser(
        "diagnose", help="what the simulation gets wrong on a recording: name the cause, extend, measure the gain"
    )
    diag.add_argument(
        "data",
        nargs="*",
        metavar="RUN.csv",
        help="measured data (t, u, y; optional load, temperature); several runs or globs are diagnosed together (v3)",
    )
    diag.add_argument(
        "--train",
        action="append",
        default=[],
        metavar="A.csv",
        help="cross-run: identify on these runs together (repeatable, globs: --train 'day1/*.csv') ...",
    )
    diag.add_argument(
        "--test", action="append", default=[], metavar="B.csv", help="... and check the model here (repeatable, globs)"
    )
    diag.add_argument(
        "--method",
        choices=("v2", "v3"),
        help="v2: held-out gain floors (default for one record); v3: calibrated conditional tests (default for "
        "several runs)",
    )
    diag.add_argument(
        "--rules",
        metavar="FIELD=VALUE,...",
        help="v3 on runs (not --train/--test): change fields of its rules (host/diagnose/rules.py), e.g. "
        "column_first=true; the verdict's method names them",
    )
    diag.add_argument("--report", metavar="DIR", help="write report.md and PNG figures here")
    diag.add_argument("--json", metavar="OUT.json", help="write the result as JSON ('-' for stdout)")
    diag.add_argument(
        "--folds",
        type=int,
        default=None,
        help="v2: blocked held-out folds in time (default 4); v3 adapts them to the data",
    )
    diag.add_argument(
        "--stability",
        action="store_true",
        help="repeat the diagnosis without the last 10%% and 20%% of the record and say whether the verdict holds "
        "(3x the time)",
    )

    add_data_options(diag)

    def run_lazily(args: argparse.Namespace) -> int:
        return run(args)

    diag.set_defaults(run=run_lazily)


def _write_json(target: str, payload: object) -> None:
    """Strict JSON (no NaN or Infinity: non-finite numbers are written as null)."""
    from host.cli.outputs import strict_json

    text = strict_json(payload, indent=2, default=float) + "\n"
    if target == "-":
        sys.stdout.write(text)
        return
    Path(target).parent.mkdir(parents=True, exist_ok=True)
    Path(target).write_text(text)


def _paths(patterns: list[str], option: str) -> list[str]:
    """``patterns`` expanded (globs sorted); a folder is refused with the pattern that named it."""
    paths = []
    for pattern in patterns:
        for path in expand_runs([pattern], option):
            if Path(path).is_dir():
                raise DataError(
                    f"{option} {pattern}: {path} is a folder, not a recording; name the files in it "
                    f"('{Path(path) / '*.csv'}')"
                )
            paths.append(path)
    return paths


def _same_units(runs: list[Measurement], paths: list[str]) -> None:
    """Refuse runs whose input or output units differ (one model cannot fit bar and psi at once)."""
    for role in ("u", "y"):
        seen: dict[str, str] = {}
        for m, path in zip(runs, paths):
            unit = m.units.get(role)
            if unit is not None:
                seen.setdefault(unit, path)
        if len(seen) > 1:
            (u1, p1), (u2, p2) = list(seen.items())[:2]
            raise DataError(
                f"mixed units of {role}: {Path(p1).name} is in {u1}, {Path(p2).name} in {u2}; convert the runs to one "
                f"unit, or give it with --units (e.g. --units u=bar,y=mm) when the headers are wrong"
            )


# v2's cross-run needs this many samples per recording (host.diagnose.run.MIN_SAMPLES; not imported
# here: the CLI imports the diagnosis lazily); shorter runs go to the runs method, whose folds adapt
V2_MIN_SAMPLES = 400


def _shortest(paths: list[str], args: argparse.Namespace) -> int:
    """The fewest samples in any of ``paths`` (read quietly: the chosen method reads them again)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return min(len(read_measurement(path, args)) for path in paths)


def run(args: argparse.Namespace) -> int:
    args.data = _paths(list(args.data), "run")
    args.test = _paths(list(args.test), "--test")
    args.train = _paths(list(args.train), "--train")
    if args.train or args.test:
        if not (args.train and args.test) or args.data:
            raise DataError(
                "cross-run diagnosis takes --train A.csv and --test B.csv (each repeatable, globs), and no RUN.csv"
            )
        if args.stability:
            raise DataError(
                "--stability checks one recording (pmactl diagnose DATA.csv --stability), not --train/--test"
            )
        if args.rules:
            raise DataError(
                "--rules sets the rules of the runs method (pmactl diagnose RUN.csv ... ); the cross-run comparison "
                "(--train/--test) takes none: drop --rules"
            )
        trained = {Path(p).resolve() for p in args.train}
        both = sorted(p for p in args.test if Path(p).resolve() in trained)
        if both:
            raise DataError(
                f"{Path(both[0]).name} is given to both --train and --test; a run cannot check the model it trained. "
                "Split the runs into two lists"
            )
        short = args.method is None and _shortest(args.train + args.test, args) < V2_MIN_SAMPLES
        if len(args.train) > 1 or args.method == "v3" or short:
            if args.method == "v2":
                raise DataError(
                    f"--method v2 identifies on one training recording and --train matches {len(args.train)}; "
                    "drop --method (several training runs are judged together) or name one --train file"
                )
            return _cross_runs(args)
        if args.report:
            raise DataError(
                "--report: the v2 cross-run (one training recording) writes no report; add --method v3 to judge the "
                "test runs with the runs method, which does"
            )
        args.train = args.train[0]
    if args.method == "v3" or len(args.data) > 1:
        _v3_rules(args)
        if args.stability:
            raise DataError("--stability is a v2 check; v3 reports held-out folds and an interval instead")
        if args.method == "v2":
            raise DataError("method v2 takes one recording; several runs are diagnosed with --method v3 (the default)")
        return _runs_v3(args)
    if args.rules:
        raise DataError(
            "--rules sets the rules of method v3 and this is a v2 diagnosis (one recording); add --method v3"
        )
    if args.folds is None:
        args.folds = 4
    if args.folds < 2:
        raise DataError(f"--folds {args.folds}: a held-out comparison needs at least 2 folds; use 2-10 (default 4)")
    to_stdout = args.json == "-"
    progress = False if to_stdout else None
    say = (lambda *a: print(*a, file=sys.stderr)) if to_stdout else print
    if args.train:
        return _cross_run(args, say, progress)
    if not args.data:
        raise DataError("name a recording (pmactl diagnose DATA.csv) or use --train A.csv --test B.csv")
    from host.diagnose.run import diagnose
    from host.diagnose.stability import diagnose_with_stability

    measurement = read_measurement(args.data[0], args)
    run_diagnosis = diagnose_with_stability if args.stability else diagnose
    result = run_diagnosis(measurement, folds=args.folds, progress=progress)
    name = Path(args.data[0]).name
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
    from host.diagnose.report import write_report

    _write_results(args, say, result.as_json(), lambda: write_report(result, args.report, name))
    return 0


def _v3_rules(args: argparse.Namespace) -> None:
    """``args.rules`` as a :class:`host.diagnose.rules.Rules` (the default without ``--rules``)."""
    from host.diagnose.rules import RULES, with_overrides

    try:
        args.rules = with_overrides(args.rules or "", RULES)
    except ValueError as exc:
        raise DataError(str(exc)) from None


def _runs_v3(args: argparse.Namespace) -> int:
    """Diagnosis v3 of one or more runs: the verdict, the evidence per cause, the held-out gain."""
    from host.diagnose.v3 import diagnose_runs

    if args.folds is not None:
        raise DataError("--folds is a v2 setting; v3 chooses its folds from the data (blocks, or whole short runs)")
    to_stdout = args.json == "-"
    say = (lambda *a: print(*a, file=sys.stderr)) if to_stdout else print
    runs = _read_runs(args.data, args)
    # a progress line on stderr for anything that takes more than a few seconds (stdout stays clean)
    result = diagnose_runs(runs, rules=args.rules, progress=sum(len(m) for m in runs) > 10_000 or len(runs) > 10)
    title = Path(args.data[0]).name if len(runs) == 1 else f"{len(runs)} runs ({Path(args.data[0]).name} ...)"
    say(f"{title}: cause {result.cause} (method {result.rules.version})")
    say(f"  {result.reason}")
    if result.cannot_tell:
        say(f"  cannot tell apart: {', '.join(result.cannot_tell)}")
    if result.also:
        say(f"  also: {', '.join(result.also)}")
    say(f"  {'cause':<18} {'unique p':>9} {'marginal p':>10} {'level':>7} {'share':>7} {'MDE':>9}")
    for g, t in result.tests.items():
        say(f"  {g:<18} {t.unique_p:>9.3g} {t.marginal_p:>10.3g} {t.level:>7.3g} {t.unique_share:>7.2%} {t.mde:>9.3g}")
    say(f"  held-out: {result.holdout}")
    say(f"  time: {result.seconds:.1f} s wall, {result.cpu_seconds:.1f} s CPU")
    run_notes = [f"{Path(m.source).name}: {n}" for m in runs for n in m.notes]
    if run_notes:
        say(f"  note: {run_notes[0]}" + (f" (and {len(run_notes) - 1} more run notes)" if len(run_notes) > 1 else ""))
    for note in result.notes:
        say(f"  note: {note}")
    from host.diagnose.report_v3 import write_report_v3

    _write_results(args, say, result.as_json(), lambda: write_report_v3(result, args.report, title, _output_unit(runs)))
    return 0


def _read_runs(paths: list[str], args: argparse.Namespace) -> list[Measurement]:
    """Every run of ``paths``, warnings folded into one line, units checked to agree."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        runs = [read_measurement(path, args) for path in paths]
    if caught:  # one line, not one per run
        first = str(caught[0].message)
        more = f" (and {len(caught) - 1} more like it)" if len(caught) > 1 else ""
        print(f"pmactl: warning: {first}{more}", file=sys.stderr)
    _same_units(runs, paths)
    return runs


def _cross_runs(args: argparse.Namespace) -> int:
    """Cross-run over lists: the model of every training run, judged on every test run."""
    from host.diagnose.crossrun_runs import cross_runs

    if args.folds is not None:
        raise DataError(
            "--folds is a v2 setting; with several training runs the folds are chosen from the data (whole test "
            "runs when runs are short, else blocks)"
        )
    say = (lambda *a: print(*a, file=sys.stderr)) if args.json == "-" else print
    train = _read_runs(args.train, args)
    test = _read_runs(args.test, args)
    _same_units(train + test, args.train + args.test)
    units = _output_unit(train + test)
    result = cross_runs(train, test)
    say(f"{_runs_title(args.train)} -> {_runs_title(args.test)}: cause {result.cause}")
    say(f"  {result.reason}")
    say(f"  {'correction':<18} {'gain':>7} {'90 % interval':>17} {'Clark-West p':>13}")
    for name, h in result.corrections.items():
        interval = f"{h.interval[0]:+.1%} to {h.interval[1]:+.1%}"
        say(f"  {name:<18} {h.gain:>+7.1%} {interval:>17} {h.clark_west_p:>13.2g}")
    say(f"  held-out: {result.holdout}; each correction's level {result.level:.2g}")
    last = f"+ {result.cause}" if result.cause != "none" else "+ offset again (nothing named)"
    say(f"  per test run, RMS error [{units}]: model as identified / + offset / {last} (held out)")
    for line in result.per_run:
        say(
            f"  {line.name:<24} {line.samples:>5} samples  {line.model_rmse:>8.3g} {line.offset_rmse:>8.3g} "
            f"{line.corrected_rmse:>8.3g}"
        )
    say(f"  time: {result.seconds:.1f} s wall, {result.cpu_seconds:.1f} s CPU")
    for note in result.notes:
        say(f"  note: {note}")
    from host.diagnose.report_crossrun import write_report_crossrun

    _write_results(args, say, result.as_json(), lambda: write_report_crossrun(result, args.report, units))
    return 0


def _runs_title(paths: list[str]) -> str:
    return Path(paths[0]).name if len(paths) == 1 else f"{len(paths)} runs ({Path(paths[0]).name} ...)"


def _output_unit(runs: list[Measurement]) -> str:
    """The output's unit for the report's axes: the runs' own (from --units or a header suffix)."""
    units = {m.units.get("y") for m in runs} - {None}
    return str(units.pop()) if len(units) == 1 else "units of y"


def _write_results(
    args: argparse.Namespace, say: Callable[..., None], payload: object, write_report: Callable[[], Path]
) -> None:
    """``--json`` (a file, or ``-`` for stdout) and ``--report``; a path that cannot be written is one error."""
    try:
        if args.json:
            _write_json(args.json, payload)
            if args.json != "-":
                say(f"  JSON written to {args.json}")
        if args.report:
            say(f"  report written to {write_report()}")
    except OSError as exc:
        raise DataError(f"cannot write the results ({exc}); choose a writable --json / --report path") from exc


def _cross_run(args: argparse.Namespace, say: Callable[..., None], progress: bool | None) -> int:
    from host.diagnose.crossrun import cross_run

    train = read_measurement(args.train, args)
    tests = [read_measurement(path, args) for path in args.test]
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
