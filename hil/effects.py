"""The effects the emulator can hide in a recording, each with physically sensible ranges.

``apply_effect(name, params, rng, duration_s)`` returns the plant parameters with the effect
switched on and its truth record. Parameters are drawn uniformly from :data:`EFFECT_RANGES`
when a random generator is given (what ``pmactl hil record`` does, from its seed) and are the
middle of each range otherwise. With ``none`` the plant is the default rig: a diagnosis must
then find nothing.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from hil.plant import PlantParams, Schedule, TemperatureProfile

EFFECTS = (
    "none", "rate_dependence", "creep", "transport_delay", "load_dependence", "temperature_drift", "session_shift",
)  # fmt: skip

SEED_000_LOADS_KG = (0.0, 1.5, 3.5, 5.5, 7.5)

EFFECT_RANGES: dict[str, dict[str, tuple[float, float]]] = {
    # velocity-strengthening braid friction, quadratic in speed: loops widen with input rate
    # (Wu2025): loop area x1.8-2.4 from 0.05 to 0.5 Hz, friction +4-26 % at the 0.01 m/s of slow triangles
    "rate_dependence": {"rate_friction_s_per_m": (30.0, 80.0)},
    # viscoelastic relaxation under a constant load (Schreiber)
    "creep": {"creep_fraction": (0.03, 0.10), "creep_time_constant_s": (5.0, 30.0)},
    # pneumatic line dead time (PAMInertial measured 0.3 s)
    "transport_delay": {"dead_time_s": (0.05, 0.30)},
    # the hanging mass steps through Ai2019's loads (Figs 8-9); order drawn, not ranged
    "load_dependence": {},
    # the rig warms up: bladder and braid soften
    "temperature_drift": {
        "temperature_rise_k": (8.0, 25.0),
        "elastic_softening_per_k": (0.003, 0.010),
        "friction_softening_per_k": (0.005, 0.02),
    },
    # the muscle of another session: the chamber pressure that makes force is gain * p - offset
    # of the transducer's. Sized on the real muscle (data/pam_muscle_sensory, 18-03 vs 31-03, a PI
    # model per series of 18-03 mapped onto 31-03's same series, 19 series): y_31 ~ a + b y_model
    # with median a = +4.1 % of p-p, b = 0.93 (same day, P001 vs P003: +0.5 %, 1.000). The middle
    # of these ranges gives a = +4.8 % of the span, b = 0.92 on this muscle's triangles.
    "session_shift": {"muscle_pressure_gain": (0.90, 0.97), "muscle_pressure_offset_bar": (-0.15, -0.03)},
}


def _draw(name: str, rng: np.random.Generator | None) -> dict[str, float]:
    ranges = EFFECT_RANGES.get(name, {})
    if rng is None:
        return {key: (lo + hi) / 2.0 for key, (lo, hi) in ranges.items()}
    return {key: float(rng.uniform(lo, hi)) for key, (lo, hi) in ranges.items()}


def apply_effect(
    name: str, params: PlantParams, rng: np.random.Generator | None, duration_s: float
) -> tuple[PlantParams, dict[str, object]]:
    """``params`` with effect ``name`` switched on, and ``{"effect": name, "parameters": {...}}``."""
    if name not in EFFECTS:
        raise ValueError(f"effect {name!r} unknown; choose one of {', '.join(EFFECTS)}")
    values = _draw(name, rng)
    truth: dict[str, object] = dict(values)
    if name == "rate_dependence":
        params = replace(params, rate_friction_s_per_m=values["rate_friction_s_per_m"])
    elif name == "creep":
        params = replace(
            params, creep_fraction=values["creep_fraction"], creep_time_constant_s=values["creep_time_constant_s"]
        )
    elif name == "session_shift":
        params = replace(
            params,
            muscle_pressure_gain=values["muscle_pressure_gain"],
            muscle_pressure_offset_bar=values["muscle_pressure_offset_bar"],
        )
    elif name == "transport_delay":
        params = replace(params, dead_time_s=values["dead_time_s"])
    elif name == "load_dependence":
        loads = [float(v) for v in (rng.permutation(SEED_000_LOADS_KG) if rng is not None else SEED_000_LOADS_KG)]
        times = [i * duration_s / len(loads) for i in range(len(loads))]
        params = replace(params, load=Schedule(tuple(times), tuple(loads)))
        truth = {"load_kg": loads, "switch_times_s": times}
    elif name == "temperature_drift":
        rise = values["temperature_rise_k"]
        profile = TemperatureProfile(params.reference_temperature_c, rise, 0.2 * rise, duration_s, duration_s / 2)
        params = replace(
            params,
            temperature=profile,
            elastic_softening_per_k=values["elastic_softening_per_k"],
            friction_softening_per_k=values["friction_softening_per_k"],
        )
    return params, {"effect": name, "parameters": truth}
