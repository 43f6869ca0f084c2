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
records. The table of every case: ``python -m bench.plants.blind4_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind4_cores import BLIND4_CORES, draw_params
from bench.plants.blind4_effects import BLIND4_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind4_protocols import BLIND4_PROTOCOLS, with_s_sweep
from bench.plants.blind4_rig import supply_droop
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
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


def blind4_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind4 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs, and every form
    meets four protocols and several rates."""
    out: list[Case] = []
    protocols, n_rates = list(BLIND4_PROTOCOLS), len(BLIND4_RATES_HZ)
    i = 0
    for p_index, plant in enumerate(BLIND4_PLANTS):
        for effect, forms in BLIND4_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    # the plant shifts the protocol and (twice over) the rate, so one form meets
                    # four protocols and four rates over the four plants
                    protocol = protocols[(i + p_index) % len(protocols)]
                    rate = BLIND4_RATES_HZ[(i + 2 * p_index) % n_rates]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the input, the columns and the truth."""
    if case.plant not in BLIND4_CORES:
        raise KeyError(f"unknown blind4 plant {case.plant!r}; known: {', '.join(BLIND4_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_s_sweep(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    core = BLIND4_CORES[case.plant]
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    noise = NOISE_MM[case.plant]
    base = core(supply_droop(u, dt, params), dt, params)
    off = render(core, params, u, dt, "none", q, load, temperature, base)

    def with_effect() -> Array:
        return render(core, params, u, dt, case.form, q, load, temperature, base)

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    return {"t": t, "u": u, "on": on, "off": off, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS`)."""
    return recorded(case, sim, SENSORS)


def blind4_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind4_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
