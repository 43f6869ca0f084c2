"""A fourth, truly blind held-out plant family for ``pmactl diagnose`` (blind2).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind2_cores`): a Jiles-Atherton-type Duhem model with a
  saturating anhysteretic curve; an antagonistic muscle pair on a joint (one muscle at the
  input, one at a fixed bias) whose bearing friction is loaded by the cable tensions; a
  dead-band valve and a Chou-Hannaford muscle with braid friction that grows with pressure; a
  Bowden cable's capstan friction between a muscle and a pretensioned exo joint.
* Five protocols (:mod:`bench.plants.blind2_protocols`): gait cycles, an amplitude-modulated
  sine, sawtooth trains, setpoint tracking, PWM chamber pressure; each starts vented and does a
  full-range check in its first ~4 s (the hysteresis memory is known early).
* Every effect in two new forms (:mod:`bench.plants.blind2_effects`).
* Sample rates 70, 120, 175, 240, 333 and 480 Hz (none used by the other families).

Every effect record is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same record with it off) lies in ``[5 x noise, 12 % of span]`` through
:func:`bench.plants.visibility.scale_into_band` (the rescale is recorded in the truth).

Confounds in every record, effect-free ones too: valve lag and a slow thermal pressure tail
(1.5-4 s), a mechanical resonance (3-20 Hz), dead bands and slack cables, sensor noise
0.02-0.05 mm per plant with 0.01 mm quantisation, load (read to 0.005 kg) and temperature
(read to 0.05 K) columns that always move and act only in their own effect's records.
The table of every case: ``python -m bench.plants blind2 100``.
"""

from __future__ import annotations

from bench.plants.blind2_cores import BLIND2_CORES, draw_params
from bench.plants.blind2_effects import BLIND2_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind2_protocols import BLIND2_PROTOCOLS, with_range_check
from bench.plants.engine import FamilySpec, over_off
from bench.plants.recording import Sensors

BLIND2_PLANTS = tuple(BLIND2_CORES)
BLIND2_RATES_HZ = (70.0, 175.0, 333.0, 480.0, 120.0, 240.0)
NOISE_MM = {"ja_duhem": 0.025, "antagonistic_joint": 0.04, "braid_deadband": 0.02, "capstan_exo": 0.05}
QUANT_MM = 0.01
LOAD_READ_KG, LOAD_NOISE_KG = 0.005, 0.008
TEMP_READ_K, TEMP_NOISE_K = 0.05, 0.03
NONE_PER_PLANT = 5
SEED_BASE = 12000
# measurement noise seeded at case.seed + 70_000, independent of the plant draws
SENSORS = Sensors(70_000, QUANT_MM, LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K)


SPEC = FamilySpec(
    name="blind2",
    cores=BLIND2_CORES,
    forms=BLIND2_FORMS,
    protocols=tuple(BLIND2_PROTOCOLS),
    rates_hz=BLIND2_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=lambda i, p: (i, i // len(BLIND2_PROTOCOLS)),
    excite=with_range_check,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=over_off(render),
    intensity_key=INTENSITY_KEY,
    sensors={p: SENSORS for p in NOISE_MM},
    none_per_plant=NONE_PER_PLANT,
    promises={"rate_growth": 3.0, "creep_sign": 1.0, "loop_cycles": 3, "loop_settled_share": 0.01},
    base=lambda r: None,
)
