"""Scorecard of ``pmactl diagnose`` on REAL records with one known effect injected (held out).

Usage: python bench/diagnose_injected.py [--data ../shared/data] [--only TEXT] [--json OUT] [--dry-run]
       [--method v2|v3]

The records come from :mod:`bench.plants.injected_real`: ten real base records (five piezo runs,
five joined pneumatic-muscle campaigns) from ``../shared/data``, each as measured and with each
effect injected. Prints one line per record (case, verdict, held-out gain, margin, CPU seconds,
which evidence decided), then a table of injected effects named / total per effect and per kind of
base data (piezo, muscle), and the verdicts on the un-injected records listed on their own: those
are not false alarms by construction, since the real rig may carry a real effect.
``--dry-run`` builds every record and prints its size only (no diagnosis).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants.injected_real import InjectedCase, injected_cases, injected_measurement  # noqa: E402
from host.data import Measurement  # noqa: E402

HERE = Path(__file__).resolve().parent


def dry_run(cases: list[InjectedCase], data: Path) -> list[dict[str, Any]]:
    """Build every record; print its samples, rate, duration, effect size over noise and over span."""
    rows = []
    start = time.process_time()
    print("| case | samples | rate [Hz] | s | intensity | size/noise | size/span | load/temperature |")
    print("|---|---|---|---|---|---|---|---|")
    for case in cases:
        m, truth = injected_measurement(case, data)
        par = truth["parameters"]
        intensity = f"{par['intensity']:.3g} {par['intensity_unit']}" if par else "-"
        print(
            f"| {case.name} | {len(m)} | {1 / m.dt:.0f} | {m.t[-1]:.1f} | {intensity} | "
            f"{truth['effect_size_over_noise']:.1f} | {100 * truth['effect_size_over_span']:.1f} % | "
            f"{truth['load_pattern']}/{truth['temperature_pattern']} |"
        )
        rows.append({"case": case.name, "samples": len(m), **truth})
    print(f"\n{len(cases)} records built in {time.process_time() - start:.2f} CPU s")
    return rows


def diagnosed_v3(m: Measurement) -> dict[str, Any]:
    """One v3 diagnosis of ``m`` in the scorecard's row format (warnings silenced)."""
    import warnings

    from host.diagnose.v3 import diagnose_runs

    start = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        d = diagnose_runs([m])
    if d.cause != "none":
        decided = "unique test + held out"
    elif d.rejected:
        decided = f"rejected held out or by the ladder: {', '.join(d.rejected)}"
    else:
        decided = "cannot tell" if d.cannot_tell else "no unique test passed"
    return {
        "verdict": d.cause,
        "gain": d.gain,
        "confidence": {},
        "decided_by": f"v3: {decided}",
        "cpu_s": time.process_time() - start,
        "samples": len(m),
    }


def score(cases: list[InjectedCase], data: Path, method: str = "v2") -> list[dict[str, Any]]:
    """Diagnose every record with ``method`` (v2: ``diagnose``; v3: ``diagnose_runs``); one printed
    line per record."""
    from bench.diagnose_scorecard import diagnosed, line  # only when scoring: --dry-run never runs the method

    rows = []
    for case in cases:
        m, truth = injected_measurement(case, data)
        row = {
            "case": case.name,
            "kind": case.plant,
            "base": case.base,
            "effect": case.effect,
            "form": case.form,
            **(diagnosed_v3(m) if method == "v3" else diagnosed(m)),
            "size_over_noise": truth["effect_size_over_noise"],
            "size_over_span": truth["effect_size_over_span"],
        }
        rows.append(row)
        mark = "base" if case.effect == "none" else "ok" if row["verdict"] == case.effect else "MISS"
        print(line(mark, case.name, row), flush=True)
    return rows


def table(rows: list[dict[str, Any]]) -> None:
    """Injected effects named / total per effect and kind; the un-injected verdicts on their own."""
    from bench.diagnose_scorecard import named_table

    print("\n## Injected effects named / total")
    named_table(rows, lambda r: [r["kind"], "all"])
    injected = [r for r in rows if r["effect"] != "none"]
    named = [r for r in injected if r["verdict"] == r["effect"]]
    cpu = [r["cpu_s"] for r in rows]
    print(
        f"\nnamed {len(named)}/{len(injected)} ({len(named) / max(1, len(injected)):.0%}; refused "
        f"{sum(r['verdict'] == 'refused' for r in injected)}); "
        f"CPU median {np.median(cpu):.1f} s, max {max(cpu):.1f} s"
    )
    for r in injected:
        if r["verdict"] != r["effect"]:
            print(f"  missed: {r['case']} -> {r['verdict']} (size {r['size_over_span']:.1%} of span)")
    print("\n## Un-injected records (real data may carry a real effect: not scored as false alarms)")
    for r in rows:
        if r["effect"] == "none":
            print(f"  {r['kind']}/{r['base']}: {r['verdict']} (gain {r['gain']:.1%}, {r['decided_by']})")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=HERE.parent.parent / "shared" / "data")
    parser.add_argument("--only", help="only cases whose name contains this text")
    parser.add_argument("--json", type=Path, help="write every row here")
    parser.add_argument("--dry-run", action="store_true", help="build the records and print their sizes only")
    parser.add_argument(
        "--method", choices=("v2", "v3"), default="v2", help="v2 (default: diagnose) or v3 (diagnose_runs)"
    )
    args = parser.parse_args(argv)
    if not args.data.is_dir():
        print(f"no real data at {args.data}; pass --data DIR (the folder with piezo_dspace/)", file=sys.stderr)
        return 2
    cases = [c for c in injected_cases(args.data) if not args.only or args.only in c.name]
    if not cases:
        print(f"no records under {args.data} match --only {args.only!r}", file=sys.stderr)
        return 2
    rows = dry_run(cases, args.data) if args.dry_run else score(cases, args.data, args.method)
    if not args.dry_run:
        table(rows)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
