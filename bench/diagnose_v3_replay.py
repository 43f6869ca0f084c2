"""Replay diagnosis v3's decision rules on a dump of ``bench/diagnose_v3_dump.py``, without refits.

Used by ``python bench/diagnose_replay.py --v3 DUMP.jsonl [--rules A] [--rules B]``: each
``--rules`` (``field=value,...`` overrides of :class:`host.diagnose.rules.Rules`) decides every
record again through :func:`host.diagnose.v3.choose`, the function a live diagnosis uses, and
the tables are printed side by side: per family named, the true cause's unique test passed,
false alarms and the oracle's detections; and for every effect that was not named, the gate
that lost it. Rules that change the decision replay exactly (alpha, the nulls combined, the
ladder, the held-out gates); a rule that changes a fit (levels, lags, nuisance) needs a new dump.
"""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from host.diagnose.conditional import GroupTest
from host.diagnose.heldout import HeldOut, scoring_name
from host.diagnose.rules import CAUSES, Rules
from host.diagnose.v3 import choose, confirmed, decide, passing_columns, with_columns

Line = dict[str, Any]
_EMPTY = np.zeros(0)


def _tests(row: Line, rules: Rules) -> dict[str, GroupTest]:
    """The dumped tests with their p and level recomputed under ``rules`` (alpha; which nulls)."""
    names = list(row["tests"])
    dynamic = [g for g in names if CAUSES[g].kind != "column"]
    out = {}
    for g, t in row["tests"].items():
        by_null = {k: tuple(v) for k, v in t.get("p_by_null", {}).items()}
        used = [
            v
            for k, v in by_null.items()
            if k in ("bootstrap", "surrogates", "chi-square")
            or (k == "permutation" and rules.within_state_null)
            or (k.startswith("composite") and rules.composite_draws > 0)
        ]
        p_u = max((v[0] for v in used), default=t["unique_p"])
        p_m = max((v[1] for v in used), default=t["marginal_p"])
        level = rules.alpha * len(dynamic) / len(names) if g in dynamic else rules.alpha / len(names)
        out[g] = GroupTest(
            g,
            t["df"],
            t["unique_stat"],
            p_u,
            t["marginal_stat"],
            p_m,
            t["unique_share"],
            t["identifiable"],
            t["mde"],
            level,
            t["null"],
        )
    return out


def _richer(row: Line, tests: dict[str, GroupTest]) -> dict[str, GroupTest]:
    out = {}
    for g, r in row["richer"].items():
        t = tests[g]
        out[g] = GroupTest(g, t.df, r["unique_stat"], r["unique_p"], 0.0, 1.0, 0.0, 0.0, 0.0, t.level, "richer rung")
    return out


def _trials(row: Line, rules: Rules) -> dict[str, Any]:
    """The dumped held-out scores the rules ask for (per row, or cluster-robust when dumped both ways)."""
    scoring = scoring_name(rules.heldout_clusters, rules.heldout_whitened)
    by = row.get("trials_by_scoring", {})
    if scoring not in by and scoring != scoring_name(False, False):
        raise SystemExit(f"this dump has no held-out scoring {scoring}: dump it again with bench/diagnose_v3_dump.py")
    return dict(by.get(scoring, row["trials"]))


def _trial(row: Line, g: str, rules: Rules) -> HeldOut:
    h = _trials(row, rules)[g]
    return HeldOut(0.0, 0.0, h["gain"], 0.0, (h["lo"], h["hi"]), 0.0, h["cw_p"], [], _EMPTY, _EMPTY)


def _column_passers(row: Line, tests: dict[str, GroupTest], rules: Rules) -> list[str]:
    """:func:`host.diagnose.v3.column_passers` from the dump (every column's held-out surrogate result)."""
    if not rules.column_heldout_surrogates:
        return []
    found = row.get("heldout_surrogates")
    if found is None:
        raise SystemExit("this dump has no held-out surrogate results: dump it again with bench/diagnose_v3_dump.py")
    results = {g: (r["p"], r["gain"]) for g, r in found.items()}
    return passing_columns(results, tests, lambda g: confirmed(_trial(row, g, rules), rules))


@dataclass
class Replayed:
    verdict: str
    unique_passed: bool  # the true cause's unique test passed at its level
    lost_at: str  # for an effect not named: the gate that lost it


def replay(row: Line, rules: Rules) -> Replayed:
    """The verdict of one dumped record under ``rules``, and where a true effect was lost."""
    tests = _tests(row, rules)
    ranked, _ = decide(tests, rules)
    choice = choose(ranked, tests, lambda: _richer(row, tests), lambda g: _trial(row, g, rules), rules)
    choice = with_columns(choice, _column_passers(row, tests, rules), lambda g: _trial(row, g, rules))
    effect = row["effect"]
    truth = tests.get(effect)
    passed = truth is not None and truth.unique_p <= truth.level
    lost = ""
    if effect != "none" and choice.cause != effect:
        if truth is None:
            lost = "not testable"
        elif not passed:
            lost = "unique test" if truth.marginal_p > truth.level else "unique test (marginal passed)"
        elif effect in choice.rejected:
            h = _trials(row, rules)[effect]
            richer = row["richer"].get(effect)
            ladder = (
                CAUSES[effect].kind == "dynamic"
                and rules.ladder_drop < 1.0
                and richer is not None
                and richer["unique_p"] > truth.level
                and richer["unique_stat"] < (1 - rules.ladder_drop) * truth.unique_stat
            )
            lost = "ladder" if ladder else ("held-out CW" if h["cw_p"] > rules.alpha else "held-out interval")
        else:
            lost = f"outranked by {choice.cause}"
    return Replayed(choice.cause, passed, lost)


def table(rows: list[Line], versions: dict[str, Rules]) -> list[str]:
    """Per family and rules version: named, unique passed, false alarms, oracle; then the gates
    that lost effects and the false alarms' causes."""
    families = list(dict.fromkeys(r["family"] for r in rows))
    results = {name: [replay(r, rules) for r in rows] for name, rules in versions.items()}
    lines = [f"{'family':10} {'rules':14} {'named':>7} {'unique':>7} {'FA':>5} {'oracle':>7} {'med gain':>8}"]
    for family in [*families, "total"]:
        pick = [i for i, r in enumerate(rows) if family in ("total", r["family"])]
        effects = [i for i in pick if rows[i]["effect"] != "none"]
        free = [i for i in pick if rows[i]["effect"] == "none"]
        oracle_known = [i for i in effects if rows[i].get("oracle_p") is not None]
        for name, res in results.items():
            level = versions[name].alpha
            named = [i for i in effects if res[i].verdict == rows[i]["effect"]]
            gains = [rows[i]["trials"][rows[i]["effect"]]["gain"] for i in named]
            oracle = sum(rows[i]["oracle_p"] <= level / len(rows[i]["tests"]) for i in oracle_known)
            lines.append(
                f"{family:10} {name:14} {len(named):3}/{len(effects):<3} "
                f"{sum(res[i].unique_passed for i in effects):3}/{len(effects):<3} "
                f"{sum(res[i].verdict != 'none' for i in free):2}/{len(free):<2} "
                + (f"{oracle:3}/{len(oracle_known):<3}" if oracle_known else "    -  ")
                + f" {np.median(gains) if gains else float('nan'):8.1%}"
            )
    for name, res in results.items():
        lost = Counter(x.lost_at for x, r in zip(res, rows) if r["effect"] != "none" and x.lost_at)
        alarms = Counter(x.verdict for x, r in zip(res, rows) if r["effect"] == "none" and x.verdict != "none")
        lines.append(f"{name}: effects lost at: {dict(lost.most_common())}; false alarms: {dict(alarms.most_common())}")
    return lines
