"""Recordings from the emulated antagonistic joint (``pmactl hil record --rig joint``).

A scenario's command ``c`` (0-4 bar, the single-muscle protocols) becomes the differential
command ``u = c - 2`` [bar] around the pretension pressure: ``u1 = p_pre + u * gain``,
``u2 = p_pre - u * gain`` (``gain`` 0.75: +-1.5 bar). The CSV has
``t,u,y,u1,u2,p1,p2,theta``: ``u`` the differential command [bar], ``y`` = ``theta`` the encoder
angle [deg] (so every ``pmactl`` tool that reads ``t,u,y`` takes a joint record), ``u1``, ``u2``
the valve commands [bar], ``p1``, ``p2`` the measured muscle pressures [bar]. The truth sidecar
holds the joint's parameters.

With ``command="angle"`` (``--joint-command angle``) the scenario commands a joint angle
instead, ``u = ANGLE_GAIN_DEG * (c - 2)`` [deg] (+-30 deg), and the valve commands come from the
edge's static inversion (:class:`edge.control.joint.StaticInversion`, built from the joint's
true statics): what the joint controller's inverse Preisach model is identified on.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from edge.control.joint import JointModel, StaticInversion
from hil.effects import apply_effect
from hil.joint import JointParams, encoder_angle_deg, joint_initial_state, joint_update
from hil.record import PRESSURE_FULL_SCALE_BAR, quantise, truth_path
from hil.scenarios import SCENARIOS

JOINT_EFFECTS = ("none", "transport_delay")
JOINT_COMMANDS = ("differential", "angle")
DIFFERENTIAL_GAIN = 0.75
ANGLE_GAIN_DEG = 15.0


@dataclass
class JointRecording:
    """Sampled joint signals (module docstring) and the truth behind them."""

    t: np.ndarray
    u: np.ndarray
    theta_deg: np.ndarray
    u1: np.ndarray
    u2: np.ndarray
    p1: np.ndarray
    p2: np.ndarray
    truth: dict[str, object]


def record_joint(
    scenario: str,
    seed: int,
    duration_s: float,
    effect: str = "none",
    rate_hz: float = 100.0,
    params: JointParams | None = None,
    command: str = "differential",
) -> JointRecording:
    """Run ``scenario`` on the joint for ``duration_s`` and sample its sensors at ``rate_hz``."""
    if scenario not in SCENARIOS:
        raise ValueError(f"scenario {scenario!r} unknown; choose one of {', '.join(SCENARIOS)}")
    if effect not in JOINT_EFFECTS:
        raise ValueError(
            f"effect {effect!r} is not emulated on the joint rig; choose one of {', '.join(JOINT_EFFECTS)}"
        )
    if command not in JOINT_COMMANDS:
        raise ValueError(f"joint command {command!r} unknown; choose one of {', '.join(JOINT_COMMANDS)}")
    base = params or JointParams()
    decimation = int(round(1.0 / (rate_hz * base.dt_s)))
    if decimation < 1 or abs(decimation * rate_hz * base.dt_s - 1.0) > 1e-9:
        raise ValueError(f"rate {rate_hz} Hz must divide the plant rate {1 / base.dt_s:g} Hz")
    rng = np.random.default_rng(seed)
    muscle, truth = apply_effect(effect, base.muscle, rng, duration_s)
    joint = replace(base, muscle=muscle)
    differential = SCENARIOS[scenario](duration_s, joint.dt_s, rng) - 2.0
    angle_deg = ANGLE_GAIN_DEG * differential
    if command == "angle":
        statics = StaticInversion(joint_model(joint))
        pressures = np.array([statics(a) for a in angle_deg.tolist()])
        u1, u2 = pressures[:, 0], pressures[:, 1]
    else:
        u1 = joint.pretension_bar + DIFFERENTIAL_GAIN * differential
        u2 = joint.pretension_bar - DIFFERENTIAL_GAIN * differential
    x = joint_initial_state(joint, float(u1[0]), float(u2[0]))
    rows = []
    for i, (a, b) in enumerate(zip(u1.tolist(), u2.tolist())):
        t = i * joint.dt_s
        if i % decimation == 0:
            rows.append((t, a, b, x.pressure_a_bar, x.pressure_b_bar, encoder_angle_deg(joint, x.angle_rad)))
        x = joint_update(t, x, a, b, joint)
    data = np.array(rows)
    n = len(data)
    params_record = asdict(joint)
    params_record["muscle"] = {k: v for k, v in params_record["muscle"].items() if not isinstance(v, dict)}
    return JointRecording(
        t=data[:, 0],
        u=angle_deg[::decimation][:n] if command == "angle" else (data[:, 1] - data[:, 2]) / 2.0,
        theta_deg=data[:, 5],
        u1=data[:, 1],
        u2=data[:, 2],
        p1=quantise(data[:, 3] + rng.normal(0.0, 0.004, n), PRESSURE_FULL_SCALE_BAR),
        p2=quantise(data[:, 4] + rng.normal(0.0, 0.004, n), PRESSURE_FULL_SCALE_BAR),
        truth={
            **truth,
            "rig": "joint",
            "command": command,
            "u_unit": "deg" if command == "angle" else "bar",
            "scenario": scenario,
            "seed": seed,
            "duration_s": duration_s,
            "rate_hz": rate_hz,
            "joint": params_record,
        },
    )


def joint_model(joint: JointParams) -> JointModel:
    """The edge's static model of ``joint`` (its true statics, in the edge's units)."""
    m = joint.muscle
    return JointModel(
        pulley_radius_mm=joint.pulley_radius_m * 1e3,
        pretension_n=joint.pretension_n,
        pretension_bar=joint.pretension_bar,
        muscle_radius_mm=m.radius_m * 1e3,
        rest_length_mm=m.rest_length_m * 1e3,
        tondu_a=m.tondu_a,
        tondu_b=m.tondu_b,
        tondu_k=m.tondu_k,
        return_stiffness_nm_per_rad=joint.return_stiffness_nm_per_rad,
    )


def write_joint_recording(recording: JointRecording, csv_path: str | Path) -> Path:
    """Write ``t,u,y,u1,u2,p1,p2,theta`` and the truth sidecar; returns the CSV path."""
    path = Path(csv_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    r = recording
    np.savetxt(
        path,
        np.column_stack([r.t, r.u, r.theta_deg, r.u1, r.u2, r.p1, r.p2, r.theta_deg]),
        delimiter=",",
        header="t,u,y,u1,u2,p1,p2,theta",
        comments="",
        fmt=["%.3f", "%.6g", "%.4f", "%.5f", "%.5f", "%.5f", "%.5f", "%.4f"],
    )
    truth_path(path).write_text(json.dumps(r.truth, indent=2, default=str) + "\n")
    return path
