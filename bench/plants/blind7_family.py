"""A ninth, truly blind held-out plant family for ``pmactl diagnose`` (blind7).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind7_cores`): a random-field Ising chain of braid crossings
  (avalanches, a lattice memory) on a reduced Sarosi (exponential-linear) force map; a
  Prandtl-Tomlinson carriage on a cogged rail (multistable wells, stick-slip jumps) on a cubic
  force map; a Valanis endochronic sleeve (a fading hereditary memory over the pressure's path
  length) on a hyperbolic force map; a twist-coupled braid whose end cap turns in a thrust
  bearing (a play in a hidden angle, its radius set by the stroke) on an exponential-saturation
  stroke map.
* Five protocols (:mod:`bench.plants.blind7_protocols`): relay autotuning, fatigue cycling with
  reference cycles, a DMA amplitude sweep, an oscillometric cuff (stepwise deflation), an ISO
  230-2 bidirectional positioning test; each starts vented and is preconditioned by three
  haversine cycles to the top in its first ~6 s.
* Every effect in two new forms (:mod:`bench.plants.blind7_effects`), all acting on the
  contraction after the core.
* Sample rates 44, 87, 138, 212, 365 and 560 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.blind5_family.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family,
:func:`bench.plants.visibility.visible_effect` makes sure the size lies in ``[5 x noise, 12 %
of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind7_rig`): a PWM-driven
valve (8-25 ms lag, a 90-210 Hz ripple of 0.3-1 % of the peak, aliased in the recorded input);
the recorded pressure taken at the valve's outlet, so it leads the muscle's by the hose's lag
(10-30 ms); the pressure transducer's noise (2-6 mbar) and converter step (2-5 mbar); the
multiplexer's channel skew (the stroke converted 0.1-0.6 ms after its time stamp); popcorn
(random telegraph) noise of 5-15 um on the stroke amplifier; stroke noise 0.011-0.026 mm and a
reading step of 0.0025-0.02 mm per plant; load (read to 0.005 kg) and temperature (read to
1/16 K, a digital thermometer's step) columns that always move and act only in their own
effect's records (one temperature pattern follows the valve's duty: a decoy correlated with the
input's slow mean). The table of every case: ``python -m bench.plants.blind7_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_family import calibrate
from bench.plants.blind7_cores import BLIND7_CORES, draw_params
from bench.plants.blind7_effects import BLIND7_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind7_protocols import BLIND7_PROTOCOLS, with_preconditioning
from bench.plants.blind7_rig import pressure_reading, valve_pressure
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
BLIND7_PLANTS = tuple(BLIND7_CORES)
BLIND7_RATES_HZ = (44.0, 212.0, 560.0, 87.0, 365.0, 138.0)
NOISE_MM = {
    "ising_crossings": 0.014,
    "detent_carriage": 0.02,
    "endochronic_sleeve": 0.026,
    "twist_bearing": 0.011,
}
QUANT_MM = {
    "ising_crossings": 0.004,
    "detent_carriage": 0.01,
    "endochronic_sleeve": 0.02,
    "twist_bearing": 0.0025,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.005, 0.003
TEMP_READ_K, TEMP_NOISE_K = 0.0625, 0.02
NONE_PER_PLANT = 5
SEED_BASE = 39000
SEED_OFFSET = 170_000  # measurement noise seeded at case.seed + 170_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind7_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind7 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets several protocols and rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND7_PROTOCOLS), len(BLIND7_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND7_PLANTS):
        for effect, forms in BLIND7_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + 3 * p_index) % len(protocols)]
                    rate = BLIND7_RATES_HZ[(i + 2 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the pressure at the
    valve's outlet, noise-free: :func:`measurement_from` adds the transducer's noise and step),
    the set pressure ``command`` [bar] the valve got, the columns and the truth."""
    if case.plant not in BLIND7_CORES:
        raise KeyError(f"unknown blind7 plant {case.plant!r}; known: {', '.join(BLIND7_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_preconditioning(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, u, peak, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    share = float(np.exp(rng.uniform(*np.log(TARGET_OVER_SPAN))))
    noise = NOISE_MM[case.plant]
    base = BLIND7_CORES[case.plant](u, dt, params)
    if case.effect in LOAD_TEMP_EFFECTS:  # the same plant with its column held still
        held_load, held_temp = np.full_like(load, load[0]), np.full_like(temperature, temperature[0])
        off = render(params, u, dt, case.form, q, held_load, held_temp, base)
    else:
        off = render(params, u, dt, "none", q, load, temperature, base)

    memo: dict[float, Array] = {}

    def with_effect() -> Array:
        key_value = q.get(INTENSITY_KEY.get(case.form, ""), 0.0)
        if key_value not in memo:
            memo.clear()
            memo[key_value] = render(params, u, dt, case.form, q, load, temperature, base)
        return memo[key_value]

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    if case.effect != "none":
        target = max(share * float(np.ptp(off)), TARGET_MIN_OVER_NOISE * noise)
        q["target_over_span"] = target / float(np.ptp(off))
        calibrate(with_effect, off, q, key, target)
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    sim = {"t": t, "u": valve_pressure(u, dt, params), "command": u, "on": on, "off": off, "base": base}
    return {**sim, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant;
    the input read by the pressure transducer)."""
    input_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    read_input = pressure_reading(sim["u"], sim["truth"]["plant_parameters"], input_rng)
    return recorded(case, {**sim, "u": read_input}, SENSORS[case.plant])


def blind7_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind7_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
