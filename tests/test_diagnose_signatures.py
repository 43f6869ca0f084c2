"""Residual signatures of the diagnosis and the two-stage rule (default run: synthetic arrays, no fits).

Each signature must fire on the effect it names and stay quiet on the look-alike that fooled the
held-out gain (a warming drift for creep, a speed-dependent lag for a dead time, an unrelated
wandering column for load or temperature is caught by the shifted-copy surrogates of the
held-out gain itself, tested here on the decision rule).
"""

from __future__ import annotations

import numpy as np

from host.diagnose.candidates import CAUSES
from host.diagnose.decide import CandidateScore, Verdict, choose, with_signatures
from host.diagnose.signatures import (
    creep_signature,
    dead_time_signature,
    reversal_lags,
)

DT = 0.01


def staircase(rng: np.random.Generator, n_steps: int = 14, hold_s: float = 8.0) -> np.ndarray:
    levels = rng.uniform(0.5, 4.5, n_steps)
    return np.repeat(levels, int(hold_s / DT))


def settle_drift(u: np.ndarray, tau_s: float, share: float) -> np.ndarray:
    """Creep's residual against a model without it: ``share`` of each step still to come, arriving
    with ``tau_s`` (after an up-step the output starts low and rises during the hold)."""
    out = np.zeros_like(u)
    a = 1.0 - np.exp(-DT / tau_s)
    slow = u[0]
    for i, value in enumerate(u):
        slow += a * (value - slow)
        out[i] = share * (slow - value)
    return out


def test_creep_shows_as_drift_with_the_step_and_warming_does_not():
    rng = np.random.default_rng(1)
    u = staircase(rng)
    noise = rng.normal(0, 0.01, u.size)
    creep = creep_signature(settle_drift(u, 10.0, 0.05) + noise, u, DT, 1.0, rng)
    assert creep is not None and creep.p_value <= 0.01, creep
    warming = 0.3 * (1 - np.exp(-np.arange(u.size) * DT / 40.0))  # one direction whatever the step
    quiet = creep_signature(warming + noise, u, DT, 1.0, rng)
    assert quiet is not None and quiet.p_value > 0.05, quiet


def test_creep_signature_needs_holds():
    t = np.arange(0, 60, DT)
    u = 2.5 + 2.0 * np.sin(2 * np.pi * 0.2 * t)
    assert creep_signature(np.zeros_like(u), u, DT, 1.0, np.random.default_rng(0)) is None


def triangles(periods: list[float]) -> np.ndarray:
    parts = []
    for p in periods:
        tt = np.arange(0, p, DT)
        parts.append(1.0 + 3.0 * (1.0 - np.abs(2.0 * tt / p - 1.0)))
    return np.concatenate(parts)


def test_a_dead_time_shifts_every_reversal_and_a_matching_simulation_shows_none():
    rng = np.random.default_rng(2)
    u = triangles(list(rng.uniform(2.0, 12.0, 14)))
    simulated = u.copy()
    shift = 12  # 120 ms at every reversal
    delayed = np.concatenate([np.full(shift, u[0]), u[:-shift]]) + rng.normal(0, 0.005, u.size)
    sig = dead_time_signature(delayed, simulated, u, DT, rng)
    assert sig is not None and sig.p_value <= 0.01 and abs(sig.statistic - 0.12) < 0.03, sig
    lags, speeds = reversal_lags(delayed, simulated, u, DT)
    assert np.all(lags > 0) and speeds.size == lags.size
    same = dead_time_signature(u + rng.normal(0, 0.005, u.size), simulated, u, DT, rng)
    assert same is not None and same.p_value >= 0.5, same


def test_shifted_copies_of_a_column_keep_its_values_and_smoothness_but_not_its_timing():
    from host.diagnose.candidates import shifted_copies

    rng = np.random.default_rng(3)
    t = np.arange(6000, dtype=np.float64) * DT
    warming = 22.0 + 15.0 * (1.0 - np.exp(-t / 20.0))
    copies = shifted_copies(warming, 9, rng)
    assert len(copies) == 9
    for copy in copies:
        assert copy.min() >= warming.min() - 1e-9 and copy.max() <= warming.max() + 1e-9
        # mirrored, not wrapped: no jump bigger than the curve's own steepest step
        assert np.max(np.abs(np.diff(copy))) <= np.max(np.abs(np.diff(warming))) + 1e-9
        assert abs(np.corrcoef(copy, warming)[0, 1]) < 0.999


def scored(cause: str, gains: list[float]) -> CandidateScore:
    s = CandidateScore(cause)
    for g in gains:
        s.add(1.0, 1.0 - g)
    return s


def scores_with(**gains: list[float]) -> dict[str, CandidateScore]:
    return {c: scored(c, gains.get(c, [0.0, 0.001, -0.001, 0.0])) for c in CAUSES}


def sig(cause: str, p: float):
    from host.diagnose.signatures import Signature

    return Signature(cause, 1.0, p, f"synthetic p = {p}")


def test_a_signature_nominates_and_the_held_out_gain_confirms():
    # +7 % on average with one fold against: not enough on its own (worst fold below -10 %)
    scores = scores_with(transport_delay=[0.2, -0.15, 0.12, 0.1])
    held_out_only = choose(scores, 0.0)
    assert held_out_only.cause == "none"
    v = with_signatures(held_out_only, scores, {"transport_delay": sig("transport_delay", 0.002)}, 0.0)
    assert v.cause == "transport_delay" and v.decided_by.startswith("signature")
    assert v.confidence["signature_p"] == {"transport_delay": 0.002}


def test_a_signature_without_held_out_confirmation_names_nothing():
    scores = scores_with(creep=[-0.14, 0.08, 0.01, 0.05])  # mean 0: no confirmation
    v = with_signatures(choose(scores, 0.0), scores, {"creep": sig("creep", 0.005)}, 0.0)
    assert v.cause == "none" and "nominated by its signature" in v.reason


def test_a_measured_column_must_beat_its_shifted_copies():
    scores = scores_with(load_dependence=[0.41, 0.38, 0.39, 0.387])
    scores["load_dependence"].null_gains = [0.05, 0.02, 0.42, 0.0, 0.01, 0.03, 0.04, -0.02, 0.06]
    v = choose(scores, 0.0)
    assert v.cause == "none" and "does not beat every shifted copy of its column" in v.reason
    assert v.confidence["surrogate_p"] == {"load_dependence": 0.2}
    scores["load_dependence"].null_gains = [0.05, 0.02, 0.32, 0.0, 0.01, 0.03, 0.04, -0.02, 0.06]
    v = choose(scores, 0.0)
    assert v.cause == "load_dependence" and "shifted copies" in v.decided_by
    assert isinstance(v, Verdict)


def test_a_signature_verdict_that_another_term_explains_far_better_is_not_named():
    """The two-stage rule may name a weak cause its signature nominates; when another term
    explains the held-out error far better the evidence conflicts, and the reason says so."""
    from host.diagnose.decide import distinct

    scores = scores_with(load_dependence=[0.40, 0.41, 0.39, 0.40], creep=[0.10, 0.11, 0.09, 0.10])
    nominated = with_signatures(choose(scores, 0.0), scores, {"creep": sig("creep", 0.001)}, 0.0)
    assert nominated.cause == "creep"
    v = distinct(nominated, scores)
    assert v.cause == "none" and "explains the held-out error better" in v.reason
    assert v.confidence["undecided_between"] == ["creep", "load_dependence"]
