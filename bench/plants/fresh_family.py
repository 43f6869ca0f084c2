"""A second held-out plant family for ``pmactl diagnose``, never used for tuning.

Four cores (:mod:`bench.plants.fresh_cores`), seven protocols (:mod:`bench.plants.fresh_protocols`),
every effect in two forms unlike the first family's (:mod:`bench.plants.fresh_effects`), sample
rates 50-500 Hz (80, 125, 250 and 400 Hz are new). Only numbers are reported from it.

Every effect case is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same plant, protocol and seed with the effect switched off) lies in
``[EFFECT_MIN_OVER_NOISE * noise, EFFECT_MAX_OVER_SPAN * span]``. The drawn intensity is kept when
it lands there; otherwise it is scaled (at most 4x either way, recorded as
``intensity_rescale`` in the truth) until it does (:mod:`bench.plants.visibility`).

Confounds a real rig has, kept on purpose in the effect-free records too: the chamber core's
fill/vent dynamics (a level- and direction-dependent lag), the slip-mass core's light
resonance, per-plant sensor noise (0.02-0.05 mm), temperature read at 0.1 K, and warming curves
or load changes that do nothing. The table of every case: ``python -m bench.plants fresh 100``.
"""

from __future__ import annotations

import numpy as np

from bench.plants.engine import FamilySpec
from bench.plants.fresh_cores import FRESH_CORES, draw_fresh_params
from bench.plants.fresh_effects import FRESH_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.fresh_protocols import FRESH_PROTOCOLS, vented_full_cycle
from bench.plants.recording import rounded_reading

FRESH_PLANTS = tuple(FRESH_CORES)
FRESH_RATES_HZ = (80.0, 250.0, 50.0, 125.0, 500.0, 400.0)
NOISE_MM = {"coleman_hodgdon": 0.02, "kp_sum": 0.04, "maxwell_slip_mass": 0.03, "pneumatic_chamber": 0.05}
NONE_PER_PLANT = 5
SEED_BASE = 7000


SPEC = FamilySpec(
    name="fresh",
    cores=FRESH_CORES,
    forms=FRESH_FORMS,
    protocols=tuple(FRESH_PROTOCOLS),
    rates_hz=FRESH_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=lambda i, p: (i, i),
    excite=vented_full_cycle,
    draw_params=draw_fresh_params,
    columns=lambda r, rng: columns(r.t, r.case.effect, rng),
    draw_effect=draw_effect_params,
    # an effect's size is set against the effect-free span (0.0 while that is rendered)
    render=lambda r, form, q, load, temp, off: render(
        r.core, r.params, r.u, r.dt, form, q, load, temp, 0.0 if off is None else float(np.ptp(off))
    ),
    intensity_key=INTENSITY_KEY,
    none_per_plant=NONE_PER_PLANT,
    # it reuses the tuning set's four protocols and two of its rates; its cores take the effects' hooks and have
    # their own loop test (tests/test_fresh_plants.py); its creep and rate checks (new to it, 6 CPU s) run under
    # -m slow
    tags=frozenset(
        {
            "shares_protocols",
            "shares_rates",
            "check_core_draws_a_closed_loop",
            "slow:check_creep_forms_keep_moving_in_a_hold",
            "slow:check_rate_forms_grow_with_the_input_speed",
        }
    ),
    read=rounded_reading(10_000),  # measurement noise, independent of the plant draws
    base=lambda r: None,
    peak_bar=(2.5, 6.0),
    grow=1.25,
)
