"""The effects the emulator can hide in a recording, each with physically sensible ranges.

``apply_effect(name, params, rng, duration_s)`` returns the plant parameters with the effect
switched on (parameters drawn uniformly from the ranges below) and its truth record. With
``none`` the plant is the default rig: the diagnosis must then find nothing.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hil.plant import PlantParams, Schedule, TemperatureProfile

EFFECTS = ("none", "rate_dependence", "creep", "transport_delay", "load_dependence", "temperature_drift")

SEED_000_LOADS_KG = (0.0, 1.5, 3.5, 5.5, 7.5)


def apply_effect(
    name: str, params: PlantParams, rng: np.random.Generator, duration_s: float
) -> tuple[PlantParams, dict[str, object]]:
    """``params`` with effect ``name`` switched on, and ``{"effect": name, "parameters": {...}}``."""
    if name not in EFFECTS:
        raise ValueError(f"effect {name!r} unknown; choose one of {', '.join(EFFECTS)}")
    truth: dict[str, float | list[float]]
    if name == "none":
        truth = {}
    elif name == "rate_dependence":  # viscous braid friction: loops widen with input rate (seed 001)
        damping = float(rng.uniform(1500.0, 5000.0))
        params, truth = replace(params, damping_n_s_per_m=damping), {"damping_n_s_per_m": damping}
    elif name == "creep":  # viscoelastic relaxation under a constant load (seed 003)
        fraction, tau = float(rng.uniform(0.03, 0.10)), float(rng.uniform(5.0, 30.0))
        params = replace(params, creep_fraction=fraction, creep_time_constant_s=tau)
        truth = {"creep_fraction": fraction, "creep_time_constant_s": tau}
    elif name == "transport_delay":  # pneumatic line dead time (seed 004: 0.3 s)
        delay = float(rng.uniform(0.05, 0.30))
        params, truth = replace(params, dead_time_s=delay), {"dead_time_s": delay}
    elif name == "load_dependence":  # the hanging mass changes (seed 000 Figs 8-9)
        loads = [float(v) for v in rng.permutation(SEED_000_LOADS_KG)]
        times = [i * duration_s / len(loads) for i in range(len(loads))]
        params = replace(params, load=Schedule(tuple(times), tuple(loads)))
        truth = {"load_kg": loads, "switch_times_s": times}
    else:  # temperature_drift: the bladder and braid soften as the rig warms up
        rise = float(rng.uniform(8.0, 25.0))
        elastic, friction = float(rng.uniform(0.003, 0.010)), float(rng.uniform(0.005, 0.02))
        profile = TemperatureProfile(params.reference_temperature_c, rise, 0.2 * rise, duration_s, duration_s / 2)
        params = replace(
            params, temperature=profile, elastic_softening_per_k=elastic, friction_softening_per_k=friction
        )
        truth = {"temperature_rise_k": rise, "elastic_softening_per_k": elastic, "friction_softening_per_k": friction}
    return params, {"effect": name, "parameters": truth}
