"""A fourth, truly blind held-out plant family for ``pmactl diagnose`` (blind2).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`bench.plants.blind2_cores`): a Jiles-Atherton-type Duhem model with a
  saturating anhysteretic curve; an antagonistic muscle pair on a joint (one muscle at the
  input, one at a fixed bias) whose bearing friction is loaded by the cable tensions; a
  dead-band valve and a Chou-Hannaford muscle with braid friction that grows with pressure; a
  Bowden cable's capstan friction between a muscle and a pretensioned exo joint.
* Five protocols (:mod:`bench.plants.blind2_protocols`): gait cycles, an amplitude-modulated
  sine, sawtooth trains, setpoint tracking, PWM chamber pressure; each starts vented and does a
  full-range check in its first ~4 s (the hysteresis memory is known early).
* Every effect in two new forms (:mod:`bench.plants.blind2_effects`).
* Sample rates 70, 120, 175, 240, 333 and 480 Hz (none used by the other families).

Every effect record is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same record with it off) lies in ``[5 x noise, 12 % of span]`` through
:func:`bench.plants.visibility.scale_into_band` (the rescale is recorded in the truth).

Confounds in every record, effect-free ones too: valve lag and a slow thermal pressure tail
(1.5-4 s), a mechanical resonance (3-20 Hz), dead bands and slack cables, sensor noise
0.02-0.05 mm per plant with 0.01 mm quantisation, load (read to 0.005 kg) and temperature
(read to 0.05 K) columns that always move and act only in their own effect's records.
The table of every case: ``python -m bench.plants.blind2_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.blind2_cores import BLIND2_CORES, draw_params
from bench.plants.blind2_effects import BLIND2_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.blind2_protocols import BLIND2_PROTOCOLS, with_range_check
from bench.plants.family import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
BLIND2_PLANTS = tuple(BLIND2_CORES)
BLIND2_RATES_HZ = (70.0, 175.0, 333.0, 480.0, 120.0, 240.0)
NOISE_MM = {"ja_duhem": 0.025, "antagonistic_joint": 0.04, "braid_deadband": 0.02, "capstan_exo": 0.05}
QUANT_MM = 0.01
LOAD_READ_KG, LOAD_NOISE_KG = 0.005, 0.008
TEMP_READ_K, TEMP_NOISE_K = 0.05, 0.03
NONE_PER_PLANT = 5
SEED_BASE = 12000
# measurement noise seeded at case.seed + 70_000, independent of the plant draws
SENSORS = Sensors(70_000, QUANT_MM, LOAD_NOISE_KG, LOAD_READ_KG, TEMP_NOISE_K, TEMP_READ_K)


def blind2_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every blind2 core plus :data:`NONE_PER_PLANT` effect-free records
    each (60 records); protocols (5) and rates (6) rotate so every pair occurs."""
    out: list[Case] = []
    protocols = list(BLIND2_PROTOCOLS)
    i = 0
    for plant in BLIND2_PLANTS:
        for effect, forms in BLIND2_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[i % len(protocols)]
                    rate = BLIND2_RATES_HZ[(i // len(protocols)) % len(BLIND2_RATES_HZ)]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the input, the columns and the truth."""
    if case.plant not in BLIND2_CORES:
        raise KeyError(f"unknown blind2 plant {case.plant!r}; known: {', '.join(BLIND2_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 6.0))  # bar
    u = with_range_check(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    core = BLIND2_CORES[case.plant]
    params = draw_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    noise = NOISE_MM[case.plant]
    off = render(core, params, u, dt, "none", q, load, temperature)

    def with_effect() -> Array:
        return render(core, params, u, dt, case.form, q, load, temperature, off)

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.3, params, patterns)
    return {"t": t, "u": u, "on": on, "off": off, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result (:data:`SENSORS`)."""
    return recorded(case, sim, SENSORS)


def blind2_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    return case_table(blind2_cases(duration_s), simulate, duration_s)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
