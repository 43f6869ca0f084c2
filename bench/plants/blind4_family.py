"""A sixth, truly blind held-out plant family for ``pmactl diagnose`` (blind4).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind4_cores`): extended-Masing friction in pressure on a
  Tondu-Lopez muscle; a sleeve muscle with the Tellinen rule between two limiting branches; a
  Tondu-Lopez muscle with Bliman-Sorine (break-away peak) friction in path length; an ensemble of
  Stoner-Wohlfarth two-well crimps on a reversible envelope.
* Five protocols (:mod:`bench.plants.blind4_protocols`): two opposed chirps, respiratory
  assist, degaussing cycles, Levy-flight set points, a sine through a 4-bit DAC; each starts
  vented and does an S-curve sweep (top and back to vented) in its first ~5 s.
* Every effect in two new forms (:mod:`bench.plants.blind4_effects`).
* Sample rates 72, 96, 144, 180, 320 and 420 Hz (none used by the other families).

Every effect record is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same record with it off) lies in ``[5 x noise, 12 % of span]`` through
:func:`bench.plants.visibility.scale_into_band` (the rescale is recorded in the truth).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind4_rig`): a supply droop
as the compressor cycles (0.4-1.2 % over 25-60 s), the linkage backlash plus the guide's friction
(a play of 0.08-0.23 mm), a compliant mounting plate (6-20 Hz), and the transducer's own
thermal offset wander (not the temperature column's), 1/f noise and rare clipped spikes; sensor
noise 0.015-0.04 mm per plant with 0.02 mm quantisation; load (read to 0.005 kg) and
temperature (read to 0.05 K) columns that always move and act only in their own effect's
records. The table of every case: ``python -m bench.plants blind4 100``.
"""

from __future__ import annotations

from bench.plants.blind4_cores import BLIND4_CORES, draw_params
from bench.plants.blind4_effects import BLIND4_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind4_protocols import BLIND4_PROTOCOLS, with_s_sweep
from bench.plants.blind4_rig import supply_droop
from bench.plants.engine import FamilySpec, core_first, shifted
from bench.plants.recording import Sensors

BLIND4_PLANTS = tuple(BLIND4_CORES)
BLIND4_RATES_HZ = (72.0, 144.0, 320.0, 96.0, 420.0, 180.0)
NOISE_MM = {"masing_tondu": 0.025, "tellinen_sleeve": 0.035, "bliman_sorine": 0.04, "stoner_crimps": 0.015}
QUANT_MM = 0.02
LOAD_READ_KG, LOAD_NOISE_KG = 0.005, 0.008
TEMP_READ_K, TEMP_NOISE_K = 0.05, 0.03
NONE_PER_PLANT = 5
SEED_BASE = 21000
# measurement noise seeded at case.seed + 70_000, independent of the plant draws
SENSORS = Sensors(70_000, QUANT_MM, LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K)


SPEC = FamilySpec(
    name="blind4",
    cores=BLIND4_CORES,
    forms=BLIND4_FORMS,
    protocols=tuple(BLIND4_PROTOCOLS),
    rates_hz=BLIND4_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(1, 2),
    excite=with_s_sweep,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=core_first(render),
    intensity_key=INTENSITY_KEY,
    sensors={p: SENSORS for p in NOISE_MM},
    none_per_plant=NONE_PER_PLANT,
    promises={"rate_growth": 3.0},
    # its measurement noise is seeded at the same offset as blind2's (70 000); its creep is checked over the
    # core without the supply droop by its own test (tests/test_blind4_family.py)
    tags=frozenset({"shares_seed_offset", "check_creep_forms_keep_moving_in_a_hold"}),
    base=lambda r: r.core(supply_droop(r.u, r.dt, r.params), r.dt, r.params),
)
