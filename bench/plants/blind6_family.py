"""An eighth, truly blind held-out plant family for ``pmactl diagnose`` (blind6).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind6_cores`): a pleated (Daerden) muscle with Berg's
  hyperbolic rubber friction; a Rayleigh-law braid (quadratic branches, wiping-out memory) on an
  exponential-force muscle solved with the Lambert W; a quadratic-force muscle whose carriage
  runs in a friction wedge (a Coulomb limit growing with the stroke, presliding); a braid with
  slip-lock *pinching* (generalised plays that collapse in a pressure band) on a logistic map.
* Five protocols (:mod:`bench.plants.blind6_protocols`): an EMG-proportional envelope,
  cardiac-assist pulses, a teleoperated joystick, creep-recovery blocks, a rate decade of
  triangles; each starts vented and does a choked-flow sweep (fill to the top and vent) in its
  first ~5 s.
* Every effect in two new forms (:mod:`bench.plants.blind6_effects`).
* Sample rates 66, 105, 168, 232, 345 and 490 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.visibility.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family,
:func:`bench.plants.visibility.visible_effect` makes sure the size lies in ``[5 x noise, 12 %
of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind6_rig`): a second-order
spool valve (6-14 Hz, damping 0.55-0.8), the recorded input read through the transducer's
snubber (a 4-15 ms lag behind the muscle's pressure), compressor vibration bursts on the frame
(8-25 um at 23-31 Hz), the multiplexer's crosstalk of the pressure into the stroke channel
(10-40 um at full pressure), the DAQ's sampling jitter (20-100 us RMS) on every channel; stroke
noise 0.01-0.028 mm and a reading step of 0.005-0.025 mm per plant; load (read to 0.002 kg) and
temperature (read to 0.025 K) columns that always move and act only in their own effect's
records. The table of every case: ``python -m bench.plants blind6 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind6_cores import BLIND6_CORES, draw_params
from bench.plants.blind6_effects import BLIND6_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind6_protocols import BLIND6_PROTOCOLS, with_choked_sweep
from bench.plants.blind6_rig import aperture_jitter, snubbed_reading
from bench.plants.engine import Calibration, Case, FamilySpec, Record, core_first, shifted
from bench.plants.recording import Sensors, recorded

BLIND6_PLANTS = tuple(BLIND6_CORES)
BLIND6_RATES_HZ = (66.0, 232.0, 490.0, 105.0, 345.0, 168.0)
NOISE_MM = {
    "pleated_berg": 0.016,
    "rayleigh_lambert": 0.022,
    "wedge_damper": 0.028,
    "pinched_sliplock": 0.01,
}
QUANT_MM = {
    "pleated_berg": 0.005,
    "rayleigh_lambert": 0.015,
    "wedge_damper": 0.025,
    "pinched_sliplock": 0.005,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.002, 0.004
TEMP_READ_K, TEMP_NOISE_K = 0.025, 0.03
NONE_PER_PLANT = 5
SEED_BASE = 33000
SEED_OFFSET = 130_000  # measurement noise seeded at case.seed + 130_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """Every channel sampled with the DAQ's aperture jitter (time stamps nominal)."""
    dt = 1.0 / case.rate_hz
    jitter_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    jitter = jitter_rng.normal(0.0, sim["truth"]["plant_parameters"]["jitter_s"], sim["on"].size)
    jittered = {**sim, "on": aperture_jitter(sim["on"], dt, jitter), "u": aperture_jitter(sim["u"], dt, jitter)}
    for name in ("load", "temperature"):
        jittered[name] = aperture_jitter(sim[name], dt, jitter)
    m, truth = recorded(case, jittered, spec.sensors[case.plant])
    truth["jitter_s"] = float(np.std(jitter))
    return m, truth


SPEC = FamilySpec(
    name="blind6",
    cores=BLIND6_CORES,
    forms=BLIND6_FORMS,
    protocols=tuple(BLIND6_PROTOCOLS),
    rates_hz=BLIND6_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(2, 1),
    excite=with_choked_sweep,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=core_first(render),
    intensity_key=INTENSITY_KEY,
    sensors=SENSORS,
    none_per_plant=NONE_PER_PLANT,
    # its own creep test is the generic one and more (tests/test_blind6_family.py)
    tags=frozenset({"check_creep_forms_keep_moving_in_a_hold"}),
    read=_read,
    recorded_input=lambda r: snubbed_reading(r.u, r.dt, r.params),
    calibration=Calibration(),
)
