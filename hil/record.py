"""Recordings from the emulated rig: the measured-data CSV and its truth sidecar.

``record`` runs a scenario through the plant at 1 kHz with one effect switched on and samples
the sensors at ``rate_hz``: pressure transducer and displacement sensor through 16-bit
quantisation with noise, plus the load cell and the temperature sensor. The CSV has
``t,u,y,p,load,temperature`` (``u``: pressure command [bar], ``y``: contraction [mm], ``p``:
measured pressure [bar], ``load`` [kg], ``temperature`` [degC]). The sidecar
``<name>.truth.json`` names the effect and its parameters: tests may read it, diagnosis code
must not. Force protocols (:data:`FORCE_SCENARIOS`) add a ``force`` column [N]: a load cell in
series with the muscle (:func:`hil.plant.tendon_force_n`, 0.5 N noise). In ``isometric`` the
muscle is clamped (:func:`hil.scenarios.isometric_contraction_ratio`): the same plant update runs
for the valve, then the contraction is held and the cell reads the muscle's static force.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hil.effects import apply_effect
from hil.plant import PlantParams, PlantState, initial_state, muscle_force_n, output, tendon_force_n, update
from hil.scenarios import SCENARIOS, isometric_contraction_ratio

PRESSURE_FULL_SCALE_BAR = 10.0
DISPLACEMENT_FULL_SCALE_MM = 150.0
FORCE_SCENARIOS = ("isotonic", "isometric")


@dataclass
class Recording:
    """Sampled sensor signals (see module docstring) and the truth behind them."""

    t: np.ndarray
    u: np.ndarray
    y: np.ndarray
    p: np.ndarray
    load: np.ndarray
    temperature: np.ndarray
    truth: dict[str, object] = field(default_factory=dict)
    force: np.ndarray | None = None


def quantise(values: np.ndarray, full_scale: float, bits: int = 16) -> np.ndarray:
    """Round to the resolution of a ``bits`` converter spanning ``0..full_scale``."""
    lsb = full_scale / 2**bits
    return np.round(values / lsb) * lsb


def record(
    scenario: str,
    seed: int,
    duration_s: float,
    effect: str = "none",
    rate_hz: float = 100.0,
    params: PlantParams | None = None,
    decoy_columns: bool = False,
) -> Recording:
    """Run ``scenario`` for ``duration_s`` with ``effect`` and sample the sensors at ``rate_hz``.

    With ``decoy_columns`` the load and temperature columns vary (load steps, a warming room)
    without touching the physics, unless the effect is that variable's own: the test of a
    diagnosis that must not blame a column for merely moving.
    """
    if scenario not in SCENARIOS:
        raise ValueError(f"scenario {scenario!r} unknown; choose one of {', '.join(SCENARIOS)}")
    base = params or PlantParams()
    decimation = int(round(1.0 / (rate_hz * base.dt_s)))
    if decimation < 1 or abs(decimation * rate_hz * base.dt_s - 1.0) > 1e-9:
        raise ValueError(f"rate {rate_hz} Hz must divide the plant rate {1 / base.dt_s:g} Hz")
    rng = np.random.default_rng(seed)
    plant, truth = apply_effect(effect, base, rng, duration_s)
    commands = SCENARIOS[scenario](duration_s, plant.dt_s, rng)
    x = initial_state(plant, float(commands[0]))
    samples = []
    forces = []
    dt = plant.dt_s
    for i, command in enumerate(commands.tolist()):
        t = i * dt
        if scenario == "isometric":
            x = _clamped(x, isometric_contraction_ratio(t, duration_s) * plant.rest_length_m)
        if i % decimation == 0:
            samples.append((t, command, *output(t, x, plant)))
            forces.append(_load_cell_n(scenario, t, x, plant))
        x = update(t, x, command, plant)
    data = np.array(samples)
    n = len(data)
    if decoy_columns:
        if effect != "load_dependence":
            steps = rng.permutation([0.0, 1.5, 3.5, 5.5, 7.5])
            data[:, 4] = steps[np.minimum((data[:, 0] / duration_s * steps.size).astype(int), steps.size - 1)]
        if effect != "temperature_drift":
            data[:, 5] = 22.0 + rng.uniform(5.0, 15.0) * data[:, 0] / duration_s
    truth["decoy_columns"] = bool(decoy_columns)
    return Recording(
        t=data[:, 0],
        u=data[:, 1],
        y=quantise(data[:, 2] + rng.normal(0.0, 0.03, n), DISPLACEMENT_FULL_SCALE_MM),
        p=quantise(data[:, 3] + rng.normal(0.0, 0.004, n), PRESSURE_FULL_SCALE_BAR),
        load=np.round(data[:, 4] + rng.normal(0.0, 0.01, n), 3),
        temperature=np.round(data[:, 5] + rng.normal(0.0, 0.05, n), 2),
        truth={**truth, "scenario": scenario, "seed": seed, "duration_s": duration_s, "rate_hz": rate_hz},
        force=np.round(np.array(forces) + rng.normal(0.0, 0.5, n), 2) if scenario in FORCE_SCENARIOS else None,
    )


def _clamped(x: PlantState, contraction_m: float) -> PlantState:
    """The muscle held at ``contraction_m``: no motion, braid friction unloaded."""
    return x._replace(contraction_m=contraction_m, creep_m=0.0, slips_m=(0.0,) * len(x.slips_m), speed_m_s=0.0)


def _load_cell_n(scenario: str, t: float, x: PlantState, params: PlantParams) -> float:
    if scenario == "isometric":
        return muscle_force_n(params, x.pressure_bar, x.contraction_m, params.temperature.at(t))
    return tendon_force_n(t, x, params)


def truth_path(csv_path: str | Path) -> Path:
    """``data.csv`` -> ``data.truth.json``."""
    path = Path(csv_path)
    return path.with_name(path.stem + ".truth.json")


def write_recording(recording: Recording, csv_path: str | Path) -> Path:
    """Write the CSV and its truth sidecar; returns the CSV path."""
    path = Path(csv_path)
    path.parent.mkdir(parents=True, exist_ok=True)
    values = [recording.t, recording.u, recording.y, recording.p, recording.load, recording.temperature]
    header, fmt = "t,u,y,p,load,temperature", ["%.3f", "%.5f", "%.4f", "%.5f", "%.3f", "%.2f"]
    if recording.force is not None:
        values, header, fmt = [*values, recording.force], header + ",force", [*fmt, "%.2f"]
    np.savetxt(path, np.column_stack(values), delimiter=",", header=header, comments="", fmt=fmt)
    truth_path(path).write_text(json.dumps(recording.truth, indent=2) + "\n")
    return path
