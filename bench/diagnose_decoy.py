"""The decoy column: how often diagnosis v2 and v3 blame a temperature that has nothing to do with
the muscle.

Usage: python bench/diagnose_decoy.py [--seeds N] [--sources hil,real] [--methods v2,v3]

A decoy ``temperature`` column is added to records whose physics it does not touch:

* ``hil``: effect-free HIL recordings (the mixed protocol, 60 s at 100 Hz, one per seed; they exist
  without ../shared/data);
* ``real``: untouched real muscle campaigns of ../shared/data (the characterisation dates 18-03
  and 31-03 and the literature-comparison dates 07-17 and 07-22; skipped when the folder is
  absent).

Shapes (the column wanders over the campaign clock, continuous across runs, 20-30 degC):

* ``walk``: a Gaussian random walk;
* ``smooth_walk``: a random walk low-passed with a time constant of a tenth of the record;
* ``sine``: a slow sine of 0.5-2 periods per record, random phase;
* ``ramp_sine``: a linear warm-up plus a slow sine (the room heats while it oscillates).

Each (source, shape, seed) is diagnosed by ``v2`` (``diagnose``; one record: a campaign's runs
laid end to end), ``v3`` (``diagnose_runs`` on the runs as recorded) and ``v3-1`` (``diagnose_runs``
on the campaign laid end to end as one record, as a user with one file would give it; the same as
``v3`` for a single recording, so not repeated there). A false alarm is a verdict of
``temperature_drift``.
The table prints the count per source, shape and method, the wall and CPU time. Target (issue 33):
at most 1 in 10.

v3's column surrogates (``host.diagnose.conditional.column_copies``) are circular shifts of the
column *reflected at its ends*, so a smooth column's copies are as smooth as it is; ``--surrogates
plain`` swaps in the plain circular shifts used before (:func:`plain_copies`): they put a jump at
the wrap of a ramp or a slow sine, which no smooth misfit in time correlates with, so the real
column beat its copies and slow decoys were named. ``--column-vs-drift`` (a second proposal, for
``host.diagnose.v3.diagnose_runs``): a column cause is confirmed held out against the baseline
*plus smooth functions of the campaign clock* (the hat functions of the drift group), so a column
is named only when it predicts held-out blocks better than a smooth trend in time does
(:func:`held_out_beyond_drift`).
``--inject SHARE``: the temperature is made real, ``y`` gets ``SHARE`` x its p-p x
the scaled column (the power check: a real temperature effect must still be named).
"""

from __future__ import annotations

import argparse
import glob
import os
import resource
import sys
import time
import warnings
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from hil.record import record
from host.data import Measurement, load_measurement
from host.diagnose.conditional import column_copies as CURRENT_COPIES
from host.diagnose.groups import clock_hats
from host.diagnose.heldout import HeldOut
from host.diagnose.heldout import held_out as CURRENT_HELD_OUT
from host.diagnose.rules import RULES, Rules
from host.diagnose.runs import RunSet

# ../shared/data beside the checkout, or $PMACTL_SHARED_DATA (as the tests find it)
DATA = Path(os.environ.get("PMACTL_SHARED_DATA", Path(__file__).resolve().parents[2] / "shared" / "data"))
DATA = DATA / "pam_muscle_sensory"
CAMPAIGNS = (
    "18-03-2026_Length_Characterisation",
    "31-03-2026_Length_Characterisation",
    "2026-07-17_Literature_Comparison",
    "2026-07-22_Literature_Comparison",
)
COLUMN = "temperature"


def walk(clock: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
    return np.cumsum(rng.normal(size=clock.size))


def smooth_walk(clock: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
    steps = rng.normal(size=clock.size)
    a = 1.0 / max(1.0, clock.size / 10)
    out = np.empty_like(steps)
    level = 0.0
    for i, s in enumerate(np.cumsum(steps)):
        level += a * (s - level)
        out[i] = level
    return out


def sine(clock: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
    periods = rng.uniform(0.5, 2.0)
    span = float(clock[-1] - clock[0]) or 1.0
    return np.sin(2 * np.pi * periods * (clock - clock[0]) / span + rng.uniform(0, 2 * np.pi))


def ramp_sine(clock: NDArray[np.float64], rng: np.random.Generator) -> NDArray[np.float64]:
    span = float(clock[-1] - clock[0]) or 1.0
    return (clock - clock[0]) / span + 0.4 * sine(clock, rng)


SHAPES: dict[str, Callable[[NDArray[np.float64], np.random.Generator], NDArray[np.float64]]] = {
    "walk": walk,
    "smooth_walk": smooth_walk,
    "sine": sine,
    "ramp_sine": ramp_sine,
}


def plain_copies(
    rs: object, values: NDArray[np.float64], count: int, rng: np.random.Generator
) -> tuple[list[NDArray[np.float64]], str]:
    """The column surrogates v3 used before reflected shifts (for comparison): per-run values
    permuted across runs when constant within every run and >= 4 runs (as now); otherwise the
    series circularly shifted by 10-90 % of its length, half of the copies mirrored in time."""
    copies, kind = CURRENT_COPIES(rs, values, count, rng)  # type: ignore[arg-type]
    if kind.startswith("its per-run values"):
        return copies, kind
    n = values.size
    out = []
    for i in range(count):
        copy = np.roll(values, int(rng.integers(int(0.1 * n), max(int(0.9 * n), int(0.1 * n) + 1))))
        out.append(copy[::-1].copy() if i % 2 else copy)
    return out, "circularly shifted and mirrored copies"


def held_out_beyond_drift(
    rs: RunSet,
    nuisance: NDArray[np.float64],
    smoothness: NDArray[np.float64],
    group: NDArray[np.float64],
    masks: list[NDArray[np.bool_]],
    ridge: float,
    rng: np.random.Generator,
    column: NDArray[np.float64] | None = None,
    clusters: NDArray[np.int64] | None = None,
    whitener: NDArray[np.float64] | None = None,
    penalised_tail: Sequence[int] = (),
) -> HeldOut:
    """``held_out`` with the drift group's hat functions of the clock added to the baseline when a
    column cause is checked (the proposal ``--column-vs-drift``), before the causes already named
    (the penalised tail stays last)."""
    if column is not None:
        at = nuisance.shape[1] - sum(penalised_tail)
        hats = np.column_stack(clock_hats(rs, RULES.drift_knots))
        nuisance = np.hstack([nuisance[:, :at], hats, nuisance[:, at:]])
    return CURRENT_HELD_OUT(
        rs, nuisance, smoothness, group, masks, ridge, rng, column, clusters, whitener, penalised_tail
    )


def to_degc(raw: NDArray[np.float64]) -> NDArray[np.float64]:
    """``raw`` scaled to wander between 20 and 30 degC."""
    spread = float(np.ptp(raw)) or 1.0
    return 20.0 + 10.0 * (raw - raw.min()) / spread


def with_decoy(runs: list[Measurement], shape: str, seed: int, inject: float = 0.0) -> list[Measurement]:
    """``runs`` with a decoy temperature over their campaign clock (runs laid end to end); with
    ``inject`` > 0 it is no decoy: y moves by ``inject`` x its p-p per unit of the scaled column."""
    lengths = [len(m) for m in runs]
    clock = np.arange(sum(lengths), dtype=float)  # samples of the campaign, runs laid end to end
    column = to_degc(SHAPES[shape](clock, np.random.default_rng(seed)))
    span = float(np.ptp(np.concatenate([m.y for m in runs])))
    out, start = [], 0
    for m, n in zip(runs, lengths):
        extras = {k: v for k, v in m.extras.items() if k != COLUMN}
        extras[COLUMN] = column[start : start + n]
        y = m.y + inject * span * (extras[COLUMN] - 25.0) / 10.0
        out.append(Measurement(m.t, m.u, y, extras, m.source, list(m.notes), dict(m.units)))
        start += n
    return out


def end_to_end(runs: list[Measurement]) -> Measurement:
    """The runs as one record (v2 takes one): each run's time shifted to follow the previous one."""
    ts, offset = [], 0.0
    for m in runs:
        ts.append(m.t - m.t[0] + offset)
        offset = float(ts[-1][-1]) + m.dt
    extras = {k: np.concatenate([m.extras[k] for m in runs]) for k in runs[0].extras}
    return Measurement(
        np.concatenate(ts),
        np.concatenate([m.u for m in runs]),
        np.concatenate([m.y for m in runs]),
        extras,
        runs[0].source,
    )


def hil_sources(seeds: int, duration_s: float = 60.0) -> dict[str, list[Measurement]]:
    """``seeds`` effect-free HIL recordings of the mixed protocol, ``duration_s`` each at 100 Hz."""
    out = {}
    for seed in range(seeds):
        rec = record("mixed", 100 + seed, duration_s, "none")
        out[f"hil-{100 + seed}"] = [Measurement(rec.t, rec.u, rec.y, {}, f"hil mixed {100 + seed}")]
    return out


def real_sources() -> dict[str, list[Measurement]]:
    out = {}
    for campaign in CAMPAIGNS:
        paths = sorted(glob.glob(str(DATA / campaign / "*.csv")))
        if paths:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # irregular steps are resampled, with a warning per file
                out[campaign[:10].rstrip("-_")] = [
                    Measurement(m.t, m.u, m.y, {}, m.source, [], dict(m.units)) for m in map(load_measurement, paths)
                ]
    return out


def verdict(method: str, runs: list[Measurement], rules: Rules = RULES) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if method.startswith("v3"):
            from host.diagnose.v3 import diagnose_runs

            d = diagnose_runs(runs if method == "v3" else [end_to_end(runs)], rules=rules)
            return "+".join([d.cause, *(g for g, _ in d.further)])  # the named cause, then those confirmed beyond it
        from host.diagnose.run import diagnose

        return diagnose(end_to_end(runs), progress=False).cause


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=5, help="decoy seeds per (source, shape) (default 5)")
    parser.add_argument("--hil-records", type=int, default=2, help="effect-free HIL recordings (default 2)")
    parser.add_argument("--sources", default="hil,real", help="hil, real or both (default)")
    parser.add_argument("--methods", default="v2,v3,v3-1", help="v2, v3, v3-1 (default: all three)")
    parser.add_argument("--only", default="", help="sources whose name contains this (e.g. 31-03)")
    parser.add_argument("--shapes", default=",".join(SHAPES), help="decoy shapes (default: all)")
    parser.add_argument("--surrogates", choices=("current", "plain"), default="current")
    parser.add_argument("--column-vs-drift", action="store_true", help="the second proposal (module docstring)")
    parser.add_argument("--inject", type=float, default=0.0, help="a real temperature effect (share of y's p-p)")
    parser.add_argument(
        "--rules", default="", help="v3 Rules overrides, field=value,... (as bench/diagnose_v3_dump.py)"
    )
    args = parser.parse_args(argv)
    from bench.diagnose_v3_dump import overridden

    rules = overridden(args.rules, RULES)
    sources: dict[str, list[Measurement]] = {}
    if "hil" in args.sources:
        sources.update(hil_sources(args.hil_records))
    if "real" in args.sources:
        real = real_sources()
        if not real:
            print(f"(no real campaigns under {DATA}: real rows skipped)", file=sys.stderr)
        sources.update(real)
    sources = {k: v for k, v in sources.items() if args.only in k}
    methods = args.methods.split(",")
    if args.surrogates == "plain":
        import host.diagnose.conditional as conditional

        conditional.column_copies = plain_copies  # type: ignore[assignment]
    if args.column_vs_drift:
        import host.diagnose.v3 as v3

        v3.held_out = held_out_beyond_drift  # type: ignore[assignment]
    target = "temperature_drift"
    injected = f"inject {args.inject}" if args.inject else "decoys"
    print(f"column vs drift: {args.column_vs_drift}; surrogates: {args.surrogates}; {injected}")
    wall, cpu = time.perf_counter(), time.process_time()
    print(f"{'source':<10} {'shape':<12} {'method':<6} {'named temperature':>18}  verdicts (+: also confirmed)")
    totals = {m: [0, 0, 0] for m in methods}
    for name, runs in sources.items():
        for shape in args.shapes.split(","):
            for method in methods:
                if method == "v3-1" and len(runs) == 1:
                    continue
                causes = [
                    verdict(method, with_decoy(runs, shape, seed, args.inject), rules) for seed in range(args.seeds)
                ]
                hits = sum(c.split("+")[0] == target for c in causes)
                totals[method][0] += hits
                totals[method][1] += len(causes)
                totals[method][2] += sum(target in c.split("+") for c in causes)
                print(
                    f"{name:<10} {shape:<12} {method:<6} {hits:>12}/{len(causes):<5}  {', '.join(causes)}", flush=True
                )
    for method, (hits, n, anywhere) in totals.items():
        what = "name the real temperature effect" if args.inject else "name the decoy (target <= 10 %)"
        print(
            f"total {method}: {hits}/{n} {what} ({hits / max(n, 1):.0%}); named or confirmed beyond it {anywhere}/{n}"
        )
    usage = resource.getrusage(resource.RUSAGE_SELF)
    print(
        f"time: {time.perf_counter() - wall:.0f} s wall, {time.process_time() - cpu:.0f} s CPU, "
        f"peak {usage.ru_maxrss / 1024:.0f} MB"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
