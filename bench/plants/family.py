"""The first plant family: cases and recordings. Every plant here is a *tuning* plant.

The Bouc-Wen plant and the HIL were the tuning set from the start; the generalised-play and
friction-spring plants were held out at first, but their per-candidate scores were read while
the method was reworked, so they are tuning plants now too (:func:`tuning_cases` keeps their
records exactly as they were: the second group is numbered from zero as before). The held-out
set is :mod:`bench.plants.fresh_family`, built separately and never used to choose anything.
Every effect appears in both of its forms on each plant (the HIL has one form per effect), with
effect-free records; protocols and sample rates (50-500 Hz) rotate over the cases.
"""

from __future__ import annotations

import numpy as np

from bench.plants import cores, effects
from bench.plants.case import Case
from bench.plants.protocols import PROTOCOLS, with_conditioning
from host.data import Measurement

RATES_HZ = (50.0, 100.0, 200.0, 500.0)
NOISE_MM = 0.03
TUNING_PLANTS = ("bouc_wen", "hil")
SECOND_TUNING_PLANTS = ("generalised_play", "friction_spring")  # held out until diagnose v4
NONE_PER_PLANT = 5


def cases(plants: tuple[str, ...], duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every plant, plus :data:`NONE_PER_PLANT` effect-free records each."""
    out: list[Case] = []
    protocols = list(PROTOCOLS)
    i = 0
    for plant in plants:
        for effect, forms in effects.FORMS.items():
            if plant == "hil":
                forms = ("hil",)
            repeats = NONE_PER_PLANT if effect == "none" else 1
            for form in forms:
                for _ in range(repeats):
                    out.append(
                        Case(plant, effect, form, protocols[i % 4], RATES_HZ[(i // 4 + i) % 4], 100 + i, duration_s)
                    )
                    i += 1
    return out


def tuning_cases(duration_s: float = 150.0) -> list[Case]:
    """Every case of the four tuning plants (55 records: 35 with an effect, 20 without)."""
    return cases(TUNING_PLANTS, duration_s) + cases(SECOND_TUNING_PLANTS, duration_s)


def measurement(case: Case) -> tuple[Measurement, dict[str, object]]:
    """The recording of ``case`` (noisy output, always-moving load and temperature) and its truth."""
    rng = np.random.default_rng(case.seed)
    if case.plant == "hil":
        from hil.record import record

        rate = case.rate_hz if case.rate_hz in (50.0, 100.0, 200.0, 500.0) else 100.0
        rec = record("mixed", case.seed, case.duration_s, case.effect, rate_hz=rate, decoy_columns=True)
        extras = {"load": rec.load, "temperature": rec.temperature}
        return Measurement(rec.t, rec.u, rec.y, extras, source=case.name), dict(rec.truth)
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(3.0, 5.0))
    u = with_conditioning(case.protocol, case.duration_s, dt, peak, rng)
    params = cores.draw_params(case.plant, rng, peak)
    y, extras, truth = effects.apply(cores.CORES[case.plant], params, u, dt, case.effect, case.form, rng)
    y = y + rng.normal(0.0, NOISE_MM, y.size)
    extras = {
        "load": np.round(extras["load"] + rng.normal(0, 0.01, y.size), 3),
        "temperature": np.round(extras["temperature"] + rng.normal(0, 0.05, y.size), 2),
    }
    return Measurement(np.arange(u.size, dtype=np.float64) * dt, u, y, extras, source=case.name), truth
