"""How a plant family's rig records a simulated case: the load and temperature columns drawn
from a family's patterns, sensor noise and reading steps on the output, load and temperature
channels, and the Markdown table of a family's cases.

Shared by every family the engine (:mod:`bench.plants.engine`) records.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.case import Case
from host.data import Measurement

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Sensors:
    """A rig's channels: noise (one standard deviation) and reading step of each.

    ``seed_offset`` is added to a case's seed for the measurement noise, so that it is
    independent of the plant's own random draws."""

    seed_offset: int
    quant_mm: float  # output reading step [mm]; the output's noise is the case's own (truth)
    load_noise_kg: float
    load_read_kg: float
    temp_noise_k: float
    temp_read_k: float


def drawn_columns(
    load_patterns: Mapping[str, Callable[[Array, np.random.Generator], Array]],
    temperature_patterns: Mapping[str, Callable[[Array, np.random.Generator], Array]],
    t: Array,
    rng: np.random.Generator,
) -> tuple[Array, Array, str, str]:
    """Load [kg] and temperature [degC] of a record, each from a pattern drawn at random, and the
    patterns' names (independent of the effect)."""
    load_name = tuple(load_patterns)[int(rng.integers(0, len(load_patterns)))]
    temp_name = tuple(temperature_patterns)[int(rng.integers(0, len(temperature_patterns)))]
    return load_patterns[load_name](t, rng), temperature_patterns[temp_name](t, rng), load_name, temp_name


def read(x: Array, step: float) -> Array:
    """``x`` read to the nearest multiple of ``step``."""
    return np.asarray(np.round(x / step) * step, dtype=np.float64)


def recorded(case: Case, sim: dict[str, Any], sensors: Sensors) -> tuple[Measurement, dict[str, Any]]:
    """The recording of ``case`` from a family's ``simulate`` result: the output [mm] with the
    truth's noise, load [kg] and temperature [degC] with the sensors' noise, each read to its step."""
    rng = np.random.default_rng(case.seed + sensors.seed_offset)
    n = sim["on"].size
    y = read(sim["on"] + rng.normal(0.0, sim["truth"]["noise"], n), sensors.quant_mm)
    extras = {
        "load": read(sim["load"] + rng.normal(0.0, sensors.load_noise_kg, n), sensors.load_read_kg),
        "temperature": read(sim["temperature"] + rng.normal(0.0, sensors.temp_noise_k, n), sensors.temp_read_k),
    }
    return Measurement(sim["t"], sim["u"], y, extras, source=case.name), dict(sim["truth"])


def rounded_reading(seed_offset: int) -> Callable[[Any, Case, dict[str, Any]], tuple[Measurement, dict[str, Any]]]:
    """The first held-out families' recording (a ``FamilySpec.read`` hook): the output [mm] with
    the truth's noise and not quantised, load [kg] with 0.01 kg noise read to 0.001 kg and
    temperature [degC] with 0.05 K noise read to 0.1 K, seeded at ``case.seed + seed_offset``."""

    def read(spec: Any, case: Case, sim: dict[str, Any]) -> tuple[Measurement, dict[str, Any]]:
        rng = np.random.default_rng(case.seed + seed_offset)
        y = sim["on"] + rng.normal(0.0, sim["truth"]["noise"], sim["on"].size)
        extras = {
            "load": np.round(sim["load"] + rng.normal(0.0, 0.01, y.size), 3),
            "temperature": np.round(sim["temperature"] + rng.normal(0.0, 0.05, y.size), 1),
        }
        return Measurement(sim["t"], sim["u"], y, extras, source=case.name), dict(sim["truth"])

    return read


def case_table(cases: list[Case], simulate: Callable[[Case], dict[str, Any]], duration_s: float) -> str:
    """A Markdown table of every case, a per-effect summary and the CPU seconds it took."""
    start = time.process_time()
    rows = [
        "| plant | effect:form | protocol | rate [Hz] | effect/noise | effect/span | rescale | load/temperature |",
        "|---|---|---|---|---|---|---|---|",
    ]
    per_effect: dict[str, list[tuple[float, float]]] = {}
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
