"""A fourth, truly blind held-out plant family for ``pmactl diagnose`` (blind2).

Built blind to the method: its author never read, imported or ran anything of the diagnosis
(``host/diagnose``, its benches or tests, ``pmactl diagnose``); only the other plant families
were read, to make this one different from all of them. It is to be scored once, for honest
numbers, and never used to choose or tune anything.

* Four cores (:mod:`tests.plants.blind2_cores`): a Jiles-Atherton-type Duhem model with a
  saturating anhysteretic curve; an antagonistic muscle pair on a joint (one muscle at the
  input, one at a fixed bias) whose bearing friction is loaded by the cable tensions; a
  dead-band valve and a Chou-Hannaford muscle with braid friction that grows with pressure; a
  Bowden cable's capstan friction between a muscle and a pretensioned exo joint.
* Five protocols (:mod:`tests.plants.blind2_protocols`): gait cycles, an amplitude-modulated
  sine, sawtooth trains, setpoint tracking, PWM chamber pressure; each starts vented and does a
  full-range check in its first ~4 s (the hysteresis memory is known early).
* Every effect in two new forms (:mod:`tests.plants.blind2_effects`).
* Sample rates 70, 120, 175, 240, 333 and 480 Hz (none used by the other families).

Every effect record is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same record with it off) lies in ``[5 x noise, 12 % of span]`` through
:func:`tests.plants.visibility.scale_into_band` (the rescale is recorded in the truth).

Confounds in every record, effect-free ones too: valve lag and a slow thermal pressure tail
(1.5-4 s), a mechanical resonance (3-20 Hz), dead bands and slack cables, sensor noise
0.02-0.05 mm per plant with 0.01 mm quantisation, load (read to 0.005 kg) and temperature
(read to 0.05 K) columns that always move and act only in their own effect's records.
The table of every case: ``python -m tests.plants.blind2_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from host.data import Measurement
from tests.plants.blind2_cores import BLIND2_CORES, draw_params
from tests.plants.blind2_effects import BLIND2_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from tests.plants.blind2_protocols import BLIND2_PROTOCOLS, with_range_check
from tests.plants.family import Case
from tests.plants.visibility import visible_effect

Array = NDArray[np.float64]
BLIND2_PLANTS = tuple(BLIND2_CORES)
BLIND2_RATES_HZ = (70.0, 175.0, 333.0, 480.0, 120.0, 240.0)
NOISE_MM = {"ja_duhem": 0.025, "antagonistic_joint": 0.04, "braid_deadband": 0.02, "capstan_exo": 0.05}
QUANT_MM = 0.01
LOAD_READ_KG, LOAD_NOISE_KG = 0.005, 0.008
TEMP_READ_K, TEMP_NOISE_K = 0.05, 0.03
NONE_PER_PLANT = 5
SEED_BASE = 12000


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


def _read(x: Array, step: float) -> Array:
    return np.asarray(np.round(x / step) * step, dtype=np.float64)


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result: output [mm] with noise,
    read to :data:`QUANT_MM`; load [kg] and temperature [degC] with noise, read to their steps."""
    rng = np.random.default_rng(case.seed + 70_000)  # measurement noise, independent of the plant draws
    n = sim["on"].size
    y = _read(sim["on"] + rng.normal(0.0, sim["truth"]["noise"], n), QUANT_MM)
    extras = {
        "load": _read(sim["load"] + rng.normal(0.0, LOAD_NOISE_KG, n), LOAD_READ_KG),
        "temperature": _read(sim["temperature"] + rng.normal(0.0, TEMP_NOISE_K, n), TEMP_READ_K),
    }
    return Measurement(sim["t"], sim["u"], y, extras, source=case.name), dict(sim["truth"])


def blind2_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, rescale, column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    import time

    start = time.process_time()
    rows = [
        "| plant | effect:form | protocol | rate [Hz] | effect/noise | effect/span | rescale | load/temperature |",
        "|---|---|---|---|---|---|---|---|",
    ]
    per_effect: dict[str, list[tuple[float, float]]] = {}
    cases = blind2_cases(duration_s)
    for case in cases:
        truth = simulate(case)["truth"]
        if case.effect != "none":
            ratios = (truth["effect_size_over_noise"], truth["effect_size_over_span"])
            per_effect.setdefault(case.effect, []).append(ratios)
        rows.append(
            f"| {case.plant} | {case.effect}:{case.form} | {case.protocol} | {case.rate_hz:g} | "
            f"{truth['effect_size_over_noise']:.1f} | {100 * truth['effect_size_over_span']:.1f} % | "
            f"{truth['intensity_rescale']:.2f} | {truth['load_pattern']}/{truth['temperature_pattern']} |"
        )
    n_cases = len(rows) - 2
    rows.append("\n| effect | effect/noise min | median | max | effect/span median | max |\n|---|---|---|---|---|---|")
    for effect, pairs in per_effect.items():
        over_noise, over_span = np.array([a for a, _ in pairs]), 100.0 * np.array([b for _, b in pairs])
        rows.append(
            f"| {effect} | {over_noise.min():.1f} | {np.median(over_noise):.1f} | {over_noise.max():.1f} | "
            f"{np.median(over_span):.1f} % | {over_span.max():.1f} % |"
        )
    rows.append(f"\nprotocols: {', '.join(sorted({c.protocol for c in cases}))}")
    rows.append(f"rates [Hz]: {', '.join(f'{r:g}' for r in sorted({c.rate_hz for c in cases}))}")
    rows.append(f"\n{n_cases} cases of {duration_s:g} s built in {time.process_time() - start:.1f} CPU s")
    return "\n".join(rows)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
