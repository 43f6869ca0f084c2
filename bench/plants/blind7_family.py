"""A ninth, truly blind held-out plant family for ``pmactl diagnose`` (blind7).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind7_cores`): a random-field Ising chain of braid crossings
  (avalanches, a lattice memory) on a reduced Sarosi (exponential-linear) force map; a
  Prandtl-Tomlinson carriage on a cogged rail (multistable wells, stick-slip jumps) on a cubic
  force map; a Valanis endochronic sleeve (a fading hereditary memory over the pressure's path
  length) on a hyperbolic force map; a twist-coupled braid whose end cap turns in a thrust
  bearing (a play in a hidden angle, its radius set by the stroke) on an exponential-saturation
  stroke map.
* Five protocols (:mod:`bench.plants.blind7_protocols`): relay autotuning, fatigue cycling with
  reference cycles, a DMA amplitude sweep, an oscillometric cuff (stepwise deflation), an ISO
  230-2 bidirectional positioning test; each starts vented and is preconditioned by three
  haversine cycles to the top in its first ~6 s.
* Every effect in two new forms (:mod:`bench.plants.blind7_effects`), all acting on the
  contraction after the core.
* Sample rates 44, 87, 138, 212, 365 and 560 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.visibility.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family,
:func:`bench.plants.visibility.visible_effect` makes sure the size lies in ``[5 x noise, 12 %
of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind7_rig`): a PWM-driven
valve (8-25 ms lag, a 90-210 Hz ripple of 0.3-1 % of the peak, aliased in the recorded input);
the recorded pressure taken at the valve's outlet, so it leads the muscle's by the hose's lag
(10-30 ms); the pressure transducer's noise (2-6 mbar) and converter step (2-5 mbar); the
multiplexer's channel skew (the stroke converted 0.1-0.6 ms after its time stamp); popcorn
(random telegraph) noise of 5-15 um on the stroke amplifier; stroke noise 0.011-0.026 mm and a
reading step of 0.0025-0.02 mm per plant; load (read to 0.005 kg) and temperature (read to
1/16 K, a digital thermometer's step) columns that always move and act only in their own
effect's records (one temperature pattern follows the valve's duty: a decoy correlated with the
input's slow mean). The table of every case: ``python -m bench.plants blind7 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind7_cores import BLIND7_CORES, draw_params
from bench.plants.blind7_effects import BLIND7_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind7_protocols import BLIND7_PROTOCOLS, with_preconditioning
from bench.plants.blind7_rig import pressure_reading, valve_pressure
from bench.plants.engine import Calibration, Case, FamilySpec, Record, params_first, shifted
from bench.plants.recording import Sensors, recorded

BLIND7_PLANTS = tuple(BLIND7_CORES)
BLIND7_RATES_HZ = (44.0, 212.0, 560.0, 87.0, 365.0, 138.0)
NOISE_MM = {
    "ising_crossings": 0.014,
    "detent_carriage": 0.02,
    "endochronic_sleeve": 0.026,
    "twist_bearing": 0.011,
}
QUANT_MM = {
    "ising_crossings": 0.004,
    "detent_carriage": 0.01,
    "endochronic_sleeve": 0.02,
    "twist_bearing": 0.0025,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.005, 0.003
TEMP_READ_K, TEMP_NOISE_K = 0.0625, 0.02
NONE_PER_PLANT = 5
SEED_BASE = 39000
SEED_OFFSET = 170_000  # measurement noise seeded at case.seed + 170_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The input read by the pressure transducer."""
    input_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    read_input = pressure_reading(sim["u"], sim["truth"]["plant_parameters"], input_rng)
    return recorded(case, {**sim, "u": read_input}, spec.sensors[case.plant])


SPEC = FamilySpec(
    name="blind7",
    cores=BLIND7_CORES,
    forms=BLIND7_FORMS,
    protocols=tuple(BLIND7_PROTOCOLS),
    rates_hz=BLIND7_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(3, 2),
    excite=with_preconditioning,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, r.u, r.peak, rng),
    draw_effect=draw_effect_params,
    render=params_first(render),
    intensity_key=INTENSITY_KEY,
    sensors=SENSORS,
    none_per_plant=NONE_PER_PLANT,
    # its jumpy cores are closed to 3 % and the others to 2 % (tests/test_blind7_family.py); its own rate test
    # is the generic one and more (tests/test_blind7_family.py)
    tags=frozenset({"check_core_draws_a_closed_loop", "check_rate_forms_grow_with_the_input_speed"}),
    read=_read,
    recorded_input=lambda r: valve_pressure(r.u, r.dt, r.params),
    calibration=Calibration(),
)
