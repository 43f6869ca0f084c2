"""Scorecard of diagnosis v3 (``pmactl diagnose --method v3``) on plant families, on a subset.

Usage: python bench/diagnose_v3_scorecard.py --set tuning[,fresh,...] [--duration S] [--every K]

Scores every K-th case of each family (effect-free records included in the same stride) at the
given record duration, and prints per record the verdict, the held-out gain, the unique-test
p-value of the true cause and CPU seconds; then per family: effects named, false alarms on the
effect-free records, how many true causes passed their unique test on the whole record (before
the held-out confirmation), and the median held-out gain when named.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from host.diagnose.v3 import diagnose_runs  # noqa: E402
from tests.plants.families import FAMILIES, family_names  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", default="tuning")
    parser.add_argument("--duration", type=float, default=60.0, metavar="S")
    parser.add_argument("--every", type=int, default=1, metavar="K")
    args = parser.parse_args(argv)
    for family in family_names(args.set):
        cases_of, record = FAMILIES[family]
        cases = cases_of(args.duration)[:: args.every]
        named = detected = effects = false = nones = 0
        gains, cpu = [], []
        for case in cases:
            m, _ = record(case)
            start = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = diagnose_runs([m])
            cpu.append(time.process_time() - start)
            truth = d.tests.get(case.effect)
            if case.effect == "none":
                nones += 1
                false += d.cause != "none"
            else:
                effects += 1
                named += d.cause == case.effect
                detected += truth is not None and truth.unique_p <= truth.level
                if d.cause == case.effect:
                    gains.append(d.gain)
            p = f"{truth.unique_p:.3f}" if truth else "  -  "
            print(
                f"{case.name:<62} -> {d.cause:<18} gain {d.gain:+6.1%} p_true {p} cpu {cpu[-1]:5.1f}s",
                flush=True,
            )
        print(
            f"\n## {family} (every {args.every}th case, {args.duration:g} s): named {named}/{effects}, "
            f"true cause's unique test passed {detected}/{effects}, false alarms {false}/{nones}, median gain when "
            f"named {np.median(gains) if gains else float('nan'):.1%}, CPU median {np.median(cpu):.1f} s\n",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
