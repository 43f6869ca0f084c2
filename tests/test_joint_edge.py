"""The joint on the edge: ``sim://joint`` behind the same ports, the joint control law, Schreiber's
comparisons (Fig 11 steps, a sine tracking table), PID alone vs PID + inverse-Preisach
feedforward, and the command line.

The Preisach bundle is fitted on a FORC recording with seed 0; the closed loops run on the
emulator with another seed (other sensor noise), in lockstep, 20 s of sine and 10 s per step.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from edge.control.tick import Readings
from edge.errors import BundleError, ConfigError
from edge.runtime.safety import State
from tests.edge_helpers import rig_config, runtime
from tests.joint_helpers import (
    HIL_JOINT,
    JOINT_SINE,
    JointRun,
    fit_joint_bundle,
    joint_config,
    run_joint,
    step_metrics,
)

RUN_URL = "sim://joint?clock=lockstep&seed=3"
EQ8 = {"feedback": "eq8", "kp": 1.0, "ki_per_s": 10.0}  # Schreiber eq 8's sum, at its best gains
ADC_DEG = 2e-3 * 54.545454  # one ADS1015 count at 4.096 V full scale, in deg of the angle channel


@pytest.fixture(scope="module")
def bundle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fit_joint_bundle(tmp_path_factory.mktemp("joint"))


def precondition_and_step(path: Path, start: float, target: float) -> str:
    """A wiping cycle (0 -> 20 -> -20 deg), a hold at ``start``, then a step at 6 s to ``target``
    [deg]: the hysteresis memory is the same for both controllers when the step comes."""
    path.write_text(f"t,y_ref\n0,0\n1,20\n2.5,-20\n3.5,{start}\n6,{start}\n6.001,{target}\n10,{target}\n")
    return str(path)


def test_sim_joint_reads_the_joint_and_vents_both_valves(bundle, tmp_path):
    config = joint_config(RUN_URL)
    rt = runtime(bundle, "const:value=10", config=config)
    hil = rt.rig.device.rig
    summary = rt.run(3.0)
    assert summary.faults == [] and summary.as_dict()["unit"] == "deg"
    frame = rt.frame
    assert frame.angle_deg == pytest.approx(hil.true_angle_deg(), abs=ADC_DEG + 0.05)
    assert frame.angle_deg == pytest.approx(10.0, abs=0.5)
    outputs = hil.outputs()
    assert frame.pressure_bar == pytest.approx(outputs.pressure_bar, abs=0.05)
    assert frame.pressure_b_bar == pytest.approx(outputs.pressure_b_bar, abs=0.05)
    assert outputs.pressure_bar > outputs.pressure_b_bar  # muscle A holds the positive angle
    assert hil.command_bar == 0.0 and hil.command_b_bar == 0.0  # the run's end vented both


def test_an_estop_vents_both_valves(bundle):
    config = joint_config("sim://joint?clock=lockstep&faults=estop@1.0")
    rt = runtime(bundle, "const:value=10", config=config)
    summary = rt.run(2.0)
    assert summary.faults and "e-stop" in summary.faults[0]
    assert rt.frame.u_bar == 0.0 and rt.frame.valve_b_bar == 0.0


def test_overpressure_in_the_second_muscle_trips_and_vents_both_valves(bundle):
    """Muscle B's pressure is held to pressure_max_bar like muscle A's (a review found it unchecked)."""
    rt = runtime(bundle, "const:value=10", config=joint_config(RUN_URL))
    frame, supervisor = rt.frame, rt.supervisor
    supervisor.arm(Readings(0.0, 1.0))
    frame.t, frame.angle_deg, frame.pressure_bar, frame.pressure_b_bar = 0.01, 0.0, 1.0, 25.0
    frame.estop, frame.lateness_us = 0.0, 0.0
    supervisor.step(frame, 0.002)
    rt.rig.close()
    assert supervisor.state is State.SAFE and "pressure_b" in str(supervisor.fault)
    assert frame.u_bar == 0.0 and frame.valve_b_bar == 0.0 and frame.valve_enable == 0.0


def test_every_joint_frame_starts_unread_and_has_only_its_own_columns():
    """Building one joint layout must not change the next (a shared module list was appended to)."""
    from edge.runtime.frame import frame_layout

    config = joint_config(RUN_URL)
    first, second = frame_layout(config.rig), frame_layout(config.rig)
    assert first.dtype == second.dtype and first.channel_fields == second.channel_fields
    assert math.isnan(second.new().angle_deg)


def test_joint_config_mistakes_are_one_line():
    with pytest.raises(ConfigError, match="valve_b missing; the joint loop needs"):
        _without_valve_b()
    with pytest.raises(ConfigError, match="both contraction and angle"):
        joint_config(channels={"contraction": {"device": "adc", "input": 3, "unit": "mm"}})
    with pytest.raises(ConfigError, match=r"\[joint\] a muscle cannot pull"):
        joint_config(joint={"pretension_n": 5000.0})
    with pytest.raises(ConfigError, match="unit 'mm': the controller works in deg"):
        joint_config(channels={"angle": {"unit": "mm"}})


def _without_valve_b() -> None:
    import tomllib

    from edge.runtime.config import config_from_dict

    raw = tomllib.loads(HIL_JOINT.read_text())
    del raw["channels"]["valve_b"], raw["devices"]["dac_b"]
    config_from_dict(raw, "hil-joint.toml")


def test_bundles_in_the_wrong_units_are_refused(bundle):
    with pytest.raises(BundleError, match="deg -> deg, the edge needs bar -> mm"):
        runtime(bundle, config=rig_config())  # the joint's map on the single muscle


def sine_table(bundle: Path, tmp_path: Path, **joint: object) -> dict[str, dict[str, float]]:
    table = {}
    for name, feedforward in (("PID", False), ("PID + inverse Preisach", True)):
        config = joint_config(RUN_URL, joint=joint)
        run = run_joint(bundle, JOINT_SINE, tmp_path / f"{feedforward}.pmt", 20.0, feedforward, 5.0, config)
        assert run.summary["faults"] == []
        table[name] = {k: float(run.summary[k]) for k in ("max_error", "mean_abs_error", "rms_error")}  # type: ignore[arg-type]
    return table


@pytest.mark.parametrize("joint", [{}, EQ8], ids=["through_model", "eq8"])
def test_feedforward_halves_the_sine_tracking_error(bundle, tmp_path, joint):
    """Schreiber's tracking comparison: 15 sin(2 pi 0.2 t) deg, scored after 5 s."""
    table = sine_table(bundle, tmp_path, **joint)
    pid, ff = table["PID"], table["PID + inverse Preisach"]
    print("\n| | max [deg] | mean abs [deg] | RMS [deg] |\n|---|---:|---:|---:|")
    for name, row in table.items():
        print(f"| {name} | {row['max_error']:.2f} | {row['mean_abs_error']:.2f} | {row['rms_error']:.3f} |")
    assert ff["rms_error"] <= 0.5 * pid["rms_error"]  # the target
    assert ff["max_error"] < pid["max_error"] and ff["mean_abs_error"] < pid["mean_abs_error"]


def step_runs(bundle: Path, tmp_path: Path, start: float, target: float, **joint: object) -> dict[bool, JointRun]:
    reference = precondition_and_step(tmp_path / "step.csv", start, target)
    config = joint_config(RUN_URL, joint=joint)
    return {ff: run_joint(bundle, reference, tmp_path / f"step{ff}.pmt", 10.0, ff, 6.0, config) for ff in (False, True)}


@pytest.mark.parametrize(("start", "target"), [(0.0, -15.0), (-10.0, 10.0)])
def test_step_responses_feedforward_rises_faster(bundle, tmp_path, start, target):
    """Schreiber Fig 11: with the compensator the angle rises faster; both settle on the target."""
    runs = step_runs(bundle, tmp_path, start, target)
    pid, ff = (step_metrics(runs[f], start, target, 6.0) for f in (False, True))
    print(f"\nstep {start:+g} -> {target:+g} deg: PID {pid}; PID + FF {ff}")
    assert all(r.summary["faults"] == [] for r in runs.values())
    assert ff.rise_s < pid.rise_s
    assert pid.steady_error_deg < 3 * ADC_DEG and ff.steady_error_deg < 3 * ADC_DEG
    # the target, within one converter count (both overshoots are a fraction of one here)
    assert ff.overshoot_deg <= pid.overshoot_deg + ADC_DEG


@pytest.mark.xfail(strict=True, reason="not met with eq 8's sum: the integrator carries a memory offset (README)")
def test_step_overshoot_with_eq8_feedforward_is_no_larger(bundle, tmp_path):
    runs = step_runs(bundle, tmp_path, 0.0, -15.0, **EQ8)
    pid, ff = (step_metrics(runs[f], 0.0, -15.0, 6.0) for f in (False, True))
    print(f"\neq 8, step +0 -> -15 deg: PID {pid}; PID + FF {ff}")
    assert ff.overshoot_deg <= pid.overshoot_deg + ADC_DEG


def test_cli_runs_the_joint(bundle, tmp_path, capsys):
    from host.cli import main

    out = tmp_path / "rec.csv"
    assert main(["hil", "record", "--rig", "joint", "--joint-command", "angle", "--scenario", "forc",
                 "--duration", "2", "--out", str(out)]) == 0  # fmt: skip
    assert json.loads(out.with_suffix(".truth.json").read_text())["u_unit"] == "deg"
    capsys.readouterr()
    args = ["edge", "run", "--config", str(HIL_JOINT), "--bundle", str(bundle), "--duration", "2", "--json"]
    assert main([*args, "--reference", "const:value=5"]) == 0
    muscle_keys = {"rms_error", "mean_abs_error", "max_error", "ticks", "overruns", "lateness_p99_us", "faults"}
    summary = json.loads(capsys.readouterr().out)
    assert muscle_keys <= set(summary) and summary["unit"] == "deg" and summary["feedforward"] is True
    assert main([*args, "--no-feedforward"]) == 0
    assert json.loads(capsys.readouterr().out)["feedforward"] is False
