"""The one engine every plant family runs on: a family is a :class:`FamilySpec` (its cores,
forms, protocols, rates, noise, sensors, seeds and rig hooks), and :func:`cases`,
:func:`simulate`, :func:`measurement` and :func:`report_table` are written once for all.

The template is python-can's ``BusABC.recv`` / ``_recv_internal``: the engine draws, in one fixed
order, the peak pressure, the protocol's input, the core's parameters, the load and temperature
columns, the effect's parameters (and, for calibrated families, a target size), renders the
record with the effect off and on, scales the effect into the visibility band and keeps the
truth; a family's hooks supply only its own physics. The engine knows nothing of any diagnosis.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.case import Case
from bench.plants.recording import Sensors, case_table, recorded
from bench.plants.visibility import calibrate, visible_effect
from host.data import Measurement

Array = NDArray[np.float64]
Record = tuple[Measurement, dict[str, Any]]
LOAD_TEMP_EFFECTS = ("load_dependence", "temperature_drift")


@dataclass(frozen=True)
class Run:
    """What a family's hooks see of one case being simulated: the case, its time step [s], the
    set pressure ``u`` [bar] and its peak, the time grid [s], the core's parameters and output
    (``base`` [mm], ``None`` where the family renders from the parameters alone)."""

    case: Case
    core: Callable[..., Array]
    dt: float
    peak: float
    u: Array
    t: Array
    params: dict[str, float]
    base: Array | None = None


Columns = tuple[Array, Array, str, str]  # load [kg], temperature [degC], their pattern names
Render = Callable[[Run, str, dict[str, float], Array, Array, "Array | None"], Array]


@dataclass(frozen=True)
class Calibration:
    """Effect sizes spread over the band: a target drawn log-uniform in ``over_span`` of the
    effect-free span (at least ``min_over_noise`` x the noise), the intensity calibrated to it
    (:func:`bench.plants.visibility.calibrate`); a load or temperature effect's effect-free
    record is the same plant with its column held still."""

    over_span: tuple[float, float] = (0.01, 0.1)
    min_over_noise: float = 6.0


@dataclass(frozen=True)
class FamilySpec:
    """A plant family as data plus hooks.

    ``rotate(i, plant_index)`` gives the protocol's and the rate's index of the ``i``-th case
    (taken modulo their counts); ``excite(protocol, duration_s, dt, peak, rng)`` the input [bar];
    ``columns(run, rng)`` the load and temperature; ``render(run, form, q, load, temperature,
    off)`` the output [mm] (``off`` is ``None`` when the effect-free record is rendered);
    ``read(spec, case, sim)`` the recording (default: :func:`bench.plants.recording.recorded`
    with the plant's :attr:`sensors`). ``tags`` switch contract checks off where a property does
    not apply (see ``tests/test_plant_contract.py``).
    """

    name: str
    cores: Mapping[str, Callable[..., Array]]
    forms: Mapping[str, tuple[str, ...]]
    protocols: tuple[str, ...]
    rates_hz: tuple[float, ...]
    noise_mm: Mapping[str, float]
    seed_base: int
    rotate: Callable[[int, int], tuple[int, int]]
    excite: Callable[[str, float, float, float, np.random.Generator], Array]
    draw_params: Callable[[str, np.random.Generator, float], dict[str, float]]
    columns: Callable[[Run, np.random.Generator], Columns] | None = None
    draw_effect: Callable[[str, str, np.random.Generator], dict[str, float]] | None = None
    render: Render | None = None
    intensity_key: Mapping[str, str] = field(default_factory=dict)
    sensors: Mapping[str, Sensors] = field(default_factory=dict)
    read: Callable[[FamilySpec, Case, dict[str, Any]], Record] | None = None
    base: Callable[[Run], Array | None] | None = None  # default: the core driven by ``u``
    recorded_input: Callable[[Run], Array] | None = None  # default: ``u`` itself
    calibration: Calibration | None = None
    peak_bar: tuple[float, float] = (3.0, 6.0)
    grow: float = 1.3  # how far past the band's floor a too-small effect is pushed
    none_per_plant: int = 5
    tags: frozenset[str] = frozenset()
    promises: Mapping[str, float] = field(default_factory=dict)  # a contract check's bound, where stricter
    custom_cases: Callable[[float], list[Case]] | None = None  # a family the engine does not draw
    custom_record: Callable[[Case], Record] | None = None

    @property
    def plants(self) -> tuple[str, ...]:
        return tuple(self.cores)


def shifted(protocol_shift: int, rate_shift: int) -> Callable[[int, int], tuple[int, int]]:
    """The common rotation: protocol ``i + protocol_shift * plant``, rate ``i + rate_shift * plant``."""
    return lambda i, p: (i + protocol_shift * p, i + rate_shift * p)


def cases(spec: FamilySpec, duration_s: float = 150.0) -> list[Case]:
    """Every effect-form on every core of ``spec`` plus ``none_per_plant`` effect-free records
    each, seeds counted from ``seed_base``, protocols and rates rotated by ``spec.rotate``."""
    if spec.custom_cases is not None:
        return spec.custom_cases(duration_s)
    out: list[Case] = []
    i = 0
    for p_index, plant in enumerate(spec.plants):
        for effect, forms in spec.forms.items():
            for form in forms:
                for _ in range(spec.none_per_plant if effect == "none" else 1):
                    protocol_index, rate_index = spec.rotate(i, p_index)
                    protocol = spec.protocols[protocol_index % len(spec.protocols)]
                    rate = spec.rates_hz[rate_index % len(spec.rates_hz)]
                    out.append(Case(plant, effect, form, protocol, rate, spec.seed_base + i, duration_s))
                    i += 1
    return out


def _drawn_run(spec: FamilySpec, case: Case, rng: np.random.Generator) -> Run:
    dt = 1.0 / case.rate_hz
    peak = float(rng.uniform(*spec.peak_bar))  # bar
    u = spec.excite(case.protocol, case.duration_s, dt, peak, rng)
    t = np.arange(u.size, dtype=np.float64) * dt
    params = spec.draw_params(case.plant, rng, peak)
    return Run(case, spec.cores[case.plant], dt, peak, u, t, params)


def simulate(spec: FamilySpec, case: Case) -> dict[str, Any]:
    """Noise-free outputs with the effect (``on``) and without (``off``), the recorded input
    ``u`` and the set pressure ``command`` [bar], the core's output ``base`` [mm] where there is
    one, the true load [kg] and temperature [degC], and the truth. Deterministic by the seed."""
    if case.plant not in spec.cores:
        raise KeyError(f"unknown {spec.name} plant {case.plant!r}; known: {', '.join(spec.cores)}")
    if spec.columns is None or spec.draw_effect is None or spec.render is None:
        raise TypeError(f"family {spec.name} records its cases itself (custom_record); it has no simulate")
    rng = np.random.default_rng(case.seed)
    run = _drawn_run(spec, case, rng)
    load, temperature, load_pattern, temp_pattern = spec.columns(run, rng)
    q = spec.draw_effect(case.effect, case.form, rng)
    cal = spec.calibration
    share = float(np.exp(rng.uniform(*np.log(cal.over_span)))) if cal is not None else 0.0
    noise = spec.noise_mm[case.plant]
    base = spec.base(run) if spec.base is not None else run.core(run.u, run.dt, run.params)
    run = replace(run, base=base)
    if cal is not None and case.effect in LOAD_TEMP_EFFECTS:  # the same plant with its column held still
        held_load, held_temp = np.full_like(load, load[0]), np.full_like(temperature, temperature[0])
        off = spec.render(run, case.form, q, held_load, held_temp, None)
    else:
        off = spec.render(run, "none", q, load, temperature, None)
    key, render = spec.intensity_key.get(case.form, ""), spec.render  # no key: effect-free
    memo: dict[float, Array] = {}

    def with_effect() -> Array:
        key_value = q.get(key, 0.0)
        if key_value not in memo:
            memo.clear()
            memo[key_value] = render(run, case.form, q, load, temperature, off)
        return memo[key_value]

    if cal is not None and case.effect != "none":
        target = max(share * float(np.ptp(off)), cal.min_over_noise * noise)
        q["target_over_span"] = target / float(np.ptp(off))
        calibrate(with_effect, off, q, key, target)
    patterns = (load_pattern, temp_pattern)
    on, truth = visible_effect(case.effect, case.form, with_effect, off, noise, q, key, spec.grow, run.params, patterns)
    u_read = spec.recorded_input(run) if spec.recorded_input is not None else run.u
    sim = {"t": run.t, "u": u_read, "command": run.u, "on": on, "off": off, "load": load, "temperature": temperature}
    return {**sim, "base": base, "truth": truth} if base is not None else {**sim, "truth": truth}


def measurement_from(spec: FamilySpec, case: Case, sim: dict[str, Any]) -> Record:
    """The recording of ``case`` from its :func:`simulate` result: the family's ``read`` hook,
    else the plant's :attr:`FamilySpec.sensors` on every channel."""
    if spec.read is not None:
        return spec.read(spec, case, sim)
    return recorded(case, sim, spec.sensors[case.plant])


def measurement(spec: FamilySpec, case: Case) -> Record:
    """The recording of ``case`` and its truth (effect, form, parameters, effect size [mm] and
    its ratio to the noise and the span, rescale, column patterns). Deterministic by the seed."""
    if spec.custom_record is not None:
        return spec.custom_record(case)
    return measurement_from(spec, case, simulate(spec, case))


def report_table(spec: FamilySpec, duration_s: float = 100.0) -> str:
    """A Markdown table of every case of ``spec``, a per-effect summary and the CPU seconds it took."""
    return case_table(cases(spec, duration_s), lambda case: simulate(spec, case), duration_s)


def core_first(render: Callable[..., Array]) -> Render:
    """``render(core, params, u, dt, form, q, load, temperature, base)`` as the engine's hook."""
    return lambda r, form, q, load, temp, off: render(r.core, r.params, r.u, r.dt, form, q, load, temp, r.base)


def plant_first(render: Callable[..., Array]) -> Render:
    """``render(plant, params, u, dt, form, q, load, temperature, base)`` as the engine's hook."""
    return lambda r, form, q, load, temp, off: render(r.case.plant, r.params, r.u, r.dt, form, q, load, temp, r.base)


def params_first(render: Callable[..., Array]) -> Render:
    """``render(params, u, dt, form, q, load, temperature, base)`` as the engine's hook."""
    return lambda r, form, q, load, temp, off: render(r.params, r.u, r.dt, form, q, load, temp, r.base)


def over_off(render: Callable[..., Array]) -> Render:
    """``render(core, params, u, dt, form, q, load, temperature, off)``: an older family whose
    effects are rendered over the effect-free output (``None`` while that is rendered)."""
    return lambda r, form, q, load, temp, off: render(r.core, r.params, r.u, r.dt, form, q, load, temp, off)
