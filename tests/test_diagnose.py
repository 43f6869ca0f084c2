"""pmactl diagnose in the default run: the decision rule on fold scores, the CLI contract, refusals.

Whole diagnoses on the plant family (tuning and held-out plants, bench/plants) are the slow
scorecard: tests/test_diagnose_family.py (``-m slow``) and bench/diagnose_scorecard.py.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

from edge.errors import DataError
from hil.record import record, write_recording
from host.cli import main
from host.data import Measurement, load_measurement
from host.diagnose.decide import COLUMN_GAIN_FLOOR, GAIN_FLOOR, CandidateScore, DecisionInputs, choose, distinct
from host.diagnose.features import branch_offset
from host.diagnose.run import CAUSES, DecimatedWarning, decimated, diagnose
from host.diagnose.signatures import Signature
from host.identify.common import MemoryStart


def scored(cause: str, gains: list[float], base: float = 1.0) -> CandidateScore:
    score = CandidateScore(cause)
    for g in gains:
        score.add(base, base * (1.0 - g))
    return score


def verdict(noise: float = 0.0, **gains: list[float]):
    scores = {c: scored(c, gains.get(c, [0.0, 0.001, -0.001, 0.0])) for c in CAUSES}
    return distinct(choose(scores, noise), scores)


def test_a_consistent_gain_is_named_with_its_margins():
    v = verdict(creep=[0.40, 0.45, 0.42, 0.38], transport_delay=[0.05, 0.06, 0.04, 0.05])
    assert v.cause == "creep"
    assert v.confidence["runner_up"] == "transport_delay"
    assert v.confidence["over_runner_up"] == pytest.approx(0.4125 - 0.05)
    assert v.confidence["over_threshold"] > 0


def test_gains_the_folds_do_not_agree_on_are_not_evidence():
    v = verdict(creep=[1.24, -0.08, -0.08, -0.04])  # one lucky fold: mean 26 %, spread 65 %
    assert v.cause == "none" and "do not agree" in v.reason
    v = verdict(creep=[0.50, 0.48, -0.15, 0.51])  # one part of the record contradicts it
    assert v.cause == "none" and "contradicts" in v.reason
    v = verdict(creep=[0.15, 0.16, 0.17, 0.15])  # consistent but below the calibrated floor
    assert v.cause == "none" and "below" in v.reason
    assert v.confidence["over_threshold"] < 0


def test_a_fit_that_blows_up_on_a_fold_is_a_failed_fit_not_evidence_against():
    v = verdict(creep=[0.30, 0.28, -49.0, 0.31])  # -4900 %: the extension diverged on one fold
    assert v.cause == "creep" and "failed fold left out" in v.reason
    v = verdict(creep=[0.30, -20.0, -49.0, 0.31])
    assert v.cause == "none" and "blew up" in v.reason


def test_a_gain_at_the_noise_floor_is_not_evidence():
    # +30 % of a baseline at 1.0 with a noise floor of 1.5 (as an overestimated floor can be:
    # above the floor, a gain of GAIN_FLOOR is also a reduction of more than NOISE_SHARE x noise)
    gains = [0.30, 0.31, 0.30, 0.305]
    assert verdict(noise=0.0, rate_dependence=gains).cause == "rate_dependence"
    v = verdict(noise=1.5, rate_dependence=gains)
    assert v.cause == "none" and "noise floor" in v.reason


def test_an_observed_cause_must_beat_a_slow_drift_of_the_same_flexibility():
    drift = [0.34, 0.36, 0.35, 0.33]
    v = verdict(temperature_drift=[0.35, 0.36, 0.35, 0.34], slow_drift=drift)
    # nor is it a drift no column explains: the record cannot tell the two apart
    assert v.cause == "none" and "cannot tell slow_drift" in v.reason
    assert v.confidence["undecided_between"] == ["slow_drift", "temperature_drift"]
    v = verdict(temperature_drift=[0.55, 0.56, 0.50, 0.53], slow_drift=drift)
    assert v.cause == "temperature_drift" and "slow drift" in v.decided_by


def test_a_drift_that_shifted_copies_of_time_explain_as_well_is_not_named():
    drift = [0.34, 0.36, 0.35, 0.33]
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["slow_drift"] = scored("slow_drift", drift)
    scores["slow_drift"].null_gains = [0.02, 0.05, 0.36, -0.1, 0.0, 0.03, 0.01, 0.04, 0.02]
    v = choose(scores, 0.0)
    assert v.cause == "none" and "every shifted copy of the ramp in time" in v.reason
    assert v.confidence["surrogate_p"] == {"slow_drift": pytest.approx(0.2)}
    scores["slow_drift"].null_gains = [0.02, 0.05, 0.3, -0.1, 0.0, 0.03, 0.01, 0.04, 0.02]
    assert choose(scores, 0.0).cause == "slow_drift"


def test_the_drift_null_is_asked_for_only_when_the_drift_would_be_named():
    from host.diagnose.decide import drift_would_be_named

    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    assert not drift_would_be_named(scores, 0.0)  # the drift does not pass
    scores["slow_drift"] = scored("slow_drift", [0.34, 0.36, 0.35, 0.33])
    assert drift_would_be_named(scores, 0.0)
    scores["creep"] = scored("creep", [0.50, 0.48, 0.51, 0.49])  # a physical cause passes: it wins
    assert not drift_would_be_named(scores, 0.0) and choose(scores, 0.0).cause == "creep"


def test_the_drift_yardstick_ignores_folds_where_either_fit_failed_and_needs_two_folds():
    from host.diagnose.decide import why_not

    load = scored("load_dependence", [0.35, 0.34, 0.36])
    drift = scored("slow_drift", [0.40, -4.0, 0.41])  # the drift blew up on fold 2
    reason = why_not(load, 0.0, drift)  # behind the drift on both folds where both fits held
    assert reason is not None and "slow drift" in reason
    one_fold = {c: scored(c, [0.0, 0.001]) for c in CAUSES}
    one_fold["creep"] = scored("creep", [0.50, -9.0])  # one valid fold of two
    v = choose(one_fold, 0.0)
    assert v.cause == "none" and "fewer than two folds" in v.reason


def test_non_finite_numbers_become_null_in_the_json():
    from host.diagnose.run import finite_or_null

    payload = {"fold_gains": {"creep": [0.1, float("nan"), float("-inf")]}, "gain": np.float64(0.2)}
    out = finite_or_null(payload)
    assert out == {"fold_gains": {"creep": [0.1, None, None]}, "gain": 0.2}
    json.dumps(out, allow_nan=False)


def test_a_column_named_for_its_confound_with_time_needs_the_floor_of_a_term_without_a_null():
    # its shifted copies follow time too, so the null that lets a column pass at 15 % is void
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["slow_drift"] = scored("slow_drift", [0.40, 0.42, 0.41, 0.40])
    scores["temperature_drift"] = scored("temperature_drift", [0.18, 0.19, 0.18, 0.17])
    assert choose(scores, 0.0, {"temperature": 0.98}).cause == "slow_drift"
    scores["temperature_drift"] = scored("temperature_drift", [0.30, 0.31, 0.30, 0.29])
    assert choose(scores, 0.0, {"temperature": 0.98}).cause == "temperature_drift"


def test_a_temperature_that_follows_time_is_named_with_the_confound():
    drift = [0.34, 0.36, 0.35, 0.33]
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["slow_drift"] = scored("slow_drift", drift)
    scores["temperature_drift"] = scored("temperature_drift", [0.35, 0.36, 0.35, 0.34])
    assert choose(scores, 0.0, {"temperature": 0.3}).cause == "slow_drift"
    assert distinct(choose(scores, 0.0, {"temperature": 0.3}), scores).cause == "none"  # cannot tell
    v = distinct(choose(scores, 0.0, {"temperature": 0.97}), scores)  # the confound is the stated doubt
    assert v.cause == "temperature_drift" and "confounded" in v.decided_by and "r = +0.97" in v.reason


def test_observed_causes_do_not_win_by_rank_against_a_stronger_dynamic_cause():
    v = verdict(creep=[0.55, 0.50, 0.52, 0.56], temperature_drift=[0.34, 0.33, 0.35, 0.34])
    assert v.cause == "creep"


def test_a_measured_column_has_a_lower_floor_than_a_term_without_a_null_of_its_own():
    gains = [0.18, 0.19, 0.17, 0.18]  # between COLUMN_GAIN_FLOOR and GAIN_FLOOR
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["load_dependence"] = scored("load_dependence", gains)
    scores["load_dependence"].null_gains = [0.02 * k for k in range(9)]  # every copy gains less
    v = distinct(choose(scores, 0.0), scores)
    assert v.cause == "load_dependence" and v.confidence["threshold"] == COLUMN_GAIN_FLOOR
    scores["load_dependence"].null_gains[-1] = 0.20  # a copy of the column explains as much
    assert distinct(choose(scores, 0.0), scores).cause == "none"
    v = verdict(creep=gains)  # a dynamic term has no null but the calibrated floor
    assert v.cause == "none" and f"below {GAIN_FLOOR:.0%}" in v.reason


def test_a_rate_term_that_a_linear_lag_explains_as_well_is_not_rate_dependence():
    rate = [0.38, 0.40, 0.37, 0.39]
    v = verdict(rate_dependence=rate, output_lag=[0.37, 0.39, 0.36, 0.38])
    assert (
        v.cause == "none"
        and "linear mechanics after the hysteresis (a lag or a fixed payload) explain as much" in v.reason
    )
    assert "baseline's dynamics are incomplete" in v.reason  # the lag itself is reported, not named
    assert verdict(rate_dependence=rate, output_lag=[0.10, 0.11, 0.09, 0.12]).cause == "rate_dependence"
    assert verdict(output_lag=[0.30, 0.31, 0.29, 0.30]).cause == "none"  # a yardstick is never the verdict


def test_a_speed_dependent_lag_that_ties_a_dead_time_is_not_a_verdict():
    tie = verdict(transport_delay=[0.40, 0.42, 0.41, 0.40], rate_dependence=[0.38, 0.40, 0.39, 0.37])
    assert tie.cause == "none" and "cannot tell transport_delay" in tie.reason
    assert "vanishes when the output stops" in tie.reason  # what to record to separate them
    clear = verdict(transport_delay=[0.60, 0.62, 0.61, 0.60], rate_dependence=[0.30, 0.31, 0.29, 0.30])
    assert clear.cause == "transport_delay" and "persists" in clear.decided_by


def test_json_carries_the_verdict_its_confidence_and_the_report_is_written(tmp_path, capsys):
    rec = record("mixed", 11, 120.0, "transport_delay")
    data = write_recording(rec, tmp_path / "d.csv")
    out = tmp_path / "out" / "d.json"
    assert main(["diagnose", str(data), "--json", str(out), "--report", str(tmp_path / "report")]) == 0
    result = json.loads(out.read_text())
    assert {"cause", "reason", "decided_by", "confidence", "scores", "gain", "extended_model"} <= set(result)
    assert set(result["scores"]) == set(CAUSES)
    assert {"over_threshold", "over_runner_up", "runner_up"} <= set(result["confidence"])
    assert result["cause"] in (*CAUSES, "none")
    # a mixed protocol has reversals: the dead-time signature is always reported, with its p-value
    assert 0.0 < result["signatures"]["transport_delay"]["p_value"] <= 1.0
    assert set(result["confidence"]["signature_p"]) == set(result["signatures"])
    assert result["extended_model"]["name"] in (result["cause"], "baseline (no extension)")
    for name in ("report.md", "loops.png", "residuals.png", "scores.png"):
        assert (tmp_path / "report" / name).stat().st_size > 1000
    assert f"cause {result['cause']}" in capsys.readouterr().out


def write_csv(path, rows, header="t,u,y"):
    path.write_text(header + "\n" + "\n".join(",".join(f"{v:g}" for v in row) for row in rows) + "\n")
    return path


@pytest.fixture
def small_csv(tmp_path):
    t = np.arange(3000) * 0.01
    u = 2 + 2 * np.sin(0.5 * t)
    return write_csv(tmp_path / "small.csv", zip(t, u, 10 * u + np.sin(3 * t)))


@pytest.mark.parametrize("folds", ["0", "1", "-3", "1000"])
def test_impossible_fold_counts_are_one_line_and_exit_2(small_csv, capsys, folds):
    assert main(["diagnose", str(small_csv), "--folds", folds]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--folds" in err[0] and "use 2-" in err[0]


def test_a_constant_output_is_refused_in_one_line(tmp_path, capsys):
    t = np.arange(2000) * 0.01
    path = write_csv(tmp_path / "flat.csv", zip(t, np.sin(t), np.full_like(t, 3.0)))
    assert main(["diagnose", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "output y is constant" in err[0]


def test_too_short_is_a_clear_error(tmp_path):
    t = np.arange(100) * 0.01
    path = write_csv(tmp_path / "short.csv", zip(t, np.sin(t), np.sin(t)))
    with pytest.raises(DataError, match="too short to diagnose"):
        diagnose(load_measurement(path))


def test_a_record_that_reaches_its_range_ends_late_is_diagnosed_with_the_state_it_assumes(tmp_path, capsys):
    # a sine of growing amplitude (a piezo excerpt, a ramped-up test): its extremes come in the
    # last cycle, so no memory is known before; the state is assumed and the report says so
    from edge.hysteresis.pi import play_outputs

    t = np.arange(3000) * 0.01
    u = 2.0 + (0.2 + 0.8 * t / t[-1]) * np.sin(2 * np.pi * 0.4 * t)
    y = 10.0 * play_outputs(u, np.array([0.15]), np.array([u[0]]))[:, 0]
    y += np.random.default_rng(1).normal(0.0, 0.01, t.size)
    path = write_csv(tmp_path / "growing.csv", zip(t, u, y))
    result = diagnose(load_measurement(path), progress=False)
    assert result.start_index == 0 and "state assumed" in result.holdout
    assert any("rose from the record's minimum" in note for note in result.notes)
    assert result.cause == "none"  # a rate-independent play: the assumption invents no effect
    assert result.as_json()["memory_assumed"] is True
    assert main(["diagnose", str(path)]) == 0
    assert "rose from the record's minimum" in capsys.readouterr().out
    with pytest.raises(DataError, match="reaches the end of its range only at sample"):
        diagnose(load_measurement(path), progress=False, assume_state=False)


def test_the_branch_an_assumed_state_starts_on_is_the_rise_from_the_records_minimum():
    # the Preisach rows of MemoryStart(0, "ascending") rise from the record's minimum; the branch
    # feature must agree: just above the minimum the play has not left the bottom yet (+1, as
    # after a fall), far above it the input rises on the ascending branch (-1)
    u = np.r_[0.02, np.linspace(0.02, 1.0, 50), np.linspace(1.0, 0.0, 50)]
    near = branch_offset(u, MemoryStart(0, "ascending"))
    assert near[0] > 0.7
    far = branch_offset(np.r_[0.9, u[1:]], MemoryStart(0, "ascending"))
    assert far[0] == pytest.approx(-1.0)
    # a true start at the maximum (memory_start's "ascending") is unchanged
    assert branch_offset(np.r_[1.0, u[::-1]], MemoryStart(0, "ascending"))[0] == pytest.approx(-1.0)


def test_a_record_the_diagnosis_refuses_is_a_counted_miss_in_the_scorecards_not_a_crash():
    from bench.diagnose_scorecard import diagnosed, line

    t = np.arange(2000) * 0.01
    row = diagnosed(Measurement(t, np.sin(t), np.full_like(t, 3.0), source="flat"))
    assert row["verdict"] == "refused" and "output y is constant" in str(row["refusal"])
    assert line("", "flat", row).startswith("REFUSED")


def test_constant_input_is_a_clear_error(tmp_path):
    t = np.arange(2000) * 0.01
    path = write_csv(tmp_path / "flat.csv", zip(t, np.ones_like(t), np.sin(t)))
    with pytest.raises(DataError, match="input u is constant"):
        diagnose(load_measurement(path))


def test_nan_rows_are_refused_on_the_command_line(tmp_path, capsys):
    t = np.arange(1000) * 0.01
    rows = [list(r) for r in zip(t, np.sin(t), np.cos(t))]
    rows[500][2] = float("nan")
    path = write_csv(tmp_path / "nan.csv", rows)
    assert main(["diagnose", str(path)]) == 2
    assert "NaN" in capsys.readouterr().err


def test_json_to_stdout_is_pure_json(small_csv, capsys):
    assert main(["diagnose", str(small_csv), "--json", "-"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["cause"] in (*CAUSES, "none")
    assert "cause" in captured.err  # the human summary moves to stderr


def test_a_long_record_is_decimated_with_a_warning_that_says_what_it_costs():
    n = 2_000_000
    t = np.arange(n, dtype=np.float64) * 0.0005
    m = Measurement(t, np.sin(t), np.cos(t), {"load": np.zeros(n)})
    small, note = decimated(m)
    assert note is not None and "dead times shorter than" in note
    q = n // len(small)
    assert len(small) <= 30_000 and small.dt == pytest.approx(m.dt * q, rel=1e-6)
    assert np.allclose(small.u[:3], [np.mean(m.u[i * q : (i + 1) * q]) for i in range(3)])
    with warnings.catch_warnings():
        warnings.simplefilter("error", DecimatedWarning)
        with pytest.raises(DecimatedWarning):
            diagnose(m, progress=False)


def test_the_velocity_squared_lag_trails_a_ramp_by_alpha_v_squared():
    """At constant speed v the element settles alpha v^2 behind its target; it never overshoots."""
    from host.diagnose.features import velocity_squared_lag

    dt, alpha, speed = 0.01, 2e-3, 40.0  # s, s^2/mm, mm/s
    target = np.r_[np.zeros(100), speed * dt * np.arange(1, 501)]
    out = velocity_squared_lag(target, dt, alpha)
    assert target[-1] - out[-1] == pytest.approx(alpha * speed**2, rel=1e-6)
    assert np.all(out <= target + 1e-12) and np.all(np.diff(out) >= 0)
    held = np.r_[target, np.full(300, target[-1])]
    assert velocity_squared_lag(held, dt, alpha)[-1] == pytest.approx(target[-1], abs=1e-3)  # catches up
    assert np.array_equal(velocity_squared_lag(target, dt, 0.0), target)


@pytest.mark.parametrize(("rise_s", "fall_s"), [(0.2, 0.0), (0.05, 0.3), (0.1, 0.1)])
def test_a_direction_dependent_dead_time_delays_each_direction_by_its_own_time(rise_s, fall_s):
    """A trapezoid: the rise arrives rise_s late, the fall fall_s late (first sample past half way)."""
    from host.diagnose.features import direction_delayed

    dt = 0.01
    u = np.r_[np.zeros(100), np.linspace(0.0, 1.0, 101), np.ones(100), np.linspace(1.0, 0.0, 101), np.zeros(200)]
    out = direction_delayed(u, dt, rise_s, fall_s)

    def half_way(x: np.ndarray, rising: bool) -> float:  # s
        segment = slice(0, 250) if rising else slice(250, None)
        k = np.flatnonzero((x[segment] >= 0.5) if rising else (x[segment] <= 0.5))[0] + segment.indices(u.size)[0]
        return k * dt

    assert half_way(out, True) - half_way(u, True) == pytest.approx(rise_s, abs=0.02)
    assert half_way(out, False) - half_way(u, False) == pytest.approx(fall_s, abs=0.02)


@pytest.mark.parametrize("noise", [0.0, 1e-3])
def test_a_move_after_a_hold_starts_after_its_own_dead_time(noise):
    """A hold takes the direction of the move that ends it: a rise after a hold is not held back
    by a longer falling dead time, nor a fall by a longer rising one, and a noisy hold too."""
    from host.diagnose.features import direction_delayed

    dt = 0.01
    hold = np.random.default_rng(3).normal(0.0, noise, 100)
    up = np.r_[hold, np.linspace(0.0, 1.0, 101)]
    out = direction_delayed(up, dt, 0.05, 0.3)
    assert np.flatnonzero(out > 0.5)[0] == pytest.approx(np.flatnonzero(up > 0.5)[0] + 5, abs=2)
    down = np.r_[1.0 + hold, np.linspace(1.0, 0.0, 101)]
    out = direction_delayed(down, dt, 0.3, 0.05)
    assert np.flatnonzero(out < 0.5)[0] == pytest.approx(np.flatnonzero(down < 0.5)[0] + 5, abs=2)


def test_a_fall_that_follows_a_rise_without_a_hold_waits_for_the_rise_to_arrive():
    """Nothing overtakes what was sent before it: with a late rise and a prompt fall, the turn
    arrives after the rise's dead time and the fall follows at once."""
    from host.diagnose.features import direction_delayed

    dt = 0.01
    u = np.r_[np.linspace(0.0, 1.0, 101), np.linspace(1.0, 0.0, 101)[1:]]
    out = direction_delayed(u, dt, 0.3, 0.05)
    assert int(np.argmax(out)) == pytest.approx(100 + 30, abs=2)
    assert out.max() == pytest.approx(1.0, abs=0.02)


def test_a_column_term_is_judged_only_inside_the_columns_training_range():
    from host.diagnose.candidates import Design

    temperature = np.linspace(20.0, 40.0, 400)
    d = Design("temperature_drift", np.zeros(400), np.zeros((400, 0)), [], np.zeros(0), source=temperature)
    held = np.zeros(400, dtype=bool)
    held[:100] = True  # the coolest quarter: below everything the training rows saw
    held[200:300] = True  # inside
    scored = d.scored(~held, held)
    assert not scored[:100].any() and scored[200:300].all() and not scored[100:200].any()
    assert np.array_equal(Design("creep", np.zeros(400), np.zeros((400, 0)), [], np.zeros(0)).scored(~held, held), held)


def test_noise_floor_reads_the_white_noise_not_the_signal():
    from host.diagnose.folds import noise_floor

    rng = np.random.default_rng(0)
    t = np.arange(20_000) * 0.01
    assert noise_floor(20 * np.sin(0.3 * t) + rng.normal(0, 0.05, t.size)) == pytest.approx(0.05, rel=0.1)


def test_a_cause_another_term_explains_as_well_is_not_named():
    """Within DISTINCT_MARGIN of another term (a yardstick too) the record cannot tell them apart:
    none, both named in the reason and the confidence, with what to record to separate them."""
    creep = [0.40, 0.42, 0.41, 0.40]
    v = verdict(creep=creep, load_dependence=[0.39, 0.41, 0.40, 0.38], output_lag=[0.38, 0.40, 0.39, 0.39])
    assert v.cause == "none" and v.decided_by == "not distinct from load_dependence"
    assert v.confidence["undecided_between"] == ["creep", "load_dependence", "output_lag"]
    assert "cannot tell creep (+40.8%) from load_dependence (+39.5%)" in v.reason
    assert "load and temperature varied independently" in v.reason  # the general advice for this pair
    clear = verdict(creep=creep, load_dependence=[0.36, 0.38, 0.37, 0.36])  # 4 % behind: distinct
    assert clear.cause == "creep"
    stronger_yardstick = verdict(creep=creep, output_lag=[0.50, 0.52, 0.51, 0.50])  # never named itself
    assert stronger_yardstick.cause == "none" and "explains the held-out error better, so" in stronger_yardstick.reason


def test_only_terms_judged_as_the_cause_was_can_be_its_rivals():
    """A term with one valid fold, or a column no better than its shifted copies, does not make a
    named cause a tie; nor does the drift for a column that beat it on the shared rows."""
    creep = [0.40, 0.42, 0.41, 0.40]
    assert verdict(creep=creep, temperature_drift=[0.45, float("nan")]).cause == "creep"  # one fold
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["creep"] = scored("creep", creep)
    scores["load_dependence"] = scored("load_dependence", [0.40, 0.41, 0.40, 0.39])
    scores["load_dependence"].null_gains = [0.45, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]  # p = 0.2
    assert distinct(choose(scores, 0.0), scores).cause == "creep"
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["load_dependence"] = scored("load_dependence", [0.40, 0.41, 0.40, 0.39])
    scores["load_dependence"].drift_margins = [0.05, 0.04, 0.06, 0.05]  # ahead on the shared rows
    scores["slow_drift"] = scored("slow_drift", [0.39, 0.40, 0.39, 0.38])
    assert distinct(choose(scores, 0.0), scores).cause == "load_dependence"


def test_the_text_output_of_a_tie_names_the_tied_terms_not_the_leading_margins(tmp_path, monkeypatch, capsys):
    """A tie printed with the leading cause's "+x % over its threshold" would read as confidence
    in it; the text names the tied terms and their gains instead."""
    import dataclasses
    from pathlib import Path

    import host.diagnose.run as run

    data = str(Path(__file__).resolve().parent.parent / "host" / "example_data" / "pma_mixed.csv")
    real = diagnose(load_measurement(data), progress=False)
    scores = dict(real.scores, creep=0.43, slow_drift=0.44)
    confidence = dict(real.confidence, undecided_between=["creep", "slow_drift"], over_threshold=0.18)
    tie = dataclasses.replace(real, cause="none", scores=scores, confidence=confidence)
    monkeypatch.setattr(run, "diagnose", lambda *args, **kwargs: tie)
    assert main(["diagnose", data]) == 0
    out = capsys.readouterr().out
    assert "undecided between: creep +43.0%, slow_drift +44.0%" in out
    assert "over its threshold" not in out


def test_the_decision_inputs_round_trip_through_json_to_the_same_verdict():
    """What a verdict is decided from survives JSON (failed folds as -inf, folds without rows as
    nan, drift margins with gaps, surrogate gains, signatures), so a dumped record is decided
    again exactly as the diagnosis decided it (bench/diagnose_replay.py)."""
    scores = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    scores["creep"] = scored("creep", [0.40, 0.42, 0.41])
    scores["creep"].add(1.0, float("inf"))  # a failed fold
    scores["creep"].all_gains.append(float("nan"))  # a fold with no rows it can be judged on
    scores["temperature_drift"] = scored("temperature_drift", [0.30, 0.31, 0.29, 0.30])
    scores["temperature_drift"].null_gains = [0.1] * 9
    scores["temperature_drift"].drift_margins = [0.05, None, 0.04, 0.06]
    found = {"creep": Signature("creep", 3.2, 0.004, "drift during holds")}
    inputs = DecisionInputs(scores, 0.01, {"temperature": 0.2}, found)
    again = DecisionInputs.from_json(json.loads(json.dumps(inputs.as_json())))
    assert again.scores["creep"].all_gains[-2] == -np.inf and np.isnan(again.scores["creep"].all_gains[-1])
    assert again.scores["temperature_drift"].drift_margins == [0.05, None, 0.04, 0.06]
    first, second = inputs.verdict(), again.verdict()
    assert (second.cause, second.reason, second.decided_by) == (first.cause, first.reason, first.decided_by)
    assert first.cause == "creep" and first.decided_by.startswith("signature")


def test_the_replay_bench_scores_a_dump_and_counts_the_verdicts_that_changed(tmp_path, capsys):
    """bench/diagnose_replay.py decides dumped records again: a line whose dumped verdict the
    current rules do not reach is counted as changed; a missing dump is one line and exit 2."""
    from bench.diagnose_replay import main as replay

    clear = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    clear["creep"] = scored("creep", [0.40, 0.42, 0.41, 0.40])
    quiet = {c: scored(c, [0.0, 0.001, -0.001, 0.0]) for c in CAUSES}
    lines = [
        {"family": "f", "index": 0, "case": "a", "effect": "creep", "verdict": "creep", "decision": clear},
        {"family": "f", "index": 1, "case": "b", "effect": "none", "verdict": "creep", "decision": quiet},
        {"family": "f", "index": 2, "case": "c", "effect": "none", "verdict": "refused", "decision": None},
    ]
    dump = tmp_path / "dump.jsonl"
    with dump.open("w") as f:
        for line in lines:
            if line["decision"] is not None:
                line["decision"] = DecisionInputs(line["decision"], 0.0, {}, {}).as_json()
            f.write(json.dumps(line) + "\n")
    assert replay([str(dump), "--changes"]) == 0
    out = capsys.readouterr().out
    assert "f          named   1/1   false alarms  0/2   wrong   0  refused 1  failed 0" in out
    assert "1 of 3 verdicts differ from the dump's" in out and "f/001 b: creep -> none (truth none)" in out
    with pytest.raises(SystemExit) as stop:
        replay([str(tmp_path / "missing.jsonl")])
    assert stop.value.code == 2 and "no such dump" in capsys.readouterr().err


def test_the_replay_bench_refuses_a_dump_it_cannot_read_in_one_line(tmp_path, capsys):
    """A line that is not a dump line names its file and line; a record twice and a family the
    dumps do not hold are refused rather than counted."""
    from bench.diagnose_replay import main as replay

    line = {"family": "f", "index": 0, "case": "a", "effect": "none", "verdict": "refused", "decision": None}
    good = tmp_path / "good.jsonl"
    good.write_text(json.dumps(line) + "\n")
    bad = tmp_path / "bad.jsonl"
    bad.write_text(json.dumps(line) + "\n" + '{"family": "f", "ind')
    for argv, message in (
        ([str(bad)], "bad.jsonl:2: not a JSON line"),
        ([str(good), str(good)], "record f/000 is in the dumps twice"),
        ([str(good), "--set", "f,g"], "--set: g not in the dumps; they hold f"),
    ):
        with pytest.raises(SystemExit) as stop:
            replay(argv)
        assert stop.value.code == 2 and message in capsys.readouterr().err


def test_the_dump_bench_resumes_after_a_cut_line_and_refuses_another_duration_or_code(tmp_path, capsys):
    """An interrupted dump is appended to: a last line cut by the interruption is dropped (its
    record is diagnosed again) and the records before it are skipped; records of another
    duration or code version are not mixed into one dump."""
    import argparse

    from bench.diagnose_dump import resumed

    parser = argparse.ArgumentParser()
    out = tmp_path / "dump.jsonl"
    line = {"family": "f", "index": 3, "case": "a", "effect": "none", "verdict": "none", "decision": None}
    out.write_text(json.dumps({**line, "duration_s": 100.0, "code": "v1"}) + "\n" + '{"family": "f", "in')
    assert resumed(parser, out, 100.0, "v1") == {("f", 3)}
    assert out.read_text().endswith("}\n") and "dropped a last line" in capsys.readouterr().err
    for duration, code, what in ((50.0, "v1", "duration_s 100.0, not 50.0"), (100.0, "v2", "code v1, not v2")):
        with pytest.raises(SystemExit) as stop:
            resumed(parser, out, duration, code)
        assert stop.value.code == 2 and what in capsys.readouterr().err
    with pytest.raises(SystemExit):
        resumed(parser, tmp_path / "no" / "dump.jsonl", 100.0, "v1")
    assert "no such folder" in capsys.readouterr().err
    assert resumed(parser, tmp_path / "new.jsonl", 100.0, "v1") == set()
