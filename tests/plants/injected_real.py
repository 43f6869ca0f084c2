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

import functools
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from host.data import Measurement

Array = NDArray[np.float64]
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
PIEZO_BLOCK = 10  # 10 kHz -> 1 kHz
SEED_BASE = 9100


@dataclass(frozen=True)
class BaseRecord:
    """One real record: files ``first..last`` (by name) of one folder, joined in name order."""

    key: str
    kind: str  # "piezo" or "muscle"
    folder: str
    first: str
    last: str
    tau_range_s: tuple[float, float]  # creep time constants
    rate_lowpass_s: float  # low-pass of du/dt (quantised input)
    min_delay_s: float  # the shortest transport delay injected


def _piezo(name: str) -> BaseRecord:
    return BaseRecord(name, "piezo", "piezo_dspace", f"{name}.csv", f"{name}.csv", (0.05, 2.0), 0.002, 0.0005)


def _muscle(key: str, folder: str, first: str, last: str) -> BaseRecord:
    return BaseRecord(key, "muscle", f"pam_muscle_sensory/{folder}", first, last, (1.0, 30.0), 0.1, 0.02)


BASES = (
    _piezo("20_hz_no_lp"),
    _piezo("bigsine_1"),
    _piezo("prbn_1"),
    _piezo("sine100_1"),
    _piezo("tri50_1"),
    _muscle("18-03_S001-S007", "18-03-2026_Length_Characterisation", "S001P001.csv", "S007P003.csv"),
    _muscle("31-03_S011-S019", "31-03-2026_Length_Characterisation", "S011P001.csv", "S019P003.csv"),
    _muscle("07-17_all", "2026-07-17_Literature_Comparison", "S001P001.csv", "S012P002.csv"),
    _muscle("07-21_all", "2026-07-21_Literature_Comparison", "S013P001.csv", "S015P002.csv"),
    _muscle("07-22_all", "2026-07-22_Literature_Comparison", "S016P001.csv", "S021P002.csv"),
)
BY_KEY = {b.key: b for b in BASES}


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


def _paths(data_root: Path, base: BaseRecord) -> list[Path]:
    folder = data_root / base.folder
    return sorted(p for p in folder.glob("*.csv") if base.first <= p.name <= base.last)


def injected_cases(data_root: Path) -> list[InjectedCase]:
    """Every base record found under ``data_root`` x (``none`` + one record per effect).

    Effects with two forms alternate the form over the base records, so each form occurs on both
    kinds of data."""
    out: list[InjectedCase] = []
    for i, base in enumerate(BASES):
        if not _paths(Path(data_root), base):
            continue
        for j, (effect, forms) in enumerate(FORMS.items()):
            out.append(InjectedCase(base.key, base.kind, effect, forms[i % len(forms)], SEED_BASE + 10 * i + j))
    return out


@functools.lru_cache(maxsize=12)
def _native(data_root: str, key: str) -> tuple[Array, Array, Array, tuple[str, ...]]:
    """t [s] (continuous over joined logs), u, y on the files' own time base, and the file names."""
    base = BY_KEY[key]
    paths = _paths(Path(data_root), base)
    if not paths:
        raise FileNotFoundError(f"no files {base.first}..{base.last} in {Path(data_root) / base.folder}")
    ts, us, ys = [], [], []
    offset = 0.0
    for path in paths:
        with path.open() as handle:
            header = [h.strip() for h in handle.readline().split(",")]
        if header[:3] != ["t", "u", "y"]:
            raise ValueError(f"{path}: expected columns t,u,y first, found {header}")
        table = np.loadtxt(path, delimiter=",", skiprows=1, usecols=(0, 1, 2), ndmin=2)
        jumps = np.abs(np.diff(table[:, 1]))
        if jumps.size > 2 and jumps[-1] > 5.0 * jumps[:-1].max():
            table = table[:-1]  # the dSPACE captures wrap round: the last sample is the first again
        t = table[:, 0] - table[0, 0]
        ts.append(t + offset)
        offset = float(ts[-1][-1] + np.median(np.diff(t)))  # the next log starts one step later
        us.append(table[:, 1])
        ys.append(table[:, 2])
    return np.concatenate(ts), np.concatenate(us), np.concatenate(ys), tuple(p.name for p in paths)


def coarsen(kind: str, t: Array, x: Array) -> Array:
    """The native-time signal ``x`` on the record's final uniform grid (a linear operation):
    block means of :data:`PIEZO_BLOCK` samples for the piezo, linear interpolation onto the
    median step for the muscle."""
    if kind == "piezo":
        n = x.size // PIEZO_BLOCK * PIEZO_BLOCK
        return np.asarray(x[:n].reshape(-1, PIEZO_BLOCK).mean(axis=1), dtype=np.float64)
    step = float(np.median(np.diff(t)))
    grid = t[0] + step * np.arange(int(np.floor((t[-1] - t[0]) / step)) + 1)
    return np.asarray(np.interp(grid, t, x), dtype=np.float64)


def noise_estimate(y: Array, resolution: float) -> float:
    """Output noise [y units]: the 10th percentile over windows of the RMS second difference / sqrt(6)
    (white noise on the quietest stretches), floored at the quantisation noise resolution/sqrt(12)."""
    e2 = np.diff(y, 2)
    width = max(20, y.size // 50)
    n = e2.size // width
    rms = np.sqrt(np.mean(e2[: n * width].reshape(n, width) ** 2, axis=1))
    return max(float(np.percentile(rms, 10)) / np.sqrt(6.0), resolution / np.sqrt(12.0))


def _resolution(y: Array) -> float:
    steps = np.abs(np.diff(y))
    steps = steps[steps > 1e-12]
    return float(np.percentile(steps, 5)) if steps.size else 0.0


def lowpass(t: Array, x: Array, tau: float, start: float | None = None) -> Array:
    """First-order low-pass (time constant ``tau`` [s]) of ``x`` sampled at times ``t``; state starts at
    ``start`` (default ``x[0]``)."""
    s0 = float(x[0]) if start is None else start
    dts = np.diff(t)
    if np.ptp(dts) <= 1e-9 * np.median(dts):  # uniform: a filter call
        a = 1.0 - np.exp(-float(dts[0]) / tau)
        out, _ = lfilter([a], [1.0, a - 1.0], x, zi=[(1.0 - a) * s0])
        return np.asarray(out, dtype=np.float64)
    alphas = 1.0 - np.exp(-np.concatenate([[dts[0]], dts]) / tau)
    out = np.empty_like(x)
    s = s0
    for i, (a, v) in enumerate(zip(alphas.tolist(), x.tolist())):
        s += a * (v - s)
        out[i] = s
    return out


def _varying_lag(t: Array, y: Array, tau: Array) -> Array:
    """First-order lag of ``y`` whose time constant ``tau`` [s] changes sample by sample."""
    dts = np.concatenate([[0.0], np.diff(t)])
    alphas = (1.0 - np.exp(-dts / np.maximum(tau, 1e-12))).tolist()
    out = np.empty_like(y)
    s = float(y[0])
    for i, (a, v) in enumerate(zip(alphas, y.tolist())):
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
        drive = y - y[0] if form == "kelvin_y" else p["y_per_u"] * (u - u[0])
        relax = sum(w * lowpass(t, drive, tau, 0.0) for w, tau in zip(p["weights"], p["taus_s"]))
        return lambda c: c * relax
    if form in ("viscous", "rate_lag"):
        rate = lowpass(t, np.gradient(u, t), p["rate_lowpass_s"])
        rate = rate / max(float(np.percentile(np.abs(rate), 99)), 1e-12)  # robust to steps in u
        if form == "viscous":
            return lambda k: k * direction * p["span"] * rate
        return lambda tau_ref: _varying_lag(t, y, tau_ref * np.minimum(np.abs(rate), 3.0)) - y
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
    edges = np.linspace(lo, hi, 4)
    return {
        "effect": case.effect,
        "taus_s": [float(np.exp(rng.uniform(a, b))) for a, b in zip(edges[:-1], edges[1:])],
        "weights": (lambda w: [float(x) for x in w / w.sum()])(rng.uniform(0.5, 1.5, 3)),
        "rate_lowpass_s": base.rate_lowpass_s,
        "sign": -1.0 if case.effect == "load_dependence" else float(rng.choice([-1.0, 1.0])),
        "target_over_span": float(rng.uniform(*TARGET_OVER_SPAN)),
    }


def _rms(x: Array) -> float:
    return float(np.sqrt(np.mean(x * x)))


def _solve(effect: Callable[[float], Array], size: Callable[[Array], float], target: float, linear: bool) -> float:
    """The intensity whose effect has RMS ``target`` on the final grid."""
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
    t, u, y, files = _native(str(data_root), case.base)
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
    noise = noise_estimate(y_base, _resolution(y) / np.sqrt(block))
    slope = float(np.polyfit(u, y, 1)[0])
    p.update(direction=float(np.sign(slope) or 1.0), y_ref=float(np.percentile(y, 2)), y_per_u=slope, span=span)
    parameters: dict[str, Any] = {}
    effect = np.zeros_like(y)
    if case.effect != "none":
        make = _unit_effect(case.form, t, u, y, cols, p)
        window = (5.0 * noise, 0.95 * MAX_OVER_SPAN * span)
        target = float(np.clip(p["target_over_span"] * span, *window))
        intensity, clipped = _intensity(make, lambda e: _rms(final(e)), target, case.form, base, window)
        effect = make(intensity)
        keys = {"kelvin_y": ("taus_s", "weights"), "kelvin_u": ("taus_s", "weights", "y_per_u")}
        keys |= {"viscous": ("rate_lowpass_s", "direction"), "rate_lag": ("rate_lowpass_s",)}
        keys |= {"compliance": ("direction",), "offset": ("sign",), "gain": ("sign", "y_ref")}
        parameters = {k: p[k] for k in keys.get(case.form, ())}
        parameters["intensity"] = intensity
        parameters["intensity_held_to_physical_range"] = clipped
        parameters["intensity_unit"] = {
            "kelvin_y": "fraction of y",
            "kelvin_u": "fraction of fitted y(u)",
            "viscous": "span at the 99th-percentile rate",
            "rate_lag": "s (lag at the 99th-percentile rate)",
            "shift": "s (delay)",
            "compliance": "y units per kg",
            "offset": "y units per K",
            "gain": "per kg" if case.effect == "load_dependence" else "per K",
        }[case.form]
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
    return Measurement(t_out - t_out[0], final(u), y_out, extras, source=case.name), truth
