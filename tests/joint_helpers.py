"""Shared set-up for the joint controller's tests and its README table: a Preisach bundle fitted
on a FORC recording of the emulated joint, and closed-loop runs on ``hil-joint.toml``."""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from edge.control.reference import parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.config import RigConfig, config_from_dict
from edge.runtime.run import EdgeRuntime
from edge.runtime.telemetry_read import read_telemetry
from hil.joint_record import record_joint, write_joint_recording
from host.data import load_measurement
from host.workflow import make_estimator, save_bundle

REPO = Path(__file__).resolve().parents[1]
HIL_JOINT = REPO / "docs" / "examples" / "hil-joint.toml"
FORC_S = 120.0  # one full set of first-order descending curves (10 maxima at 0.4 bar/s)
JOINT_SINE = "sine:amplitude=15,frequency=0.2,offset=0"  # deg, inside the identified +-23 deg


def joint_config(url: str | None = None, **sections: dict) -> RigConfig:
    """``hil-joint.toml``, its sim:// URL replaced by ``url`` and ``sections`` merged in."""
    raw = tomllib.loads(HIL_JOINT.read_text())
    if url is not None:
        raw["buses"]["i2c"]["url"] = url
    for name, values in sections.items():
        if name in ("buses", "devices", "channels"):
            for key, table in values.items():
                raw[name].setdefault(key, {}).update(table)
        else:
            raw.setdefault(name, {}).update(values)
    return config_from_dict(raw, str(HIL_JOINT))


def fit_joint_bundle(directory: Path, seed: int = 0) -> Path:
    """What ``pmactl hil record --rig joint --joint-command angle --scenario forc --duration 120``
    and ``pmactl fit --model preisach --preisach-method forc --units deg,deg --save`` write."""
    csv = write_joint_recording(record_joint("forc", seed, FORC_S, command="angle"), directory / "joint-forc.csv")
    train = load_measurement(csv)
    estimator = make_estimator("preisach", preisach_method="forc").fit(train.u, train.y)
    return save_bundle(estimator, train, directory / "bundle", ("deg", "deg"), {"model": "preisach"})


@dataclass
class JointRun:
    """A closed-loop run: its summary and the telemetry columns [s, deg, bar]."""

    summary: dict[str, object]
    t: np.ndarray
    reference_deg: np.ndarray
    angle_deg: np.ndarray
    u_bar: np.ndarray
    valve_b_bar: np.ndarray


def run_joint(
    bundle: Path | None,
    reference: str,
    telemetry: Path,
    duration_s: float,
    feedforward: bool = True,
    settle_s: float = 5.0,
    config: RigConfig | None = None,
) -> JointRun:
    runtime = EdgeRuntime(
        config or joint_config(),
        load_bundle(bundle) if bundle is not None else None,
        parse_reference(reference),
        feedforward=feedforward,
        telemetry_path=telemetry,
        settle_s=settle_s,
    )
    summary = runtime.run(duration_s).as_dict()
    rows = read_telemetry(telemetry).rows
    return JointRun(summary, rows["t"], rows["reference_deg"], rows["angle_deg"], rows["u_bar"], rows["valve_b_bar"])


def step_reference(path: Path, start_deg: float, target_deg: float, at_s: float, end_s: float) -> str:
    """A CSV reference holding ``start_deg`` until ``at_s``, then ``target_deg`` (a step)."""
    path.write_text(f"t,y_ref\n0,{start_deg}\n{at_s},{start_deg}\n{at_s + 1e-3},{target_deg}\n{end_s},{target_deg}\n")
    return str(path)


@dataclass
class StepMetrics:
    """Schreiber Fig 11's reading of a step: overshoot [deg], 10-90 % rise time [s], 2 % settling
    time [s] (or inf), steady-state error over the last second [deg]."""

    overshoot_deg: float
    rise_s: float
    settle_s: float
    steady_error_deg: float


def step_metrics(run: JointRun, start_deg: float, target_deg: float, at_s: float) -> StepMetrics:
    after = run.t >= at_s
    t, y = run.t[after] - at_s, run.angle_deg[after]
    size = target_deg - start_deg
    progress = (y - start_deg) / size  # 0 before, 1 at the target, > 1 beyond it
    overshoot = max(0.0, float(np.max(progress)) - 1.0) * abs(size)
    t10 = t[np.argmax(progress >= 0.1)] if np.any(progress >= 0.1) else math.inf
    t90 = t[np.argmax(progress >= 0.9)] if np.any(progress >= 0.9) else math.inf
    outside = np.nonzero(np.abs(y - target_deg) > 0.02 * abs(size))[0]
    settle = 0.0 if outside.size == 0 else (float(t[outside[-1] + 1]) if outside[-1] + 1 < t.size else math.inf)
    last = t >= t[-1] - 1.0
    return StepMetrics(overshoot, float(t90 - t10), settle, float(np.mean(np.abs(y[last] - target_deg))))
