"""The emulated antagonistic joint: statics from the single-muscle physics, wiping-out, congruency, CLI.

Statistics (Schreiber Figs 7-8):

* wiping-out: the decaying-sine sequence is played twice; after the full cycle that opens each
  sequence, ``max |theta_2(t) - theta_1(t)|`` over the rest, as a fraction of the output range.
  Threshold 1 %.
* congruency: the same minor loop (2.0 <-> 2.5 bar command) after two histories; each loop's
  ascending and descending branches resampled on a common input grid, the mean offset between
  the loops removed; ``max |difference|`` as a fraction of the loop height. Threshold 5 %. The
  offset itself must exceed the loop height, or the histories did not differ and the test says
  nothing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hil.joint import JointParams, joint_initial_state, pretension_contraction_m
from hil.joint_record import record_joint
from hil.plant import muscle_force_n
from hil.record import record
from hil.scenarios import MINOR_LOOP_HIGH_BAR, MINOR_LOOP_LOW_BAR, minor_loop_corner_times
from host.cli import main
from host.data import load_measurement

WIPE_OUT_THRESHOLD = 0.01
CONGRUENCY_THRESHOLD = 0.05


def wiping_out_error(theta: np.ndarray) -> float:
    """Second decaying-sine sequence against the first, after each one's opening full cycle."""
    half = theta.size // 2
    first, second = theta[:half], theta[half : 2 * half]
    start = half // 11
    return float(np.max(np.abs(second[start:] - first[start:])) / np.ptp(theta))


def congruency(t: np.ndarray, u_bar: np.ndarray, y: np.ndarray, duration_s: float) -> tuple[float, float, float]:
    """(error as a fraction of the loop height, offset between the loops, loop height)."""
    times = minor_loop_corner_times(duration_s)
    span = MINOR_LOOP_HIGH_BAR - MINOR_LOOP_LOW_BAR
    grid = np.linspace(MINOR_LOOP_LOW_BAR + 0.05 * span, MINOR_LOOP_HIGH_BAR - 0.05 * span, 40)

    def loop(i: int) -> np.ndarray:
        up = (t >= times[i]) & (t <= times[i + 1])
        down = (t >= times[i + 1]) & (t <= times[i + 2])
        rising = np.interp(grid, u_bar[up], y[up])
        falling = np.interp(grid, u_bar[down][::-1], y[down][::-1])
        return np.concatenate([rising, falling])

    # the last of the three loops after each history (indices into MINOR_LOOP_CORNERS_BAR)
    first, second = loop(7), loop(16)
    offset = float(np.mean(first) - np.mean(second))
    height = float(np.ptp(first))
    return float(np.max(np.abs(first - second - offset)) / height), offset, height


def test_joint_statics_come_from_the_muscle_force():
    params = JointParams()
    x_pre = pretension_contraction_m(params)
    assert muscle_force_n(params.muscle, params.pretension_bar, x_pre, 22.0) == pytest.approx(params.pretension_n)
    assert joint_initial_state(params, 2.5, 2.5).angle_rad == pytest.approx(0.0, abs=1e-9)
    state = joint_initial_state(params, 3.5, 1.5)
    assert state.angle_rad > 0  # muscle A pulls harder: towards A
    r = params.pulley_radius_m
    fa = muscle_force_n(params.muscle, 3.5, x_pre + r * state.angle_rad, 22.0)
    fb = muscle_force_n(params.muscle, 1.5, x_pre - r * state.angle_rad, 22.0)
    stiffness = params.muscle.slip_stiffness_n_per_m
    sa = sum(k * s for k, s in zip(stiffness, state.slips_a_m))
    sb = sum(k * s for k, s in zip(stiffness, state.slips_b_m))
    assert sa > 0 > sb  # A contracted, B extended: each muscle's braid friction opposes its own motion
    # at rest the muscles' net torque, less their friction, is held by the return spring
    assert r * (fa - sa) - r * (fb - sb) == pytest.approx(
        params.return_stiffness_nm_per_rad * state.angle_rad, rel=1e-6
    )


def test_the_joint_reads_its_muscles_parameters():
    """Not a copy of the physics: the muscle's own parameters decide the joint's response."""
    from dataclasses import replace

    base = JointParams()
    softer_braid = replace(base, muscle=replace(base.muscle, tondu_k=1.8))
    assert joint_initial_state(softer_braid, 3.5, 1.5).angle_rad != pytest.approx(
        joint_initial_state(base, 3.5, 1.5).angle_rad, rel=1e-3
    )


def test_joint_wipes_out_and_a_creeping_muscle_does_not():
    rec = record_joint("decaying-sines", 0, 60.0)
    assert np.ptp(rec.theta_deg) > 40.0
    assert wiping_out_error(rec.theta_deg) < WIPE_OUT_THRESHOLD
    # the statistic can fail: creep remembers more than the extremes
    creeping = record("decaying-sines", 0, 60.0, effect="creep")
    assert wiping_out_error(creeping.y) > WIPE_OUT_THRESHOLD


def test_joint_minor_loops_are_congruent():
    rec = record_joint("minor-loops", 0, 60.0)
    error, offset, height = congruency(rec.t, rec.u + 2.0, rec.theta_deg, 60.0)
    assert abs(offset) > height  # the two histories left different memories
    assert error < CONGRUENCY_THRESHOLD


def test_cli_records_the_joint(tmp_path):
    out = tmp_path / "joint.csv"
    assert main(["hil", "record", "--rig", "joint", "--scenario", "forc", "--duration", "5", "--out", str(out)]) == 0
    assert out.read_text().splitlines()[0] == "t,u,y,u1,u2,p1,p2,theta"
    m = load_measurement(out)
    assert set(m.extras) >= {"u1", "u2", "p1", "p2", "theta"}
    np.testing.assert_allclose(m.u, (m.extras["u1"] - m.extras["u2"]) / 2, atol=1e-5)
    assert math.isfinite(float(m.y.max()))
    assert (
        main(
            [
                "hil",
                "record",
                "--rig",
                "joint",
                "--scenario",
                "forc",
                "--effect",
                "creep",
                "--duration",
                "5",
                "--out",
                str(out),
            ]
        )
        == 2
    )
