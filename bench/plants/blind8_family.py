"""A tenth, truly blind held-out plant family for ``pmactl diagnose`` (blind8).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind8_cores`): a natural-rubber bladder that crystallises
  under strain (Ivshin-Pence phase kinetics, a one-reversal memory) relieving its Mooney-Rivlin
  resistance, on a Chou-Hannaford braid; Dafalias-Popov bounding-surface plasticity of the braid's
  friction on a datasheet chart (PCHIP); Cattaneo-Mindlin partial slip at Hertzian fibre
  crossings (an Iwan set with Mindlin's backbone, slip force ``~ N``, slip distance ``~ N^(2/3)``)
  on a thick-walled Chou-Hannaford map; a multi-leaf return spring with Fancher's interleaf
  friction on an arctangent stroke map.
* Five protocols (:mod:`bench.plants.blind8_protocols`): an ATC-24 incremental cyclic test,
  sine-on-random, a hand pump with a bleed valve, leak-down tests, a cycloidal cam; each starts
  vented and is shaken down by four trapezoids to the top in its first ~7 s.
* Every effect in two new forms (:mod:`bench.plants.blind8_effects`), all acting on the
  contraction after the core.
* Sample rates 48, 78, 117, 196, 270 and 512 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.visibility.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family,
:func:`bench.plants.visibility.visible_effect` makes sure the size lies in ``[5 x noise, 12 %
of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind8_rig`): a proportional
valve with a slew-limited set point (6-15 x the peak per second) and a 10-30 ms lag; the
transducer in the muscle's inlet reading the flow noise of the jet past its port (0.3-1 % of the
peak at full flow); its noise (2-6 mbar) and step (2-5 mbar); a SAR stroke converter with
mismatched bit weights (jumps of a few um at its carries); the stroke amplifier's auto-zero
steps (3-8 um every 20-40 s); the DAQ's second-order Butterworth anti-alias filters on both
channels (0.3-0.4 x the rate, 2-5 % apart); stroke noise 0.012-0.03 mm and a reading step of
0.002-0.02 mm per plant; load (read to 0.004 kg) and temperature (read to 1/32 K, an RTD
converter's step) columns that always move and act only in their own effect's records (one
temperature pattern follows the muscle's vents: a decoy correlated with the input's falls).
The table of every case: ``python -m bench.plants blind8 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind8_cores import BLIND8_CORES, draw_params
from bench.plants.blind8_effects import BLIND8_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind8_protocols import BLIND8_PROTOCOLS, with_shakedown
from bench.plants.blind8_rig import muscle_pressure, pressure_reading, recorded_pressure
from bench.plants.engine import Calibration, Case, FamilySpec, Record, params_first, shifted
from bench.plants.recording import Sensors, recorded

BLIND8_PLANTS = tuple(BLIND8_CORES)
BLIND8_RATES_HZ = (48.0, 196.0, 512.0, 78.0, 270.0, 117.0)
NOISE_MM = {
    "crystallising_bladder": 0.018,
    "bounding_surface_braid": 0.03,
    "mindlin_crossings": 0.012,
    "fancher_leaf_spring": 0.024,
}
QUANT_MM = {
    "crystallising_bladder": 0.005,
    "bounding_surface_braid": 0.02,
    "mindlin_crossings": 0.002,
    "fancher_leaf_spring": 0.01,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.004, 0.004
TEMP_READ_K, TEMP_NOISE_K = 0.03125, 0.015
NONE_PER_PLANT = 5
SEED_BASE = 41000
SEED_OFFSET = 210_000  # measurement noise seeded at case.seed + 210_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The input read by the inlet transducer."""
    input_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    read_input = pressure_reading(sim["u"], sim["truth"]["plant_parameters"], input_rng)
    return recorded(case, {**sim, "u": read_input}, spec.sensors[case.plant])


SPEC = FamilySpec(
    name="blind8",
    cores=BLIND8_CORES,
    forms=BLIND8_FORMS,
    protocols=tuple(BLIND8_PROTOCOLS),
    rates_hz=BLIND8_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(3, 2),
    excite=with_shakedown,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, np.clip(muscle_pressure(r.u, r.dt, r.params) / r.peak, 0.0, None), rng),
    draw_effect=draw_effect_params,
    render=params_first(render),
    intensity_key=INTENSITY_KEY,
    sensors=SENSORS,
    none_per_plant=NONE_PER_PLANT,
    # its creep (growing, then recovering) is checked by its own test (tests/test_blind8_forms.py), with its own
    # rendering; the generic creep, rate and loop checks (new to it) run under -m slow
    tags=frozenset(
        {
            "check_creep_forms_keep_moving_in_a_hold",
            "slow:check_rate_forms_grow_with_the_input_speed",
            "slow:check_core_draws_a_closed_loop",
        }
    ),
    read=_read,
    recorded_input=lambda r: recorded_pressure(r.u, r.dt, r.params),
    calibration=Calibration(),
)
