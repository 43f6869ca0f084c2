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
(:func:`bench.plants.blind5_family.calibrate`: up to three proportional passes, at most 3 x from
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
``python -m bench.plants.blind11_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_family import calibrate
from bench.plants.blind11_cores import BLIND11_CORES, draw_params
from bench.plants.blind11_effects import BLIND11_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind11_protocols import BLIND11_PROTOCOLS, with_ringdown_conditioning
from bench.plants.blind11_rig import load_reading, pressure_reading, sensor_pressure, thermocouple_reading
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
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
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind11_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind11 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets several protocols and rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND11_PROTOCOLS), len(BLIND11_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND11_PLANTS):
        for effect, forms in BLIND11_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + 3 * p_index) % len(protocols)]
                    rate = BLIND11_RATES_HZ[(i + 4 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the transducer's
    channel, noise-free: :func:`measurement_from` adds the converter's noise and step), the set
    pressure ``command`` [bar] the regulator got, the true columns and the truth."""
    if case.plant not in BLIND11_CORES:
        raise KeyError(f"unknown blind11 plant {case.plant!r}; known: {', '.join(BLIND11_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_ringdown_conditioning(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    share = float(np.exp(rng.uniform(*np.log(TARGET_OVER_SPAN))))
    noise = NOISE_MM[case.plant]
    base = BLIND11_CORES[case.plant](u, dt, params)
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
    sim = {"t": t, "u": sensor_pressure(u, dt, params), "command": u, "on": on, "off": off, "base": base}
    return {**sim, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant;
    the input read by the transducer's converter, the load through the amplifier and its 12-bit
    converter, the temperature by the thermocouple's converter)."""
    params = sim["truth"]["plant_parameters"]
    dt = 1.0 / case.rate_hz
    read_input = pressure_reading(sim["u"], params, np.random.default_rng(case.seed + SEED_OFFSET + 1))
    read_load = load_reading(sim["load"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 2))
    read_temp = thermocouple_reading(sim["temperature"], dt, params, np.random.default_rng(case.seed + SEED_OFFSET + 3))
    return recorded(case, {**sim, "u": read_input, "load": read_load, "temperature": read_temp}, SENSORS[case.plant])


def blind11_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind11_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
