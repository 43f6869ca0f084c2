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
(:func:`bench.plants.blind5_family.calibrate`: up to three proportional passes, at most 3 x from
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
The table of every case: ``python -m bench.plants.blind9_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_family import calibrate
from bench.plants.blind9_cores import BLIND9_CORES, draw_params, normalised_pressure
from bench.plants.blind9_effects import BLIND9_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind9_protocols import BLIND9_PROTOCOLS, with_shakedown
from bench.plants.blind9_rig import load_cell_zero_shift, pressure_reading, recorded_pressure
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
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
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind9_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind9 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets several protocols and rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND9_PROTOCOLS), len(BLIND9_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND9_PLANTS):
        for effect, forms in BLIND9_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + 2 * p_index) % len(protocols)]
                    rate = BLIND9_RATES_HZ[(i + 2 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the manifold
    transducer's channel, noise-free: :func:`measurement_from` adds the converter's noise and
    step), the set pressure ``command`` [bar] the valves got, the columns and the truth."""
    if case.plant not in BLIND9_CORES:
        raise KeyError(f"unknown blind9 plant {case.plant!r}; known: {', '.join(BLIND9_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_shakedown(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    params = draw_params(case.plant, rng, peak)
    v = np.clip(normalised_pressure(u, dt, params), 0.0, None)
    load, temperature, load_pattern, temp_pattern = columns(t, v, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    share = float(np.exp(rng.uniform(*np.log(TARGET_OVER_SPAN))))
    noise = NOISE_MM[case.plant]
    base = BLIND9_CORES[case.plant](u, dt, params)
    if case.effect in LOAD_TEMP_EFFECTS:  # the same plant with its column held still
        held_load, held_temp = np.full_like(load, load[0]), np.full_like(temperature, temperature[0])
        off = render(case.plant, params, u, dt, case.form, q, held_load, held_temp, base)
    else:
        off = render(case.plant, params, u, dt, "none", q, load, temperature, base)

    memo: dict[float, Array] = {}

    def with_effect() -> Array:
        key_value = q.get(INTENSITY_KEY.get(case.form, ""), 0.0)
        if key_value not in memo:
            memo.clear()
            memo[key_value] = render(case.plant, params, u, dt, case.form, q, load, temperature, base)
        return memo[key_value]

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    if case.effect != "none":
        target = max(share * float(np.ptp(off)), TARGET_MIN_OVER_NOISE * noise)
        q["target_over_span"] = target / float(np.ptp(off))
        calibrate(with_effect, off, q, key, target)
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    sim = {"t": t, "u": recorded_pressure(u, dt, params), "command": u, "on": on, "off": off, "base": base}
    return {**sim, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant;
    the input read by the manifold's transducer, the load by a bridge with a thermal zero shift)."""
    params = sim["truth"]["plant_parameters"]
    input_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    read_input = pressure_reading(sim["u"], params, input_rng)
    read_load = sim["load"] + load_cell_zero_shift(sim["temperature"], params)
    return recorded(case, {**sim, "u": read_input, "load": read_load}, SENSORS[case.plant])


def blind9_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind9_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
