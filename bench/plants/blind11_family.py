"""A thirteenth, truly blind held-out plant family for ``pmactl diagnose`` (blind11).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``) nor any family's scores; only the
other plant families and their property tests were read, to make this one different from all of
them. It is to be scored once, for honest numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind11_cores`), each on an extensible-braid Chou-Hannaford
  muscle (the fibres stretch with the pressure): the braid's crossings as a Prandtl-Ishlinskii set
  whose density *runs in* with the slip each play makes and re-seats at every vent (a loop that is
  wider after a vent and narrows with use); the return spring *tied down by a strap wrapped round a
  post* (distributed capstan friction on an elastic strap: a memory stored as the strap's tension
  profile, nested fronts in log-tension); *Greenwood-Williamson contacts* between bladder and braid
  born unloaded as the pressure rises and dying as it falls, each a Mindlin element (the friction's
  anchors record where the stroke was when each contact formed); a *wire-rope isolator* as the
  return element, its force following the *Menegotto-Pinto* law (smooth branches rounded by the
  previous excursion: a Bauschinger effect, no return-point memory).
* Five protocols (:mod:`bench.plants.blind11_protocols`): a pseudo-random ternary sequence of
  ramps (GF(3) maximal-length register), a sum of decaying ring-downs struck at random, a Matsuoka
  central pattern generator with stepped tonic drive, exoskeleton sit-to-stand repetitions, a
  JONSWAP sea state; each starts vented and is conditioned by two raised-cosine fills and a
  decaying oscillation about mid-range in its first ~6 s.
* Every effect in two forms (:mod:`bench.plants.blind11_effects`): a plain textbook one in a new
  parameterisation (a two-term Prony-series Maxwell solid, a three-term Prony retardation spectrum
  of Kelvin units a decade apart, a FIFO delay of whole samples, the load through a block and
  tackle into the force balance, a linear temperature coefficient of the lift-off pressure) and
  an unusual one (a centrifugal governor brake that only acts above a threshold speed, reverse
  creep from air permeating into a sealed cover, an adaptive jitter buffer on a network link, an
  imperfect column whose bow the load amplifies towards its Euler load, the nylon braid's wet
  glass transition).
* Sample rates 58, 142, 236, 310, 396 and 540 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.visibility.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family, :func:`bench.plants.visibility.visible_effect`
makes sure the size lies in ``[5 x noise, 12 % of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind11_rig`): a proportional
pressure regulator with a spool overlap (a dead band of 0.4-1.2 % of the peak where the outlet
holds short of the set pressure), a 12-30 ms approach and a slew limit of 8-20 x the peak per
second, and a 6-18 ms line to the muscle; the recorded input from a piezoresistive transducer at
the regulator's outlet (leading the muscle's pressure), seeing the line's quarter-wave ringing
(15-45 Hz) and drifting 2-6 mbar as its bridge warms up after power-on, read with 1-3 mbar of noise
and a 12-bit step; a laser triangulation stroke sensor with a cubic linearity error (8-25 um),
speckle (3-8 um RMS, correlated over 0.3-1.5 mm) and internal averaging over 1-5 ms; stroke noise
0.011-0.026 mm and a reading step of 1-4 um per plant; a load column from an instrumentation
amplifier's two-pole low-pass (6-15 Hz) with aliased mains hum (2-6 g) and a 12-bit count (2.4-7.3
g), and a temperature column from an exposed type-K thermocouple (0.3-1.5 s) through a converter
that completes a conversion every 100 ms and reads to 0.25 K with a cold-junction error. The load
and temperature columns always move and act only in their own effect's records (one load pattern
follows the temperature: a decoy correlated with it). The table of every case:
``python -m bench.plants blind11 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind11_cores import BLIND11_CORES, draw_params
from bench.plants.blind11_effects import BLIND11_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind11_protocols import BLIND11_PROTOCOLS, with_ringdown_conditioning
from bench.plants.blind11_rig import load_reading, pressure_reading, sensor_pressure, thermocouple_reading
from bench.plants.engine import Calibration, Case, FamilySpec, Record, plant_first, shifted
from bench.plants.recording import Sensors, recorded

BLIND11_PLANTS = tuple(BLIND11_CORES)
BLIND11_RATES_HZ = (58.0, 236.0, 540.0, 142.0, 396.0, 310.0)
NOISE_MM = {
    "runin_crossings": 0.016,
    "wrapped_tiedown": 0.019,
    "contact_births": 0.011,
    "wire_rope_return": 0.026,
}
QUANT_MM = {
    "runin_crossings": 0.002,
    "wrapped_tiedown": 0.004,
    "contact_births": 0.001,
    "wire_rope_return": 0.002,
}
LOAD_READ_KG = 1e-9  # the load converter's counts make the real step (per plant); this only rounds floats
TEMP_READ_K = 0.25  # the thermocouple converter's step
NONE_PER_PLANT = 5
SEED_BASE = 51000
SEED_OFFSET = 330_000  # measurement noise seeded at case.seed + 330_000, independent of the plant draws
SENSORS = {p: Sensors(SEED_OFFSET, QUANT_MM[p], 0.0, LOAD_READ_KG, 0.0, TEMP_READ_K) for p in NOISE_MM}


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The input read by the transducer's converter, the load through the amplifier and its 12-bit
    converter, the temperature by the thermocouple's converter."""
    params, dt = sim["truth"]["plant_parameters"], 1.0 / case.rate_hz
    read_input = pressure_reading(sim["u"], params, np.random.default_rng(case.seed + SEED_OFFSET + 1))
    read_load = load_reading(sim["load"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 2))
    read_temp = thermocouple_reading(sim["temperature"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 3))
    return recorded(
        case, {**sim, "u": read_input, "load": read_load, "temperature": read_temp}, spec.sensors[case.plant]
    )


SPEC = FamilySpec(
    name="blind11",
    cores=BLIND11_CORES,
    forms=BLIND11_FORMS,
    protocols=tuple(BLIND11_PROTOCOLS),
    rates_hz=BLIND11_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(3, 4),
    excite=with_ringdown_conditioning,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=plant_first(render),
    intensity_key=INTENSITY_KEY,
    sensors=SENSORS,
    none_per_plant=NONE_PER_PLANT,
    # the generic creep, rate and loop checks (new to it) run under -m slow
    tags=frozenset(
        {
            "slow:check_creep_forms_keep_moving_in_a_hold",
            "slow:check_rate_forms_grow_with_the_input_speed",
            "slow:check_core_draws_a_closed_loop",
        }
    ),
    read=_read,
    recorded_input=lambda r: sensor_pressure(r.u, r.dt, r.params),
    calibration=Calibration(),
)
