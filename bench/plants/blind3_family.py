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
``python -m bench.plants.blind3_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind3_cores import BLIND3_CORES, draw_params
from bench.plants.blind3_effects import BLIND3_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind3_protocols import BLIND3_PROTOCOLS, with_full_sweep
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
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


def blind3_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind3 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets four protocols and four rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND3_PROTOCOLS), len(BLIND3_RATES_HZ)
    per_plant = NONE_PER_PLANT + sum(len(forms) for effect, forms in BLIND3_FORMS.items() if effect != "none")
    half = len(BLIND3_PLANTS) * per_plant // 2
    i = 0
    for p_index, plant in enumerate(BLIND3_PLANTS):
        for effect, forms in BLIND3_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    # the plant shifts the protocol and the half shifts the rate, so one form meets
                    # four protocols and four rates over the four plants
                    protocol = protocols[(i + p_index) % len(protocols)]
                    rate = BLIND3_RATES_HZ[(i + i // half) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the input, the columns and the truth."""
    if case.plant not in BLIND3_CORES:
        raise KeyError(f"unknown blind3 plant {case.plant!r}; known: {', '.join(BLIND3_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_full_sweep(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    core = BLIND3_CORES[case.plant]
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    noise = NOISE_MM[case.plant]
    base = core(u, dt, params)
    off = render(core, params, u, dt, "none", q, load, temperature, base)

    def with_effect() -> Array:
        return render(core, params, u, dt, case.form, q, load, temperature, base)

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    return {"t": t, "u": u, "on": on, "off": off, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS`)."""
    return recorded(case, sim, SENSORS)


def blind3_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind3_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
