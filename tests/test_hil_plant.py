"""Physics of the emulated rig: each effect shows only when it is switched on."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from hil.effects import EFFECTS, apply_effect
from hil.plant import PlantParams, Schedule, simulate
from hil.record import FORCE_SCENARIOS, record, truth_path, write_recording
from hil.scenarios import SCENARIOS

BASE = PlantParams()


def sine(frequency_hz: float, cycles: int = 3, amplitude: float = 1.5) -> np.ndarray:
    t = np.arange(int(cycles / frequency_hz / BASE.dt_s)) * BASE.dt_s
    return 2.0 + amplitude * np.sin(2 * np.pi * frequency_hz * t)


def loop_area(params: PlantParams, frequency_hz: float) -> float:
    """Area of the last cycle of contraction [mm] against measured pressure [bar]."""
    out, _ = simulate(sine(frequency_hz), params)
    last = out[-out.shape[0] // 3 :]
    p, y = last[:, 1], last[:, 0]
    return float(abs(np.sum((p[1:] - p[:-1]) * (y[1:] + y[:-1]) / 2)))


def test_static_curve_rises_with_pressure():
    ramp = np.linspace(0.0, 5.0, 50_000)  # 50 s: quasi-static
    out, _ = simulate(ramp, BASE)
    contraction = out[::500, 0]
    assert np.all(np.diff(contraction) > 0)
    assert 0.2 * 400 > contraction[-1] > 0.1 * 400  # 10-20 % of the 400 mm rest length at 5 bar


def test_hysteresis_loop_exists_without_any_effect():
    assert loop_area(BASE, 0.05) > 5.0  # mm * bar: braid friction


def test_loops_widen_with_rate_only_with_rate_dependence():
    plain = loop_area(BASE, 0.5) / loop_area(BASE, 0.05)
    faster_friction = replace(BASE, rate_friction_s_per_m=40.0)
    widened = loop_area(faster_friction, 0.5) / loop_area(faster_friction, 0.05)
    assert plain < 1.3
    assert widened > 1.6


def drift_during_hold(params: PlantParams) -> float:
    """Contraction change [mm] over 20 s at a constant 2.5 bar after a 1 s ramp."""
    commands = np.r_[np.linspace(0.0, 2.5, 1000), np.full(20_000, 2.5)]
    out, _ = simulate(commands, params)
    return float(out[-1, 0] - out[2000, 0])


def test_drift_under_a_hold_only_with_creep():
    assert abs(drift_during_hold(BASE)) < 0.05
    assert drift_during_hold(replace(BASE, creep_fraction=0.06, creep_time_constant_s=10.0)) < -1.0


def test_heavier_load_means_less_contraction_at_the_same_pressure():
    """Ai2019 Fig 9: for the same displacement a heavier load needs more pressure."""
    ramp = np.linspace(0.0, 4.0, 20_000)
    results = []
    for kg in (0.0, 3.5, 7.5):
        out, _ = simulate(ramp, replace(BASE, load=Schedule((0.0,), (kg,))))
        results.append(out[-1, 0])
    assert results[0] > results[1] > results[2]


def test_dead_time_delays_the_pressure_response():
    step = np.r_[np.zeros(100), np.full(1000, 3.0)]
    delayed, _ = simulate(step, replace(BASE, dead_time_s=0.2))
    prompt, _ = simulate(step, BASE)
    first = lambda out: int(np.argmax(out[:, 1] > 0.5))  # noqa: E731
    assert first(delayed) - first(prompt) == 200


def test_temperature_softens_the_muscle():
    from hil.plant import TemperatureProfile

    ramp = np.linspace(0.0, 3.0, 10_000)
    cold, _ = simulate(ramp, BASE)
    warm_params = replace(BASE, temperature=TemperatureProfile(base_c=37.0), elastic_softening_per_k=0.008)
    warm, _ = simulate(ramp, warm_params)
    assert warm[-1, 0] - cold[-1, 0] > 1.0  # softer bladder: more contraction at 3 bar


@pytest.mark.parametrize("effect", EFFECTS)
def test_effect_parameters_are_drawn_reproducibly(effect):
    first = apply_effect(effect, BASE, np.random.default_rng(5), 100.0)
    second = apply_effect(effect, BASE, np.random.default_rng(5), 100.0)
    assert first == second
    assert first[1]["effect"] == effect


@pytest.mark.parametrize("scenario", SCENARIOS)
def test_scenarios_stay_within_the_valve_range(scenario):
    commands = SCENARIOS[scenario](60.0, 1e-3, np.random.default_rng(0))
    assert commands.size == 60_000
    # hysteresis protocols stay within Ai2019's 0-4 bar; force maps use the valve's whole supply
    top = PlantParams().supply_bar if scenario in FORCE_SCENARIOS else 4.0
    assert commands.min() >= 0.0 and commands.max() <= top
    assert np.abs(np.diff(commands)).max() < 0.05  # no steps: joins are continuous


def test_recording_and_truth_sidecar(tmp_path):
    rec = record("holds", seed=4, duration_s=30.0, effect="creep", rate_hz=50.0)
    path = write_recording(rec, tmp_path / "r.csv")
    header = path.read_text().splitlines()[0]
    assert header == "t,u,y,p,load,temperature"
    truth = json.loads(truth_path(path).read_text())
    assert truth["effect"] == "creep" and truth["seed"] == 4
    assert 0.03 <= truth["parameters"]["creep_fraction"] <= 0.10
    from host.data import load_measurement

    m = load_measurement(path)
    assert len(m) == 1500 and m.dt == pytest.approx(0.02)
    again = record("holds", seed=4, duration_s=30.0, effect="creep", rate_hz=50.0)
    np.testing.assert_array_equal(again.y, rec.y)


def test_recorder_refuses_a_rate_that_does_not_divide_the_plant_rate():
    with pytest.raises(ValueError, match="must divide"):
        record("holds", seed=0, duration_s=5.0, rate_hz=300.0)


def test_cli_record(tmp_path, capsys):
    from host.cli import main

    out = tmp_path / "d.csv"
    assert main(["hil", "record", "--scenario", "forc", "--seed", "2", "--duration", "10", "--out", str(out)]) == 0
    assert "1000 samples" in capsys.readouterr().out
    assert truth_path(out).exists()


@pytest.mark.parametrize("effect", [e for e in EFFECTS if e not in ("none", "load_dependence")])
def test_defaults_are_the_middle_of_each_range(effect):
    from hil.effects import EFFECT_RANGES

    _, truth = apply_effect(effect, BASE, None, 100.0)
    for key, (lo, hi) in EFFECT_RANGES[effect].items():
        assert truth["parameters"][key] == pytest.approx((lo + hi) / 2)
