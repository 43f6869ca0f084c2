"""A fifth, truly blind held-out plant family for ``pmactl diagnose`` (blind3).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind3_cores`): a chain of bistable bellows folds under mixed
  loading (avalanches of snaps); a power-law muscle with Armstrong-Frederick elasto-plastic braid
  friction; a textile-sleeve muscle (slack, then taut and jamming) with contact-pressure Dahl
  friction; a mass on a guide with Karnopp stick-slip friction.
* Five protocols (:mod:`bench.plants.blind3_protocols`): a Schroeder multisine on a slow offset,
  a speed ladder of full-range ramps, a stepped sine, dithered triangles, minimum-jerk reaching;
  each starts vented and does a full sweep (top and back to vented) in its first ~5 s.
* Every effect in two new forms (:mod:`bench.plants.blind3_effects`).
* Sample rates 64, 110, 160, 220, 280 and 360 Hz (none used by the other families).

Every effect record is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same record with it off) lies in ``[5 x noise, 12 % of span]`` through
:func:`bench.plants.visibility.scale_into_band` (the rescale is recorded in the truth).

Confounds in every record, effect-free ones too: a two-lag valve and a slow thermal pressure
tail (1.5-4 s), a mechanical resonance (4-20 Hz), and two that no other family has: the stroke
transducer's integral nonlinearity (a bow and a ripple, 0.1-0.35 mm) and mains hum (50 or 60 Hz,
8-20 um, aliased by the low rates) on its cable; sensor noise 0.02-0.055 mm per plant with
0.01 mm quantisation; load (read to 0.01 kg) and temperature (read to 0.1 K) columns that always
move and act only in their own effect's records. The table of every case:
``python -m bench.plants blind3 100``.
"""

from __future__ import annotations

from bench.plants.blind3_cores import BLIND3_CORES, draw_params
from bench.plants.blind3_effects import BLIND3_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind3_protocols import BLIND3_PROTOCOLS, with_full_sweep
from bench.plants.engine import FamilySpec, core_first
from bench.plants.recording import Sensors

BLIND3_PLANTS = tuple(BLIND3_CORES)
BLIND3_RATES_HZ = (64.0, 110.0, 160.0, 220.0, 280.0, 360.0)
NOISE_MM = {"bistable_bellows": 0.035, "af_braid": 0.02, "sleeve_dahl": 0.045, "karnopp_stickslip": 0.055}
QUANT_MM = 0.01
LOAD_READ_KG, LOAD_NOISE_KG = 0.01, 0.01
TEMP_READ_K, TEMP_NOISE_K = 0.1, 0.04
NONE_PER_PLANT = 5
SEED_BASE = 15000
# measurement noise seeded at case.seed + 90_000, independent of the plant draws
SENSORS = Sensors(90_000, QUANT_MM, LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K)

# the plant shifts the protocol and the half shifts the rate, so one form meets four protocols
# and four rates over the four plants
HALF = len(BLIND3_CORES) * (NONE_PER_PLANT + sum(len(f) for e, f in BLIND3_FORMS.items() if e != "none")) // 2


SPEC = FamilySpec(
    name="blind3",
    cores=BLIND3_CORES,
    forms=BLIND3_FORMS,
    protocols=tuple(BLIND3_PROTOCOLS),
    rates_hz=BLIND3_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=lambda i, p: (i + p, i + i // HALF),
    excite=with_full_sweep,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=core_first(render),
    intensity_key=INTENSITY_KEY,
    sensors={p: SENSORS for p in NOISE_MM},
    none_per_plant=NONE_PER_PLANT,
    promises={"rate_growth": 3.0, "creep_sign": -1.0},
)
