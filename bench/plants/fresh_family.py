"""A second held-out plant family for ``pmactl diagnose``, never used for tuning.

Four cores (:mod:`bench.plants.fresh_cores`), seven protocols (:mod:`bench.plants.fresh_protocols`),
every effect in two forms unlike the first family's (:mod:`bench.plants.fresh_effects`), sample
rates 50-500 Hz (80, 125, 250 and 400 Hz are new). Only numbers are reported from it.

Every effect case is *visible*: its effect size (RMS [mm] of the noise-free output with the
effect minus the same plant, protocol and seed with the effect switched off) lies in
``[EFFECT_MIN_OVER_NOISE * noise, EFFECT_MAX_OVER_SPAN * span]``. The drawn intensity is kept when
it lands there; otherwise it is scaled (at most 4x either way, recorded as
``intensity_rescale`` in the truth) until it does (:mod:`bench.plants.visibility`).

Confounds a real rig has, kept on purpose in the effect-free records too: the chamber core's
fill/vent dynamics (a level- and direction-dependent lag), the slip-mass core's light
resonance, per-plant sensor noise (0.02-0.05 mm), temperature read at 0.1 K, and warming curves
or load changes that do nothing. The table of every case: ``python -m bench.plants.fresh_family 100``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.family import Case
from bench.plants.fresh_cores import FRESH_CORES, draw_fresh_params
from bench.plants.fresh_effects import FRESH_FORMS, INTENSITY_KEY, columns, draw_effect_params, render
from bench.plants.fresh_protocols import FRESH_PROTOCOLS, vented_full_cycle
from bench.plants.visibility import visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
FRESH_PLANTS = tuple(FRESH_CORES)
FRESH_RATES_HZ = (80.0, 250.0, 50.0, 125.0, 500.0, 400.0)
NOISE_MM = {"coleman_hodgdon": 0.02, "kp_sum": 0.04, "maxwell_slip_mass": 0.03, "pneumatic_chamber": 0.05}
NONE_PER_PLANT = 5
SEED_BASE = 7000


def fresh_cases(duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every fresh core, plus :data:`NONE_PER_PLANT` effect-free records each.

    Protocols (7) and rates (6) rotate with the case index, so all 42 pairs occur.
    """
    out: list[Case] = []
    protocols = list(FRESH_PROTOCOLS)
    i = 0
    for plant in FRESH_PLANTS:
        for effect, forms in FRESH_FORMS.items():
            for form in forms:
                for _ in range(NONE_PER_PLANT if effect == "none" else 1):
                    protocol = protocols[i % len(protocols)]
                    rate = FRESH_RATES_HZ[i % len(FRESH_RATES_HZ)]
                    out.append(Case(plant, effect, form, protocol, rate, SEED_BASE + i, duration_s))
                    i += 1
    return out


def simulate(case: Case) -> dict[str, Any]:
    """Noise-free outputs with and without the effect, the input, the columns and the truth."""
    if case.plant not in FRESH_CORES:
        raise KeyError(f"unknown fresh plant {case.plant!r}; known: {', '.join(FRESH_CORES)}")
    rng = np.random.default_rng(case.seed)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(2.5, 6.0))
    u = vented_full_cycle(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    core = FRESH_CORES[case.plant]
    params = draw_fresh_params(case.plant, rng, peak)
    load, temperature, load_pattern, temp_pattern = columns(t, case.effect, rng)
    q = draw_effect_params(case.effect, case.form, rng)
    noise = NOISE_MM[case.plant]
    off = render(core, params, u, dt, "none", q, load, temperature, 0.0)
    span = float(np.ptp(off))

    def with_effect() -> Array:
        return render(core, params, u, dt, case.form, q, load, temperature, span)

    key, patterns = INTENSITY_KEY.get(case.form, ""), (load_pattern, temp_pattern)  # no key: effect-free
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, 1.25, params, patterns)
    return {"t": t, "u": u, "on": on, "off": off, "load": load, "temperature": temperature, "truth": truth}


def measurement_from(case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from its :func:`simulate` result: noisy output [mm], load [kg]
    and temperature [degC] columns (sensor noise and resolution), and the truth."""
    rng = np.random.default_rng(case.seed + 10_000)  # measurement noise, independent of the plant draws
    noise = sim["truth"]["noise"]
    y = sim["on"] + rng.normal(0.0, noise, sim["on"].size)
    extras = {
        "load": np.round(sim["load"] + rng.normal(0.0, 0.01, y.size), 3),
        "temperature": np.round(sim["temperature"] + rng.normal(0.0, 0.05, y.size), 1),
    }
    return Measurement(sim["t"], sim["u"], y, extras, source=case.name), dict(sim["truth"])


def fresh_measurement(case: Case) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm], effect
    size over noise and over span, the column patterns). Deterministic by ``case.seed``."""
    return measurement_from(case, simulate(case))


def report_table(duration_s: float = 100.0) -> str:
    """A Markdown table of every case: plant, effect:form, protocol, rate, effect size over noise
    and over span, column patterns; and the CPU seconds it took to build them all."""
    import time

    start = time.process_time()
    rows = [
        "| plant | effect:form | protocol | rate [Hz] | effect/noise | effect/span | load/temperature |",
        "|---|---|---|---|---|---|---|",
    ]
    for case in fresh_cases(duration_s):
        truth = simulate(case)["truth"]
        rows.append(
            f"| {case.plant} | {case.effect}:{case.form} | {case.protocol} | {case.rate_hz:g} | "
            f"{truth['effect_size_over_noise']:.1f} | {100 * truth['effect_size_over_span']:.1f} % | "
            f"{truth['load_pattern']}/{truth['temperature_pattern']} |"
        )
    rows.append(f"\n{len(rows) - 2} cases of {duration_s:g} s built in {time.process_time() - start:.1f} CPU s")
    return "\n".join(rows)


if __name__ == "__main__":
    import sys

    print(report_table(float(sys.argv[1]) if len(sys.argv) > 1 else 100.0))
