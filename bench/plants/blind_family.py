"""A third, blind held-out plant family for ``pmactl diagnose``: built without looking at the method.

Four cores (:mod:`bench.plants.blind_cores`: LuGre friction in a McKibben balance with a payload
mass, a Preisach plane with a lightly damped resonance, asymmetric plays with a cubic map and a
soft end stop, a valve feeding a chamber whose air heats and cools), seven protocols
(:mod:`bench.plants.blind_protocols`), every effect in two forms unlike the other families'
(:mod:`bench.plants.blind_effects`), sample rates 60-450 Hz (60, 90, 150, 300 and 450 Hz are
new). Only numbers are reported from it: it is scored once and never used to choose anything.

Every effect case is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same plant, protocol and seed with the effect switched off) lies in
``[EFFECT_MIN_OVER_NOISE * noise, EFFECT_MAX_OVER_SPAN * span]``; otherwise the intensity is
scaled (at most 4x either way, recorded as ``intensity_rescale`` in the truth) until it does
(:mod:`bench.plants.visibility`).

Confounds a real rig has, kept in the effect-free records too: the chamber's fill/vent and
thermal dynamics (a slow pressure tail after every move), the Preisach core's resonance, the
LuGre core's presliding and payload mass, sensor noise 0.02-0.05 mm per plant, load read at
0.001 kg with 0.01 kg noise, temperature read at 0.1 K with 0.05 K noise, and load and
temperature columns that move (heater cycles, door steps, swinging payloads) and do nothing.
The table of every case: ``python -m bench.plants blind 100``.
"""

from __future__ import annotations

import math

import numpy as np

from bench.plants.blind_cores import BAR_PA, BLIND_CORES, G_MS2, R_AIR, muscle_force
from bench.plants.blind_effects import BLIND_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind_protocols import BLIND_PROTOCOLS, vented_start
from bench.plants.engine import FamilySpec, over_off
from bench.plants.recording import rounded_reading

BLIND_PLANTS = tuple(BLIND_CORES)
BLIND_RATES_HZ = (60.0, 150.0, 300.0, 100.0, 450.0, 200.0, 90.0)
NOISE_MM = {"lugre_mckibben": 0.03, "preisach_resonant": 0.02, "asym_play_poly": 0.05, "valve_chamber": 0.04}
NONE_PER_PLANT = 5
SEED_BASE = 9100


def _geometry(rng: np.random.Generator, peak: float, kappa: float) -> dict[str, float]:
    """Muscle geometry and a spring chosen so the nominal contraction at ``peak`` is 18-36 mm."""
    g = {
        "peak": peak,
        "kappa": kappa,
        "r0_m": rng.uniform(0.006, 0.010),  # 12-20 mm bore
        "theta0": np.radians(rng.uniform(20.0, 26.0)),  # braid angle
        "l0_m": rng.uniform(0.2, 0.3),
        "payload_kg": rng.uniform(1.0, 3.0),
    }
    eps = rng.uniform(18.0, 36.0) / 1000.0 / g["l0_m"]
    k_total = (muscle_force(peak, eps, g) - g["payload_kg"] * G_MS2) / eps / g["l0_m"]  # N/m
    rubber = rng.uniform(0.2, 0.4)
    return {**g, "k_rubber": rubber * k_total, "k_spring": (1.0 - rubber) * k_total, "x_peak_m": eps * g["l0_m"]}


def draw_blind_params(core: str, rng: np.random.Generator, peak: float) -> dict[str, float]:
    """Plausible parameters for ``core`` (a 200-300 mm muscle, output span ~15-45 mm)."""
    if core == "lugre_mckibben":
        g = _geometry(rng, peak, 1.0)
        fc = rng.uniform(0.05, 0.1) * (g["k_spring"] + g["k_rubber"]) * g["x_peak_m"]  # N
        mass = rng.uniform(1.0, 2.5)
        sigma0 = fc / rng.uniform(6e-4, 1.2e-3)  # N/m: presliding of 0.6-1.2 mm
        return {
            **g,
            "mass_kg": mass,
            "fc_n": fc,
            "fs_n": fc * rng.uniform(1.05, 1.25),
            "vs_ms": rng.uniform(0.001, 0.005),
            "sigma0": sigma0,
            "sigma1": math.sqrt(sigma0 * mass),  # N s/m: bristles damped at ~0.5
            "sigma2": rng.uniform(300.0, 600.0),  # N s/m: the braid and rubber are lossy
        }
    if core == "preisach_resonant":
        return {
            **_geometry(rng, peak, rng.uniform(1.1, 1.3)),
            "mid": rng.uniform(0.4, 0.6),
            "mid_sd": rng.uniform(0.15, 0.3),
            "half": rng.uniform(0.06, 0.14),
            "half_sd": rng.uniform(0.4, 0.8),
            "share": rng.uniform(0.4, 0.65),
            "f_res_hz": rng.uniform(5.0, 20.0),
            "zeta": rng.uniform(0.05, 0.2),
        }
    if core == "asym_play_poly":
        a1, a2 = rng.uniform(0.5, 0.8), rng.uniform(0.2, 0.6)
        a3 = -rng.uniform(0.0, 0.3) * (a1 + 2 * a2) / 3.0  # keeps f' > 0 on [0, 1]
        total = a1 + a2 + a3
        stroke = rng.uniform(25.0, 45.0)
        return {
            "peak": peak,
            "stroke_mm": stroke,
            "a1": a1 / total,
            "a2": a2 / total,
            "a3": a3 / total,
            "r_up": rng.uniform(0.06, 0.12),
            "r_down": rng.uniform(0.03, 0.08),
            "c_plays": rng.uniform(0.4, 0.65),
            "k0_n_mm": rng.uniform(3.0, 6.0),
            "k1_n_mm": rng.uniform(6.0, 12.0),
            "payload_kg": rng.uniform(1.0, 3.0),
            "rubber_share": rng.uniform(0.2, 0.5),
            "ymax_mm": stroke * rng.uniform(1.1, 1.3),
        }
    if core == "valve_chamber":
        g = _geometry(rng, peak, 1.0)
        vol = rng.uniform(1.0e-4, 2.5e-4)  # m^3: muscle plus tube
        tau_fill = rng.uniform(0.15, 0.4)  # s to fill to peak at full opening
        m_fill = peak * BAR_PA * vol / (R_AIR * 293.15)
        return {
            **g,
            "volume_m3": vol,
            "orifice": m_fill / tau_fill * math.sqrt(R_AIR * 293.15) / (7.0 * BAR_PA),  # m^2 (C_d A / sqrt-law)
            "band_bar": rng.uniform(0.4, 1.0),  # proportional band of the valve's pressure loop
            "tau_th_s": rng.uniform(1.5, 5.0),
            "slope": rng.uniform(3.0, 6.0),
            "split": rng.uniform(0.06, 0.14),
            "share": rng.uniform(0.4, 0.7),
        }
    raise KeyError(f"unknown blind core {core!r}; known: {', '.join(BLIND_CORES)}")


SPEC = FamilySpec(
    name="blind",
    cores=BLIND_CORES,
    forms=BLIND_FORMS,
    protocols=tuple(BLIND_PROTOCOLS),
    rates_hz=BLIND_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=lambda i, p: (i, i + i // len(BLIND_PROTOCOLS)),
    excite=vented_start,
    draw_params=draw_blind_params,
    columns=lambda r, rng: columns(r.t, r.case.effect, rng),
    draw_effect=draw_effect_params,
    render=over_off(render),
    intensity_key=INTENSITY_KEY,
    none_per_plant=NONE_PER_PLANT,
    # two of its rates are the tuning set's; its protocols start with a vent, not a sweep of the range; its
    # tests never checked creep on a hold or rate growth, and the generic checks fail on cyclic_ratchet and
    # frequency_width; its cores take the effects' hooks and have their own loop test
    # (tests/test_blind_family.py)
    tags=frozenset(
        {
            "shares_rates",
            "check_memory_known_early",
            "check_creep_forms_keep_moving_in_a_hold",
            "check_rate_forms_grow_with_the_input_speed",
            "check_core_draws_a_closed_loop",
        }
    ),
    read=rounded_reading(50_000),  # measurement noise, independent of the plant draws
    base=lambda r: None,
)
