"""Scorecard of diagnosis v3 (``pmactl diagnose --method v3``) on plant families, on a subset.

Usage: python bench/diagnose_v3_scorecard.py --set tuning[,fresh,...] [--duration S] [--every K]
       [--composite-draws N]

Scores every K-th case of each family (effect-free records included in the same stride) at the
given record duration, and prints per record the verdict, the held-out gain, the unique-test
p-value of the true cause and CPU seconds; then per family: effects named, false alarms on the
effect-free records, how many true causes passed their unique test on the whole record (before
the held-out confirmation), and the median held-out gain when named. For families whose module
can simulate a case with and without its effect (every family but tuning), also how many effects
the *oracle's* own test detects at the method's level: the effect's true noise-free waveform as
one regressor, tested beyond the baseline (whitened, block-bootstrap calibrated, at the level of
one cause); "detectable" means that, not a floor.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bench.plants import engine  # noqa: E402
from bench.plants.families import FAMILIES, family_names  # noqa: E402
from bench.plants.registry import specs  # noqa: E402
from host.data import Measurement  # noqa: E402
from host.diagnose.actuator import with_actuator  # noqa: E402
from host.diagnose.conditional import block_length, orthonormal, stationary_draws, whitened  # noqa: E402
from host.diagnose.rules import RULES  # noqa: E402
from host.diagnose.runs import run_set  # noqa: E402
from host.diagnose.v3 import diagnose_runs, score  # noqa: E402


def oracle_p(m: Measurement, waveform: np.ndarray, tests: int) -> float:
    """Block-bootstrap p of the true effect waveform as one regressor beyond v3's baseline, at the
    level of one of ``tests`` causes (returned p is compared with alpha / tests by the caller)."""
    rs = with_actuator(run_set([m], RULES.max_rows, RULES.min_samples), RULES)  # the baseline diagnose_runs uses
    wave = run_set([Measurement(m.t, m.u, waveform, {}, m.source)], RULES.max_rows, RULES.min_samples).y
    base = score(rs, RULES.preisach_levels, RULES, 0)[0]
    w = whitened(rs, base, RULES)
    u = orthonormal(w.prepare(wave[:, None]))
    e = w.residual
    stat = float(np.sum((u.T @ e) ** 2))
    draws = e[stationary_draws(e.size, block_length(e), 199, np.random.default_rng(0))]
    null = np.sum((u.T @ draws) ** 2, axis=0) * (e @ e / e.size) / np.mean(draws**2, axis=0)
    return float((1 + np.sum(null >= stat)) / 200)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--set", default="tuning")
    parser.add_argument("--duration", type=float, default=60.0, metavar="S")
    parser.add_argument("--every", type=int, default=1, metavar="K")
    parser.add_argument(
        "--composite-draws",
        type=int,
        default=RULES.composite_draws,
        metavar="N",
        help="simulated records per effect-free class of the composite null (0: off, the v3.0 tests)",
    )
    args = parser.parse_args(argv)
    rules = replace(RULES, composite_draws=args.composite_draws)
    for family in family_names(args.set):
        cases_of, record = FAMILIES[family]
        cases = cases_of(args.duration)[:: args.every]
        named = detected = effects = false = nones = oracle_yes = oracle_known = 0
        relaxed_named = relaxed_false = 0
        spec = specs().get(family)  # the engine simulates a case with and without its effect
        gains, cpu = [], []
        for case in cases:
            m, _ = record(case)
            start = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                d = diagnose_runs([m], rules=rules)
            cpu.append(time.process_time() - start)
            truth = d.tests.get(case.effect)
            # the verdict had Clark-West p <= alpha alone confirmed a cause (no interval gate): the
            # first trial in order that passes it (at or before the strict one)
            relaxed = next((g for g, h in d.trials.items() if h.clark_west_p <= RULES.alpha), "none")
            if case.effect == "none":
                nones += 1
                false += d.cause != "none"
                relaxed_false += relaxed != "none"
            else:
                effects += 1
                named += d.cause == case.effect
                relaxed_named += relaxed == case.effect
                detected += truth is not None and truth.unique_p <= truth.level
                if d.cause == case.effect:
                    gains.append(d.gain)
            p = f"{truth.unique_p:.3f}" if truth else "  -  "
            oracle = ""
            if case.effect != "none" and spec is not None:
                try:
                    sim = engine.simulate(spec, case)
                except (TypeError, KeyError):  # a family whose cases the engine does not simulate
                    sim = {}
                if "on" in sim and "off" in sim and np.size(sim["on"]) == m.y.size:
                    p_oracle = oracle_p(m, np.asarray(sim["on"] - sim["off"], dtype=np.float64), len(d.tests))
                    oracle_known += 1
                    oracle_yes += p_oracle <= RULES.alpha / len(d.tests)
                    oracle = f" p_oracle {p_oracle:.3f}"
            print(
                f"{case.name:<62} -> {d.cause:<18} (CW only: {relaxed:<18}) "
                f"gain {d.gain:+6.1%} p_true {p} cpu {cpu[-1]:5.1f}s{oracle}",
                flush=True,
            )
        print(
            f"\n## {family} (every {args.every}th case, {args.duration:g} s): named {named}/{effects}, "
            f"true cause's unique test passed {detected}/{effects}, false alarms {false}/{nones}, median gain when "
            f"named {np.median(gains) if gains else float('nan'):.1%}, CPU median {np.median(cpu):.1f} s"
            + (f", oracle detects {oracle_yes}/{oracle_known}" if oracle_known else "")
            + f"; with Clark-West alone as the held-out gate: named {relaxed_named}/{effects}, "
            f"false alarms {relaxed_false}/{nones}" + "\n",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
