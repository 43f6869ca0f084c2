"""A twelfth, truly blind held-out plant family for ``pmactl diagnose`` (blind10).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind10_cores`), each on a Chou-Hannaford braid around a Gent
  bladder: Haessig-Friedland bristles between bladder and braid (bonds that snap and re-bond at
  random: a friction whose loops never repeat exactly); the braid's crossings as an
  Olami-Feder-Christensen lattice (slip avalanches of all sizes); twin muscles in parallel, the
  second fed through opposed check valves (an asymmetric play of the pressure from the pneumatic
  circuit); a snap-action over-centre spring on the carriage (one macroscopic snap each way) with
  a little Coulomb friction.
* Five protocols (:mod:`bench.plants.blind10_protocols`): a frequency-hopping sine, a
  crank-driven bellows, a bias ladder with a sine on every rung, the Lorenz system's chaos, a
  pneumatic relaxation oscillator; each starts vented and is shaken down by three sawtooth fills
  with quick exhausts in its first ~6 s.
* Every effect in two forms (:mod:`bench.plants.blind10_effects`): a plain textbook one in a new
  parameterisation (a linear dashpot held by the muscle's stiffness, first-order creep driven by
  the pressure, a pure dead time in the supply line, a linear compliance in the load path, a
  linear temperature coefficient of the gain) and an unusual one (the bladder's self-heating,
  Struik ageing creep, a PLC whose scan time grows with its workload, a rope's knots bedding in, an
  R-phase NiTi bias spring with thermal hysteresis).
* Sample rates 52, 128, 184, 264, 352 and 464 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.visibility.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family, :func:`bench.plants.visibility.visible_effect`
makes sure the size lies in ``[5 x noise, 12 % of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind10_rig`): an I/P
converter (15-35 ms) piloting a volume booster that exhausts faster than it fills (25-60 ms,
0.35-0.7 x on the way down); the recorded input from a 4-20 mA transmitter at the booster's
outlet that updates every 8-20 ms, with HART FSK bursts on its loop (aliased through the RC
anti-alias filter), read with 1.5-4 mbar of noise and a 12-bit step; a magnetostrictive stroke
sensor with a periodic nonlinearity (4-12 um), a bow (5-15 um) and triboelectric cable noise that
grows with the speed (3-8 um at 20 mm/s); stroke noise 0.012-0.03 mm and a reading step of
1-5 um per plant; a load column from a 24-bit bridge converter at 10 or 80 conversions per second
(held: stairs) and a temperature column from an NTC probe (1-4 s bead lag) through a 10-bit
divider (a non-uniform step). The load and temperature columns always move and act only in
their own effect's records (one temperature pattern follows the load's activity: a decoy
correlated with the load). The table of every case: ``python -m bench.plants blind10 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind10_cores import BLIND10_CORES, draw_params
from bench.plants.blind10_effects import BLIND10_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind10_protocols import BLIND10_PROTOCOLS, with_exhaust_shakedown
from bench.plants.blind10_rig import hx711_load, ntc_temperature, pressure_reading, recorded_pressure
from bench.plants.engine import Calibration, Case, FamilySpec, Record, plant_first, shifted
from bench.plants.recording import Sensors, recorded

BLIND10_PLANTS = tuple(BLIND10_CORES)
BLIND10_RATES_HZ = (52.0, 184.0, 464.0, 128.0, 352.0, 264.0)
NOISE_MM = {
    "bristle_bladder": 0.016,
    "avalanche_crossings": 0.024,
    "check_valve_twin": 0.012,
    "overcentre_latch": 0.03,
}
QUANT_MM = {
    "bristle_bladder": 0.002,
    "avalanche_crossings": 0.001,
    "check_valve_twin": 0.005,
    "overcentre_latch": 0.002,
}
TEMP_READ_K = 1e-6  # the NTC's counts make the real (non-uniform) step; this only rounds floats
NONE_PER_PLANT = 5
SEED_BASE = 47000
SEED_OFFSET = 290_000  # measurement noise seeded at case.seed + 290_000, independent of the plant draws
LOAD_STEP_KG = 0.0005  # the bridge converter's count, as scaled
SENSORS = {p: Sensors(SEED_OFFSET, QUANT_MM[p], 0.0, LOAD_STEP_KG, 0.0, TEMP_READ_K) for p in NOISE_MM}


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The input read by the transmitter's converter, the load by the bridge converter, held
    between conversions, the temperature by the NTC probe and its 10-bit divider."""
    params, dt = sim["truth"]["plant_parameters"], 1.0 / case.rate_hz
    read_input = pressure_reading(sim["u"], params, np.random.default_rng(case.seed + SEED_OFFSET + 1))
    read_load = hx711_load(sim["load"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 2))
    read_temp = ntc_temperature(sim["temperature"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 3))
    return recorded(
        case, {**sim, "u": read_input, "load": read_load, "temperature": read_temp}, spec.sensors[case.plant]
    )


SPEC = FamilySpec(
    name="blind10",
    cores=BLIND10_CORES,
    forms=BLIND10_FORMS,
    protocols=tuple(BLIND10_PROTOCOLS),
    rates_hz=BLIND10_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(3, 2),
    excite=with_exhaust_shakedown,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=plant_first(render),
    intensity_key=INTENSITY_KEY,
    sensors=SENSORS,
    none_per_plant=NONE_PER_PLANT,
    # its creep is checked by its own test over 3-28 s (tests/test_blind10_forms.py); its self-heating rate form
    # does not grow on the generic 4 s triangles; it never promised the generic loop and fails it
    tags=frozenset(
        {
            "check_creep_forms_keep_moving_in_a_hold",
            "check_rate_forms_grow_with_the_input_speed",
            "check_core_draws_a_closed_loop",
        }
    ),
    read=_read,
    recorded_input=lambda r: recorded_pressure(r.u, r.dt, r.params),
    calibration=Calibration(),
)
