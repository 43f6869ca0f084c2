"""Online adaptation: the RLS estimate of the model's output map (offset a, gain b) learns a
shift, stays put without excitation, keeps to its bounds, predicts one step ahead; the rig
applies it to the feedforward, and ``pmactl fit --adapt`` replays it over held-out data."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from edge.control.adapt import AdaptSettings, OutputMapEstimator, replay
from edge.errors import ConfigError
from host.cli import main
from host.examples import example_path
from tests.edge_helpers import fit_bundle, rig_config, runtime

SETTINGS = AdaptSettings(enabled=True, memory_s=5.0)
PIEZO = Path(__file__).resolve().parents[3] / "shared" / "data" / "piezo_dspace"
if not PIEZO.is_dir():
    PIEZO = Path("/work/shared/data/piezo_dspace")


def sweep(n: int, dt: float = 1e-3, span: float = 50.0) -> list[float]:
    """A model output sweeping ``span`` at 0.5 Hz, plus a slower tone (not one fixed shape)."""
    t = np.arange(n) * dt
    return (0.5 * span * (1 + 0.7 * np.sin(2 * np.pi * 0.5 * t) + 0.3 * np.sin(2 * np.pi * 0.13 * t))).tolist()


@pytest.mark.parametrize(("a", "b"), [(3.0, 0.9), (-2.0, 1.15), (0.0, 1.0)])
def test_it_learns_an_offset_and_a_gain(a, b):
    model = sweep(20_000)
    noise = np.random.default_rng(1).normal(0.0, 0.05, len(model))
    estimator = OutputMapEstimator(SETTINGS, 1e-3, 50.0)
    for m, e in zip(model, noise):
        estimator.update(m, a + b * m + e)
    assert estimator.offset_ == pytest.approx(a, abs=0.1) and estimator.gain_ == pytest.approx(b, abs=0.005)
    assert estimator.target(a + b * 20.0) == pytest.approx(20.0, abs=0.2)


def test_a_resting_input_freezes_it_and_a_moving_one_thaws_it():
    estimator = OutputMapEstimator(SETTINGS, 1e-3, 50.0)
    for _ in range(5000):  # the muscle held at 20 mm, the sensor 4 mm off: offset and gain cannot be told apart
        estimator.update(20.0 + 0.01 * math.sin(_), 24.0)
    assert not estimator.excited_ and estimator.updates_ == 0 and (estimator.offset_, estimator.gain_) == (0.0, 1.0)
    for m in sweep(3000):
        estimator.update(m, 4.0 + m)
    assert estimator.excited_ and estimator.updates_ > 2000 and estimator.offset_ == pytest.approx(4.0, abs=0.3)


def test_it_keeps_to_its_bounds_and_resets_to_the_identity():
    estimator = OutputMapEstimator(SETTINGS, 1e-3, 50.0)
    for m in sweep(10_000):
        estimator.update(m, 40.0 + 3.0 * m)  # far beyond a session's drift
    offset_max = SETTINGS.offset_max_share * 50.0
    assert SETTINGS.gain_min <= estimator.gain_ <= SETTINGS.gain_max and abs(estimator.offset_) <= offset_max
    assert estimator.gain_ == SETTINGS.gain_max or estimator.offset_ > 0.99 * offset_max  # held at a bound
    estimator.reset()
    assert (estimator.offset_, estimator.gain_, estimator.updates_, estimator.excited_) == (0.0, 1.0, 0, False)


def test_the_replay_predicts_each_sample_from_the_samples_before_it():
    model = sweep(3000)
    measured = [2.0 + m for m in model]
    first = replay(SETTINGS, 1e-3, 50.0, model, measured, start=100)
    measured[2000] += 100.0  # a spike changes nothing before or at its own sample
    second = replay(SETTINGS, 1e-3, 50.0, model, measured, start=100)
    assert all(math.isnan(v) for v in first[:100]) and first[:2001][100:] == second[:2001][100:]
    assert first[2001] != second[2001]


def test_a_bad_span_is_refused():
    with pytest.raises(ValueError, match="output span"):
        OutputMapEstimator(SETTINGS, 1e-3, 0.0)


def test_adapt_keys_are_checked_and_a_joint_refuses_it():
    with pytest.raises(ConfigError, match=r"\[adapt\] gain_min = 1.5 must be in 0.01..1"):
        rig_config(adapt={"gain_min": 1.5})
    with pytest.raises(ConfigError, match="did you mean 'memory_s'"):
        rig_config(adapt={"memory": 3.0})
    with pytest.raises(ConfigError, match="single muscle only"):
        rig_config("hil-joint.toml", adapt={"enabled": True})


@pytest.fixture(scope="module")
def bundle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fit_bundle(tmp_path_factory.mktemp("bundle") / "preisach")


def test_on_a_shifted_muscle_the_feedforward_tracks_better_with_it(bundle):
    """Feedforward alone (no PID to hide the map), the HIL muscle of another session."""
    errors = {}
    for enabled in (False, True):
        config = rig_config(
            buses={"i2c": {"url": "sim://rig?clock=lockstep&effect=session_shift"}},
            adapt={"enabled": enabled},
            control={"kp_bar_per_mm": 0.0, "ki_bar_per_mm_s": 0.0},
        )
        summary = runtime(bundle, "sine:amplitude=20,frequency=0.2,offset=30", config, settle_s=10.0).run(30.0)
        errors[enabled] = summary.as_dict()
    adapted = errors[True]["adapt"]
    assert errors[True]["rms_error"] < 0.8 * errors[False]["rms_error"]
    assert adapted["offset_mm"] > 0.0 and adapted["gain"] < 1.0  # the session's direction (hil.effects)
    assert "adapt" not in errors[False]


def test_fit_adapt_prints_both_columns_and_needs_a_test(capsys):
    train, test = str(example_path("train")), str(example_path("test"))
    assert main(["fit", "--model", "pi", "--train", train, "--test", test, "--adapt", "--json"]) == 0
    (entry,) = json.loads(capsys.readouterr().out)["tests"]
    assert entry["adapted"]["samples"] > 1000 and math.isfinite(entry["adapted"]["rmse_pct_pp"])
    assert main(["fit", "--model", "pi", "--train", train, "--adapt"]) == 2
    err = capsys.readouterr().err.strip()
    assert "--adapt scores the --test recordings" in err and "\n" not in err


@pytest.mark.skipif(not (PIEZO / "20_hz_no_lp.csv").is_file(), reason="the real piezo data is not here")
def test_on_the_real_piezo_it_brings_the_held_out_error_under_the_target(capsys):
    runs = ["sine50_1", "sine100_1", "tri50_1", "tri100_1", "bigsine_1", "prbn_1"]
    tests = [arg for name in runs for arg in ("--test", str(PIEZO / f"{name}.csv"))]
    args = ["fit", "--model", "pi", "--train", str(PIEZO / "20_hz_no_lp.csv"), *tests, "--adapt", "--json"]
    assert main(args) == 0
    entries = json.loads(capsys.readouterr().out)["tests"]
    adapted = np.mean([e["adapted"]["rmse_pct_pp"] for e in entries])
    plain = np.mean([e["rmse_pct_pp"] for e in entries])
    assert adapted <= 1.3 < plain  # issue 30: <= 1.3 % of p-p (1.93 % plain)
