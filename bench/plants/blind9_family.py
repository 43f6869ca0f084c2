"""An eleventh, truly blind held-out plant family for ``pmactl diagnose`` (blind9).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind9_cores`), each a hysteretic force put back into a
  Chou-Hannaford muscle's force balance (so its width in stroke follows the muscle's stiffness):
  a superelastic NiTi return wire (Graesser-Cozzarelli: Ozdemir's rate-independent plasticity
  with a superelastic back stress, a flag-shaped loop); a granular jamming sleeve (Mohr-Coulomb
  yield and Hertz-Mindlin stiffness under the bladder's confinement, the packing relaxing to its
  critical state with slip); a Mullins-softened bladder (Ogden-Roxburgh max-memory) on a braid
  with pressure-dependent Coulomb friction; an Iwan set of crossings with static friction above
  kinetic (a breakaway bump after each reversal).
* Five protocols (:mod:`bench.plants.blind9_protocols`): endurance blocks with vented rests, a
  pseudo-random binary sequence, a staircase through an underdamped pressure loop, human
  tracking with reaction delay and tremor, a descending logarithmic sine sweep; each starts
  vented and is shaken down by four raised-cosine pulses to the top in its first ~6 s.
* Every effect in two new forms (:mod:`bench.plants.blind9_effects`), one acting inside the
  core (the force balance or the muscle's pressure), one on the contraction or its reading.
* Sample rates 56, 112, 164, 228, 304 and 416 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.visibility.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family, :func:`bench.plants.visibility.visible_effect`
makes sure the size lies in ``[5 x noise, 12 % of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind9_rig`): on/off valves
PWM-driven at 23-47 Hz with a 9-10 bit duty (the muscle's pressure in small steps) averaged by
the muscle's volume (40-90 ms); the manifold's carrier ripple (0.1-0.4 % of the peak, aliased)
in the recorded input, read through a slew-limited amplifier, an RC anti-alias filter, noise
(2-5 mbar) and a converter step (1.5-4 mbar); a wire-wound string pot stepping from turn to
turn (8-20 um, irregular winding), ratiometric to a rail that dips with the solenoids' duty (a
gain error following the input), through its own RC filter; stroke noise 0.012-0.03 mm and a
reading step of 0.002-0.01 mm per plant; load (read to 0.002 kg, with the strain-gauge bridge's
thermal zero shift of 5-20 g/K) and temperature (read to 1/16 K, a one-wire sensor's step)
columns that always move and act only in their own effect's records (one temperature pattern
follows the muscle's fills and vents: a decoy correlated with the input).
The table of every case: ``python -m bench.plants blind9 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bench.plants.blind9_cores import BLIND9_CORES, draw_params, normalised_pressure
from bench.plants.blind9_effects import BLIND9_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind9_protocols import BLIND9_PROTOCOLS, with_shakedown
from bench.plants.blind9_rig import load_cell_zero_shift, pressure_reading, recorded_pressure
from bench.plants.engine import Calibration, Case, FamilySpec, Record, Run, plant_first, shifted
from bench.plants.recording import Sensors, recorded

BLIND9_PLANTS = tuple(BLIND9_CORES)
BLIND9_RATES_HZ = (56.0, 228.0, 416.0, 112.0, 304.0, 164.0)
NOISE_MM = {
    "nitinol_flag_return": 0.022,
    "jamming_sleeve": 0.014,
    "mullins_bladder": 0.03,
    "breakaway_crossings": 0.018,
}
QUANT_MM = {
    "nitinol_flag_return": 0.01,
    "jamming_sleeve": 0.002,
    "mullins_bladder": 0.005,
    "breakaway_crossings": 0.004,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.002, 0.003
TEMP_READ_K, TEMP_NOISE_K = 0.0625, 0.02
NONE_PER_PLANT = 5
SEED_BASE = 43000
SEED_OFFSET = 250_000  # measurement noise seeded at case.seed + 250_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}


def _columns(run: Run, rng: np.random.Generator) -> tuple[Any, Any, str, str]:
    """One temperature pattern follows the muscle's fills and vents (its normalised pressure)."""
    return columns(run.t, np.clip(normalised_pressure(run.u, run.dt, run.params), 0.0, None), rng)


def _read(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The input read by the manifold's transducer, the load by a bridge with a thermal zero shift."""
    params = sim["truth"]["plant_parameters"]
    read_input = pressure_reading(sim["u"], params, np.random.default_rng(case.seed + SEED_OFFSET + 1))
    read_load = sim["load"] + load_cell_zero_shift(sim["temperature"], params)
    return recorded(case, {**sim, "u": read_input, "load": read_load}, spec.sensors[case.plant])


SPEC = FamilySpec(
    name="blind9",
    cores=BLIND9_CORES,
    forms=BLIND9_FORMS,
    protocols=tuple(BLIND9_PROTOCOLS),
    rates_hz=BLIND9_RATES_HZ,
    noise_mm=NOISE_MM,
    seed_base=SEED_BASE,
    rotate=shifted(2, 2),
    excite=with_shakedown,
    draw_params=draw_params,
    columns=_columns,
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
    recorded_input=lambda r: recorded_pressure(r.u, r.dt, r.params),
    calibration=Calibration(),
)
