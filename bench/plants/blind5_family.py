"""A seventh, truly blind held-out plant family for ``pmactl diagnose`` (blind5).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind5_cores`): a vector play of crossed braid fibres on the
  curved (axial, hoop) path of a Chou-Hannaford muscle; a rolling lobe with peel and
  re-adhesion thresholds; a frictionless muscle read through a draw-wire sensor with stick-slip;
  a moving Prandtl-Ishlinskii braid with a negative-stiffness assist spring and lock-up.
* Five protocols (:mod:`bench.plants.blind5_protocols`): an equal-step pressure ladder with
  holds of 2-10 s, minor loops riding on a major triangle, pedal assist with wandering cadence,
  pick-and-place gripper cycles, blocks of trapezoids with dwells; each starts vented and does a
  valve sweep (first-order fill to the top and vent) in its first ~5 s.
* Every effect in two new forms (:mod:`bench.plants.blind5_effects`).
* Sample rates 84, 135, 192, 256, 375 and 440 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it (up to
three proportional passes, at most 3 x from the drawn intensity either way so that it stays
plausible, recorded in the truth as ``target_over_span`` and ``calibration``); then, as in
every held-out family, :func:`bench.plants.visibility.visible_effect` makes sure the size lies
in ``[5 x noise, 12 % of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind5_rig`): the supply
regulator's lag (25-70 ms) and its diaphragm's play (0.4-1.2 % of the peak), a pressure
transducer gain error (0.6-2 %) and offset in the recorded input, the mount settling
0.015-0.04 mm over 15-40 s, aliased mains hum of 4-12 um, 0.1-0.4 % dropped DAQ frames repeated on
every channel; stroke noise 0.012-0.03 mm and a reading step of 0.01-0.03 mm per plant; load
(read to 0.01 kg) and temperature (read to 0.02 K) columns that always move and act only in
their own effect's records. The table of every case: ``python -m bench.plants blind5 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind5_cores import BLIND5_CORES, draw_params
from bench.plants.blind5_effects import BLIND5_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind5_protocols import BLIND5_PROTOCOLS, with_valve_sweep
from bench.plants.blind5_rig import dropped_frames, transducer_reading
from bench.plants.engine import Calibration, Case, FamilySpec, Record, core_first, shifted
from bench.plants.recording import Sensors, recorded
from host.data import Measurement

BLIND5_PLANTS = tuple(BLIND5_CORES)
BLIND5_RATES_HZ = (84.0, 192.0, 375.0, 135.0, 440.0, 256.0)
NOISE_MM = {
    "vector_fibre_play": 0.02,
    "rolling_lobe_peel": 0.028,
    "drawwire_stickslip": 0.012,
    "moving_play_assist": 0.03,
}
QUANT_MM = {
    "vector_fibre_play": 0.01,
    "rolling_lobe_peel": 0.02,
    "drawwire_stickslip": 0.01,
    "moving_play_assist": 0.03,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.01, 0.006
TEMP_READ_K, TEMP_NOISE_K = 0.02, 0.02
NONE_PER_PLANT = 5
SEED_BASE = 27000
SEED_OFFSET = 110_000  # measurement noise seeded at case.seed + 110_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The frames the DAQ dropped repeat the frame before on every channel."""
    m, truth = recorded(case, sim, spec.sensors[case.plant])
    drops = dropped_frames(
        len(m), np.random.default_rng(case.seed + SEED_OFFSET + 1), sim["truth"]["plant_parameters"]["drop_share"]
    )
    y, u = m.y.copy(), m.u.copy()
    extras = {name: column.copy() for name, column in m.extras.items()}
    for i in drops.tolist():  # in order, so a run of drops repeats the last good frame
        y[i], u[i] = y[i - 1], u[i - 1]
        for column in extras.values():
            column[i] = column[i - 1]
    truth["dropped_frames"] = int(drops.size)
    return Measurement(m.t, u, y, extras, source=m.source), truth


SPEC = FamilySpec(
    name="blind5",
    cores=BLIND5_CORES,
    forms=BLIND5_FORMS,
    protocols=tuple(BLIND5_PROTOCOLS),
    rates_hz=BLIND5_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(1, 2),
    excite=with_valve_sweep,
    draw_params=draw_params,
    columns=lambda r, rng: columns(r.t, rng),
    draw_effect=draw_effect_params,
    render=core_first(render),
    intensity_key=INTENSITY_KEY,
    sensors=SENSORS,
    none_per_plant=NONE_PER_PLANT,
    read=_read,
    recorded_input=lambda r: transducer_reading(r.u, r.params),
    calibration=Calibration(),
)
