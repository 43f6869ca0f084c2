"""The diagnosis on the real recordings in ../shared/data (not shipped; skipped when absent).

Usage: python bench/diagnose_real.py [--data ../shared/data] [--report DIR]

Piezo (dSPACE, 10 kHz): the 20 Hz identification run and three 2 s validation runs. Pneumatic
muscle: each log is one ~4 s cycle (~200 samples), too short alone, so a campaign's logs are
joined in file order with time made continuous (each resampled to its own uniform grid first).
Prints one line per record: cause, held-out gain, the mean score of every candidate. Then the
cross-run diagnosis (``pmactl diagnose --train A --test B``): the piezo identified on
``20_hz_no_lp`` and checked on the 50/100 Hz and ``bigsine_1`` runs; the muscle identified on the
18-03 campaign and checked on the 31-03 campaign (the session drift the data README describes).
"""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path

import numpy as np

from host.data import Measurement, load_measurement
from host.diagnose.crossrun import cross_run
from host.diagnose.report import write_report
from host.diagnose.run import diagnose

HERE = Path(__file__).resolve().parent


def joined(folder: Path) -> Measurement:
    """A campaign's logs end to end on one uniform grid (the first log's period)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # each log is resampled; the loader says so
        logs = [load_measurement(path) for path in sorted(folder.glob("*.csv"))]
    dt = logs[0].dt
    u = np.concatenate([np.interp(np.arange(0, m.t[-1] - m.t[0], dt) + m.t[0], m.t, m.u) for m in logs])
    y = np.concatenate([np.interp(np.arange(0, m.t[-1] - m.t[0], dt) + m.t[0], m.t, m.y) for m in logs])
    return Measurement(np.arange(u.size) * dt, u, y, source=f"{folder.name} ({len(logs)} logs joined)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", type=Path, default=HERE.parent.parent / "shared" / "data")
    parser.add_argument("--report", type=Path, help="write a report per record under this directory")
    parser.add_argument("--cross-only", action="store_true", help="only the cross-run diagnoses")
    args = parser.parse_args()
    if not args.data.is_dir():
        raise SystemExit(f"no real data at {args.data}; pass --data")
    piezo = args.data / "piezo_dspace"
    muscle = args.data / "pam_muscle_sensory"
    records: dict[str, Measurement] = {}
    for name in ("20_hz_no_lp", "sine100_1", "prbn_1", "tri50_1"):
        records[f"piezo {name}"] = load_measurement(piezo / f"{name}.csv")
    records["muscle 2026-07-22"] = joined(muscle / "2026-07-22_Literature_Comparison")
    records["muscle 18-03"] = joined(muscle / "18-03-2026_Length_Characterisation")
    both = [joined(muscle / f) for f in ("18-03-2026_Length_Characterisation", "31-03-2026_Length_Characterisation")]
    records["muscle 18-03 + 31-03"] = Measurement(
        np.arange(sum(len(m) for m in both)) * both[0].dt,
        np.concatenate([m.u for m in both]),
        np.concatenate([m.y for m in both]),
        source="18-03 + 31-03 joined",
    )
    print(f"{'record':<24} {'samples':>8} {'cause':<16} {'gain':>6}  scores (mean held-out gain)")
    for name, measurement in ({} if args.cross_only else records).items():
        try:
            result = diagnose(measurement)
        except Exception as exc:  # noqa: BLE001 - a record the diagnosis refuses is reported, not fatal
            print(f"{name:<24} {len(measurement):>8} refused: {exc}")
            continue
        scores = " ".join(f"{k[:5]} {v:+.1%}" for k, v in result.scores.items())
        print(f"{name:<24} {len(measurement):>8} {result.cause:<16} {result.gain:>6.1%}  {scores}")
        print(f"{'':<24} {result.reason}")
        if args.report:
            write_report(result, args.report / name.replace(" ", "_"), measurement.source)

    print("\ncross-run: identified on the first, checked on the second")
    piezo_train = records["piezo 20_hz_no_lp"]
    piezo_tests = [
        load_measurement(piezo / f"{name}.csv")
        for name in ("sine50_1", "sine100_1", "tri50_1", "tri100_1", "bigsine_1")
    ]
    pairs = [(piezo_train, piezo_tests), (both[0], [both[1]])]
    for train, tests in pairs:
        for result in cross_run(train, tests, progress=False):
            scores = " ".join(f"{k} {v:+.1%}" for k, v in result.scores.items())
            print(
                f"{train.source} -> {result.source}: {result.cause}  (raw test RMSE {result.test_rmse:.3g}, "
                f"training {result.train_rmse:.3g})"
            )
            print(f"    {scores}")
            for note in result.notes:
                print(f"    note: {note}")


if __name__ == "__main__":
    main()
