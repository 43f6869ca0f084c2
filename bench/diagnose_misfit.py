"""The diagnosis baseline's structural misfit on effect-free records, at several Preisach grid sizes.

Usage: python bench/diagnose_misfit.py [--set tuning,fresh,...] [--per N] [--levels 16,24] [--duration S]
       [--workers N] [--json OUT]      (default: every family, 4 effect-free records each, levels 16,24)

An effect is named only when the error it leaves is large against what the rate-independent
baseline cannot fit anyway (``bench/diagnose_ceiling.py``: most unnamed effects are *buried*
under that misfit). This measures the misfit itself: for each family's first ``--per``
effect-free records (``--duration 100``), the record is prepared as the diagnosis does
(:func:`host.diagnose.run.prepare`, decimated the same way), the actuator lag chosen at the
default grid, and the baseline (Preisach hysteresis + all-pole ARX, fitted on every row) is
refitted with the Preisach grid at each of ``--levels`` intervals. Printed per record and as
per-family medians: the whole-record RMSE over the record's noise floor
(:func:`host.diagnose.folds.noise_floor`; 1 would be a perfect model) and the CPU seconds of the
Preisach rows and the fit (per family the mean). The grid's cost grows with the square of its
intervals (its cells), and the diagnosis' with it.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from multiprocessing import Pool
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants.families import FAMILIES, family_names  # noqa: E402
from bench.plants.family import Case  # noqa: E402
from host.diagnose.features import actuator_input, preisach_rows  # noqa: E402
from host.diagnose.folds import noise_floor  # noqa: E402
from host.diagnose.hammerstein import fit_hammerstein, rmse  # noqa: E402
from host.diagnose.run import PREISACH_LEVELS, choose_actuator_lag, decimated, known_memory, prepare  # noqa: E402


def misfit(job: tuple[str, Case, tuple[int, ...]]) -> dict[str, Any]:
    """One effect-free record's baseline RMSE over its noise floor at each grid size."""
    family, case, levels = job
    m, _truth = FAMILIES[family][1](case)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m, _note = decimated(m)
        ctx, _start_index, _notes = prepare(m, PREISACH_LEVELS)
        ctx.lag_s = choose_actuator_lag(ctx)
        start, _ = known_memory(m.u, m.source)
        driving = actuator_input(m.u, m.dt, ctx.lag_s)
        every = np.ones(ctx.y.size, dtype=bool)
        noise = noise_floor(ctx.y)
        row: dict[str, Any] = {"set": family, "case": case.name, "noise": noise, "lag_s": ctx.lag_s}
        for n in levels:
            cpu = time.process_time()
            rows = preisach_rows(driving, start, n)  # timed with the fit, at every size alike
            model, _x = fit_hammerstein("baseline", rows, ctx.y, every, ctx.dt)
            row[f"misfit_{n}"] = rmse(model.prediction, ctx.y) / noise if noise > 0 else float("nan")
            row[f"cpu_{n}"] = time.process_time() - cpu
    return row


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", default=",".join(FAMILIES), help=f"comma-separated, of {', '.join(FAMILIES)}")
    parser.add_argument("--per", type=int, default=4, help="effect-free records per family")
    parser.add_argument("--levels", default=f"{PREISACH_LEVELS},24", help="Preisach grid intervals, comma-separated")
    parser.add_argument("--duration", type=float, default=100.0, metavar="S")
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--json", type=Path, help="write every row here")
    args = parser.parse_args(argv)
    try:
        sets = family_names(args.set)
    except ValueError as e:
        parser.error(f"--set: {e}")
    try:
        levels = tuple(int(v) for v in args.levels.split(","))
    except ValueError:
        parser.error(f"--levels {args.levels!r}: give whole numbers of grid intervals, e.g. 16,24")
    if min(levels) < 2:
        parser.error("--levels: a Preisach grid needs at least 2 intervals")
    jobs = [
        (s, c, levels)
        for s in sets
        for c in [c for c in FAMILIES[s][0](args.duration) if c.effect == "none"][: args.per]
    ]
    rows: list[dict[str, Any]] = []
    with Pool(max(1, args.workers)) as pool:
        for row in pool.imap(misfit, jobs):
            rows.append(row)
            cells = " ".join(f"{n}: {row[f'misfit_{n}']:5.2f} ({row[f'cpu_{n}']:.1f} s)" for n in levels)
            print(f"{row['case'][:64]:<64} {cells}", flush=True)
    print("\n| set | records | " + " | ".join(f"RMSE / noise at {n} (CPU s)" for n in levels) + " |")
    print("|---|---|" + "---|" * len(levels))
    for s in [*sets, "all"]:
        group = rows if s == "all" else [r for r in rows if r["set"] == s]
        cells = " | ".join(
            f"{np.median([r[f'misfit_{n}'] for r in group]):.2f} ({np.mean([r[f'cpu_{n}'] for r in group]):.1f})"
            for n in levels
        )
        print(f"| {s} | {len(group)} | {cells} |")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2, default=float) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
