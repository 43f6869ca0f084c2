"""A tenth, truly blind held-out plant family for ``pmactl diagnose`` (blind8).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind8_cores`): a natural-rubber bladder that crystallises
  under strain (Ivshin-Pence phase kinetics, a one-reversal memory) relieving its Mooney-Rivlin
  resistance, on a Chou-Hannaford braid; Dafalias-Popov bounding-surface plasticity of the braid's
  friction on a datasheet chart (PCHIP); Cattaneo-Mindlin partial slip at Hertzian fibre
  crossings (an Iwan set with Mindlin's backbone, slip force ``~ N``, slip distance ``~ N^(2/3)``)
  on a thick-walled Chou-Hannaford map; a multi-leaf return spring with Fancher's interleaf
  friction on an arctangent stroke map.
* Five protocols (:mod:`bench.plants.blind8_protocols`): an ATC-24 incremental cyclic test,
  sine-on-random, a hand pump with a bleed valve, leak-down tests, a cycloidal cam; each starts
  vented and is shaken down by four trapezoids to the top in its first ~7 s.
* Every effect in two new forms (:mod:`bench.plants.blind8_effects`), all acting on the
  contraction after the core.
* Sample rates 48, 78, 117, 196, 270 and 512 Hz (none used by the other families).

Effect sizes are spread over the band: each effect record draws a target size, log-uniform in
1-10 % of the span (at least 6 x its noise), and the form's intensity is calibrated to it
(:func:`bench.plants.blind5_family.calibrate`: up to three proportional passes, at most 3 x from
the drawn intensity either way, recorded in the truth as ``target_over_span`` and
``calibration``); then, as in every held-out family,
:func:`bench.plants.visibility.visible_effect` makes sure the size lies in ``[5 x noise, 12 %
of span]`` (its rescale recorded too).

Confounds in every record, effect-free ones too (:mod:`bench.plants.blind8_rig`): a proportional
valve with a slew-limited set point (6-15 x the peak per second) and a 10-30 ms lag; the
transducer in the muscle's inlet reading the flow noise of the jet past its port (0.3-1 % of the
peak at full flow); its noise (2-6 mbar) and step (2-5 mbar); a SAR stroke converter with
mismatched bit weights (jumps of a few um at its carries); the stroke amplifier's auto-zero
steps (3-8 um every 20-40 s); the DAQ's second-order Butterworth anti-alias filters on both
channels (0.3-0.4 x the rate, 2-5 % apart); stroke noise 0.012-0.03 mm and a reading step of
0.002-0.02 mm per plant; load (read to 0.004 kg) and temperature (read to 1/32 K, an RTD
converter's step) columns that always move and act only in their own effect's records (one
temperature pattern follows the muscle's vents: a decoy correlated with the input's falls).
The table of every case: ``python -m bench.plants.blind8_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind5_family import calibrate
from bench.plants.blind8_cores import BLIND8_CORES, draw_params
from bench.plants.blind8_effects import BLIND8_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind8_protocols import BLIND8_PROTOCOLS, with_shakedown
from bench.plants.blind8_rig import muscle_pressure, pressure_reading, recorded_pressure
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
BLIND8_PLANTS = tuple(BLIND8_CORES)
BLIND8_RATES_HZ = (48.0, 196.0, 512.0, 78.0, 270.0, 117.0)
NOISE_MM = {
    "crystallising_bladder": 0.018,
    "bounding_surface_braid": 0.03,
    "mindlin_crossings": 0.012,
    "fancher_leaf_spring": 0.024,
}
QUANT_MM = {
    "crystallising_bladder": 0.005,
    "bounding_surface_braid": 0.02,
    "mindlin_crossings": 0.002,
    "fancher_leaf_spring": 0.01,
}
LOAD_READ_KG, LOAD_NOISE_KG = 0.004, 0.004
TEMP_READ_K, TEMP_NOISE_K = 0.03125, 0.015
NONE_PER_PLANT = 5
SEED_BASE = 41000
SEED_OFFSET = 210_000  # measurement noise seeded at case.seed + 210_000, independent of the plant draws
SENSORS = {
    p: Sensors(SEED_OFFSET, QUANT_MM[p], LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K) for p in NOISE_MM
}
TARGET_OVER_SPAN = (0.01, 0.1)
TARGET_MIN_OVER_NOISE = 6.0
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


def blind8_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind8 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets several protocols and rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND8_PROTOCOLS), len(BLIND8_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND8_PLANTS):
        for effect, forms in BLIND8_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[(i + 3 * p_index) % len(protocols)]
                    rate = BLIND8_RATES_HZ[(i + 2 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the recorded input (the inlet
    transducer's channel, noise-free: :func:`measurement_from` adds the transducer's noise and
    step), the set pressure ``command`` [bar] the valve got, the columns and the truth."""
    if case.plant not in BLIND8_CORES:
        raise KeyError(f"unknown blind8 plant {case.plant!r}; known: {', '.join(BLIND8_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_shakedown(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    params = draw_params(case.plant, rng, peak)
    v = np.clip(muscle_pressure(u, dt, params) / peak, 0.0, None)
    load, temperature, load_pattern, temp_pattern = columns(t, v, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    share = float(np.exp(rng.uniform(*np.log(TARGET_OVER_SPAN))))
    noise = NOISE_MM[case.plant]
    base = BLIND8_CORES[case.plant](u, dt, params)
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
    sim = {"t": t, "u": recorded_pressure(u, dt, params), "command": u, "on": on, "off": off, "base": base}
    return {**sim, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS` of its plant;
    the input read by the inlet transducer)."""
    input_rng = np.random.default_rng(case.seed + SEED_OFFSET + 1)
    read_input = pressure_reading(sim["u"], sim["truth"]["plant_parameters"], input_rng)
    return recorded(case, {**sim, "u": read_input}, SENSORS[case.plant])


def blind8_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind8_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
