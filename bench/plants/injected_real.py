"""A held-out scoring set for ``pmactl diagnose``: REAL measured records with one known effect injected.

Ten base records from ``../shared/data`` (never copied into the repository): five piezo runs
(dSPACE, 10 kHz, block-averaged to 1 kHz; y in um) and five pneumatic-muscle records, each several
single-cycle logs of ONE date joined end to end with time made continuous, then resampled onto a
uniform grid at the median step (y in mm). For each base: the record as measured (effect
``none``: nothing injected; the real rig may carry effects of its own) and one record per effect,
computed from the record's own u and y on its native time base before the grid change:

- creep ``kelvin_y`` / ``kelvin_u``: three Kelvin-Voigt relaxations (time constants spread
  log-uniformly over 1-30 s for the muscle, 0.05-2 s for the 2-4 s piezo runs) driven by y, or by
  u mapped into y's units by a straight-line fit; the output keeps creeping after the input stops.
- rate_dependence ``viscous``: a term proportional to the low-passed input rate du/dt (a loop
  that widens with speed); ``rate_lag``: a first-order lag of y whose time constant grows with
  the low-passed |du/dt| (no lag at rest, more at speed).
- transport_delay ``shift``: y(t - d), interpolated (np.interp on the native, non-uniform time).
- load_dependence ``compliance`` (offset proportional to load) / ``gain`` (stroke scaled by load).
- temperature_drift ``offset`` (thermal expansion) / ``gain`` (stroke scaled by temperature).

Every record carries ``load`` [kg] (steps or a slow walk) and ``temperature`` [degC] (heating and
cooling segments, or a slow cycle) columns with sensor noise; only the injected effect's column
acts on y, the other (and both, in ``none`` records) is a decoy. Effect size = RMS of (injected y -
measured y) on the final grid; its intensity is solved to land on a target drawn in
:data:`TARGET_OVER_SPAN` of y's span, and never below :data:`MIN_OVER_NOISE` x the record's noise
(:func:`noise_estimate`). Deterministic by seed. The table of every case:
``python bench/diagnose_injected.py --dry-run``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from bench.plants.real_records import (
    BASES,
    BY_KEY,
    PIEZO_BLOCK,
    BaseRecord,
    coarsen,
    native_record,
    noise_estimate,
    record_paths,
    resolution,
)
from host.data import Measurement

Array = NDArray[np.float64]
E = TypeVar("E")  # an effect: one array, or a list of arrays (one per run)
FORMS: dict[str, tuple[str, ...]] = {
    "none": ("as_measured",),
    "creep": ("kelvin_y", "kelvin_u"),
    "rate_dependence": ("viscous", "rate_lag"),
    "transport_delay": ("shift",),
    "load_dependence": ("compliance", "gain"),
    "temperature_drift": ("offset", "gain"),
}
NONLINEAR_INTENSITY = {"rate_lag", "shift"}  # size is not proportional to the intensity: bisection
PHYSICAL_RANGE = {  # intensity bounds: creep at most half the drive, brief's delays, lags < 0.5 s
    "kelvin_y": (0.0, 0.5),
    "kelvin_u": (0.0, 0.5),
    "shift": (0.0, 0.15),
    "rate_lag": (0.0, 0.5),
}
MIN_OVER_NOISE = 4.0  # the brief's floor; the target is raised to 5x to leave room
MAX_OVER_SPAN = 0.12
TARGET_OVER_SPAN = (0.03, 0.09)
SEED_BASE = 9100
FORM_PARAMETERS = {  # what each form's truth reports besides its intensity
    "kelvin_y": ("taus_s", "weights", "drive_reference"),
    "kelvin_u": ("taus_s", "weights", "y_per_u", "drive_reference"),
    "viscous": ("rate_lowpass_s", "direction"),
    "rate_lag": ("rate_lowpass_s",),
    "shift": (),
    "compliance": ("direction",),
    "offset": ("sign",),
    "gain": ("sign", "y_ref"),
}
UNITS = {
    "kelvin_y": "fraction of y",
    "kelvin_u": "fraction of fitted y(u)",
    "viscous": "span at the 99th-percentile rate",
    "rate_lag": "s (lag at the 99th-percentile rate)",
    "shift": "s (delay)",
    "compliance": "y units per kg",
    "offset": "y units per K",
}


@dataclass(frozen=True)
class InjectedCase:
    """One scored record: a base record, the effect injected into it (``none``: as measured)."""

    base: str
    plant: str  # base-data kind: "piezo" or "muscle" (named ``plant`` like the synthetic cases)
    effect: str
    form: str
    seed: int

    @property
    def name(self) -> str:
        return f"{self.plant}/{self.base}/{self.effect}:{self.form}/s{self.seed}"


def injected_cases(data_root: Path) -> list[InjectedCase]:
    """Every base record found under ``data_root`` x (``none`` + one record per effect).

    Effects with two forms alternate the form over the base records, so each form occurs on both
    kinds of data."""
    out: list[InjectedCase] = []
    for i, base in enumerate(BASES):
        if not record_paths(Path(data_root), base):
            continue
        for j, (effect, forms) in enumerate(FORMS.items()):
            out.append(InjectedCase(base.key, base.kind, effect, forms[i % len(forms)], SEED_BASE + 10 * i + j))
    return out


def lowpass(t: Array, x: Array, tau: float, start: float | None = None) -> Array:
    """First-order low-pass (time constant ``tau`` [s]) of ``x`` sampled at times ``t``; state starts at
    ``start`` (default ``x[0]``)."""
    s0 = float(x[0]) if start is None else start
    dts = np.diff(t)
    if np.ptp(dts) > 1e-9 * np.median(dts):
        return _lag(t, x, np.full(x.size, tau), s0)
    a = 1.0 - np.exp(-float(dts[0]) / tau)  # uniform: one filter call
    out, _ = lfilter([a], [1.0, a - 1.0], x, zi=[(1.0 - a) * s0])
    return np.asarray(out, dtype=np.float64)


def _lag(t: Array, x: Array, tau: Array, start: float) -> Array:
    """First-order lag of ``x`` whose time constant ``tau`` [s] may change sample by sample."""
    dts = np.diff(t, prepend=2 * t[0] - t[1])
    alphas = (1.0 - np.exp(-dts / np.maximum(tau, 1e-12))).tolist()
    out = np.empty_like(x)
    s = start
    for i, (a, v) in enumerate(zip(alphas, x.tolist())):
        s += a * (v - s)
        out[i] = s
    return out


def load_column(t: Array, rng: np.random.Generator) -> tuple[Array, str]:
    """Load [kg]: weights hung and taken off (steps, settling in 2 % of the record) or a slow walk."""
    span = float(t[-1] - t[0])
    if rng.random() < 0.5:
        times = np.sort(rng.uniform(t[0] + 0.05 * span, t[-1] - 0.05 * span, int(rng.integers(3, 7))))
        levels = np.round(rng.uniform(0.0, 6.0, times.size + 1) * 2) / 2
        return lowpass(t, levels[np.searchsorted(times, t)], 0.02 * span), "steps"
    knots = np.cumsum(rng.normal(0.0, 1.0, 12))
    walk = np.interp(t, np.linspace(t[0], t[-1], knots.size), knots)
    walk = (walk - walk.min()) / max(float(np.ptp(walk)), 1e-9)
    return 0.5 + rng.uniform(3.0, 7.5) * walk, "walk"


def temperature_column(t: Array, rng: np.random.Generator) -> tuple[Array, str]:
    """Temperature [degC]: alternating heating and cooling ramps, or a slow cycle on a drift."""
    span = float(t[-1] - t[0])
    start = rng.uniform(20.0, 28.0)
    if rng.random() < 0.5:
        n = int(rng.integers(3, 6))
        signs = np.where(np.arange(n) % 2 == 0, 1.0, -1.0) * rng.choice([-1.0, 1.0])
        levels = start + np.concatenate([[0.0], np.cumsum(signs * rng.uniform(3.0, 12.0, n))])
        knots = np.sort(np.concatenate([[t[0], t[-1]], rng.uniform(t[0], t[-1], n - 1)]))
        return lowpass(t, np.interp(t, knots, levels), 0.03 * span), "heat_cool"
    phase = rng.uniform(0.0, 2 * np.pi)
    cycle = rng.uniform(3.0, 8.0) * np.sin(2 * np.pi * (t - t[0]) / (rng.uniform(0.5, 0.9) * span) + phase)
    return start + cycle + rng.uniform(-3.0, 3.0) * (t - t[0]) / span, "cycle"


def _unit_effect(
    form: str, t: Array, u: Array, y: Array, cols: dict[str, Array], p: dict[str, Any]
) -> Callable[[float], Array]:
    """The effect of ``form`` as a function of its one intensity (``y_injected - y`` on native time)."""
    direction = p["direction"]  # +1 when y rises with u: the sign a physical effect takes
    y_ref = p["y_ref"]
    if form in ("kelvin_y", "kelvin_u"):
        drive = y - p["drive_reference"] if form == "kelvin_y" else p["y_per_u"] * (u - p["drive_reference"])
        relax = sum(w * lowpass(t, drive, tau, 0.0) for w, tau in zip(p["weights"], p["taus_s"]))
        return lambda c: c * relax
    if form in ("viscous", "rate_lag"):
        rate = lowpass(t, np.gradient(u, t), p["rate_lowpass_s"])
        rate = rate / max(float(np.percentile(np.abs(rate), 99)), 1e-12)  # robust to steps in u
        if form == "viscous":
            return lambda k: k * direction * p["span"] * rate
        return lambda tau_ref: _lag(t, y, tau_ref * np.minimum(np.abs(rate), 3.0), float(y[0])) - y
    if form == "shift":
        return lambda d: np.interp(t - d, t, y, left=y[0]) - y
    column = cols["load"] if p["effect"] == "load_dependence" else cols["temperature"]
    change = column - column[0]
    if form == "compliance":
        return lambda c: -direction * c * change  # a load pulls against the stroke
    if form == "offset":
        return lambda a: p["sign"] * a * change
    return lambda g: p["sign"] * g * change * (y - y_ref)  # gain forms of load and temperature


def _draw_params(case: InjectedCase, base: BaseRecord, rng: np.random.Generator) -> dict[str, Any]:
    lo, hi = np.log(base.tau_range_s[0]), np.log(base.tau_range_s[1])
    edges = np.linspace(lo, hi, 4)  # one time constant per third of the log range
    weights = rng.uniform(0.5, 1.5, 3)
    return {
        "effect": case.effect,
        "taus_s": [float(np.exp(rng.uniform(a, b))) for a, b in zip(edges[:-1], edges[1:])],
        "weights": [float(w) for w in weights / weights.sum()],
        "rate_lowpass_s": base.rate_lowpass_s,
        "sign": -1.0 if case.effect == "load_dependence" else float(rng.choice([-1.0, 1.0])),
        "target_over_span": float(rng.uniform(*TARGET_OVER_SPAN)),
    }


def _rms(x: Array) -> float:
    return float(np.sqrt(np.mean(x * x)))


def _solve(effect: Callable[[float], E], size: Callable[[E], float], target: float, linear: bool) -> float:
    """The intensity whose effect (an array, or one array per run) has size ``target`` (RMS on the final grid)."""
    if linear:
        return target / max(size(effect(1.0)), 1e-300)
    lo, hi = 1e-6, 5.0  # [s]: a delay or a largest lag time constant
    for _ in range(40):
        mid = float(np.sqrt(lo * hi))
        lo, hi = (mid, hi) if size(effect(mid)) < target else (lo, mid)
        if hi / lo < 1.005:
            break
    return float(np.sqrt(lo * hi))


def _intensity(
    make: Callable[[float], Array],
    size: Callable[[Array], float],
    target: float,
    form: str,
    base: BaseRecord,
    window: tuple[float, float],
) -> tuple[float, bool]:
    """The intensity for ``target``, held to the form's physical range (:data:`PHYSICAL_RANGE`; a
    muscle delay of at least ``base.min_delay_s``) unless that leaves the size ``window``."""
    linear = form not in NONLINEAR_INTENSITY
    wanted = _solve(make, size, target, linear)
    lo, hi = PHYSICAL_RANGE.get(form, (0.0, np.inf))
    held = float(np.clip(wanted, max(lo, base.min_delay_s if form == "shift" else 0.0), hi))
    reached = size(make(held))
    if reached < window[0] or reached > window[1]:  # visible and modest wins over plausible
        held = _solve(make, size, window[0] if reached < window[0] else window[1], linear)
    return held, abs(held - wanted) > 1e-9 * abs(wanted)


def injected_measurement(case: InjectedCase, data_root: Path) -> tuple[Measurement, dict[str, Any]]:
    """The record of ``case`` (t [s], u, y, ``load`` [kg], ``temperature`` [degC]) and its truth:
    effect, form, parameters (the solved intensity among them), effect size [y units], size over
    noise and over span, noise, span, column patterns, base files."""
    base = BY_KEY[case.base]
    t, u, y, files = native_record(str(data_root), case.base)
    rng = np.random.default_rng(case.seed)
    cols: dict[str, Array] = {}
    patterns: dict[str, str] = {}
    cols["load"], patterns["load"] = load_column(t, rng)
    cols["temperature"], patterns["temperature"] = temperature_column(t, rng)
    p = _draw_params(case, base, rng)

    def final(x: Array) -> Array:
        return coarsen(base.kind, t, x)

    y_base = final(y)
    span = float(np.ptp(y_base))
    block = PIEZO_BLOCK if base.kind == "piezo" else 1
    noise = noise_estimate(y_base, resolution(y) / np.sqrt(block))
    slope = float(np.polyfit(u, y, 1)[0])
    p.update(direction=float(np.sign(slope) or 1.0), y_ref=float(np.percentile(y, 2)), y_per_u=slope, span=span)
    p["drive_reference"] = float(u[0] if case.form == "kelvin_u" else y[0])  # the state before the record
    parameters: dict[str, Any] = {}
    effect = np.zeros_like(y)
    if case.effect != "none":
        make = _unit_effect(case.form, t, u, y, cols, p)
        window = (5.0 * noise, 0.95 * MAX_OVER_SPAN * span)
        target = float(np.clip(p["target_over_span"] * span, *window))
        intensity, clipped = _intensity(make, lambda e: _rms(final(e)), target, case.form, base, window)
        effect = make(intensity)
        unit = UNITS[case.form] if case.form != "gain" else "per kg" if case.effect == "load_dependence" else "per K"
        parameters = {k: p[k] for k in FORM_PARAMETERS[case.form]}
        parameters |= {"intensity": intensity, "intensity_unit": unit, "intensity_held_to_physical_range": clipped}
    y_out = final(y + effect)
    size = _rms(y_out - y_base)
    noise_rng = np.random.default_rng(case.seed + 50_000)  # column sensor noise
    t_out = final(t)
    extras = {
        "load": np.round(final(cols["load"]) + noise_rng.normal(0.0, 0.005, t_out.size), 3),
        "temperature": np.round(final(cols["temperature"]) + noise_rng.normal(0.0, 0.03, t_out.size), 1),
    }
    truth: dict[str, Any] = {
        "case": case.name,
        "effect": case.effect,
        "form": case.form,
        "kind": base.kind,
        "base": base.key,
        "base_files": [f"{base.folder}/{f}" for f in files],
        "parameters": parameters,
        "effect_size": size,
        "noise": noise,
        "span": span,
        "effect_size_over_noise": size / noise,
        "effect_size_over_span": size / span,
        "target_over_span": p["target_over_span"],
        "active_column": {"load_dependence": "load", "temperature_drift": "temperature"}.get(case.effect),
        "load_pattern": patterns["load"],
        "temperature_pattern": patterns["temperature"],
        "note": "nothing injected; the real rig may carry effects of its own" if case.effect == "none" else "",
    }
    return Measurement(
        t_out - t_out[0],
        final(u),
        y_out,
        extras,
        source=f"{base.kind}/{base.key} (injected-real set, record s{case.seed})",
    ), truth
