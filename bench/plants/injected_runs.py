"""A held-out scoring set for ``pmactl diagnose RUN.csv [RUN.csv ...]``: real campaigns of short runs,
one known effect injected, given as separate runs.

The bases are the real pneumatic-muscle campaigns of ``../shared/data/pam_muscle_sensory`` (never
copied into the repository): every log of a folder (or one half of a long folder) is one run, one
inflate/deflate cycle of 100-250 samples at 30-60 Hz on its own, not quite uniform clock restarting
at 0, as labs record them. For each base: the runs as measured (effect ``none``) and one campaign
per effect, injected into each run on its native time (memory restarts at each run: the muscle
rests between runs):

- creep ``kelvin_y``: three Kelvin-Voigt relaxations (1-30 s, log-spread) driven by the run's output;
- rate_dependence ``viscous`` (a term in the low-passed input rate) or ``rate_lag`` (a lag of y that
  grows with |du/dt|), the rate normalised over the whole campaign;
- transport_delay ``shift``: y(t - d) within each run;
- load_dependence ``compliance`` / ``gain``: one hanging mass per run (0-6 kg in 0.5 kg steps,
  constant within the run), an offset or a stroke scale proportional to it;
- temperature_drift ``offset`` / ``gain``: a temperature that heats and cools over the campaign's
  clock (runs laid end to end), nearly constant within one run.

Every campaign carries both a per-run ``load`` and a ``temperature`` column; only the injected
effect's column acts (the others are decoys). The effect's RMS over the campaign is solved to land
on a draw from 3-9 % of y's span and at least 5x the noise, as in :mod:`bench.plants.injected_real`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from bench.plants.injected_real import _lag, _solve, lowpass, temperature_column
from bench.plants.real_records import noise_estimate, resolution
from host.data import Measurement

Array = NDArray[np.float64]
FOLDER = "pam_muscle_sensory"
FORMS: dict[str, tuple[str, ...]] = {
    "none": ("as_measured",),
    "creep": ("kelvin_y",),
    "rate_dependence": ("viscous", "rate_lag"),
    "transport_delay": ("shift",),
    "load_dependence": ("compliance", "gain"),
    "temperature_drift": ("offset", "gain"),
}
TARGET_OVER_SPAN = (0.03, 0.09)
MIN_OVER_NOISE = 5.0
SEED_BASE = 7300
RATE_LOWPASS_S = 0.1
CREEP_TAUS_S = (1.0, 30.0)
# the oracle's waveform is the effect computed from y smoothed over this window [s] (cubic
# Savitzky-Golay): an effect made from the measured y (a shift, a lag, a relaxation of y) carries
# y's own noise, and a regressor holding the record's noise "detects" itself
ORACLE_SMOOTHING_S = 0.2


@dataclass(frozen=True)
class Campaign:
    """Runs ``first..last`` (file names, inclusive) of one folder; ``stride`` keeps every k-th."""

    key: str
    folder: str
    first: str
    last: str
    stride: int = 1


CAMPAIGNS = (
    Campaign("18-03_odd", "18-03-2026_Length_Characterisation", "S001P001.csv", "S019P002.csv", 2),
    Campaign("18-03_even", "18-03-2026_Length_Characterisation", "S001P002.csv", "S019P003.csv", 2),
    Campaign("31-03_odd", "31-03-2026_Length_Characterisation", "S001P001.csv", "S019P002.csv", 2),
    Campaign("31-03_even", "31-03-2026_Length_Characterisation", "S001P002.csv", "S019P003.csv", 2),
    Campaign("07-17", "2026-07-17_Literature_Comparison", "S001P001.csv", "S999.csv"),
    Campaign("07-21+22", "2026-07-2", "S001P001.csv", "S999.csv"),
)


@dataclass(frozen=True)
class RunsCase:
    campaign: str
    effect: str
    form: str
    seed: int

    @property
    def name(self) -> str:
        return f"runs/{self.campaign}/{self.effect}:{self.form}/s{self.seed}"


def run_paths(data_root: Path, c: Campaign) -> list[Path]:
    """The campaign's run files in name order (empty when the data are absent)."""
    root = Path(data_root) / FOLDER
    folders = sorted(p for p in root.glob(f"{c.folder}*") if p.is_dir())
    paths = sorted((p for f in folders for p in f.glob("*.csv") if c.first <= p.name <= c.last), key=lambda p: p.name)
    return paths[:: c.stride]


def runs_cases(data_root: Path) -> list[RunsCase]:
    """Every campaign found x (``none`` + one campaign per effect, forms alternating over campaigns)."""
    out = []
    for i, c in enumerate(CAMPAIGNS):
        if len(run_paths(data_root, c)) < 4:
            continue
        for j, (effect, forms) in enumerate(FORMS.items()):
            out.append(RunsCase(c.key, effect, forms[i % len(forms)], SEED_BASE + 10 * i + j))
    return out


def _read(path: Path) -> tuple[Array, Array, Array]:
    table = np.loadtxt(path, delimiter=",", skiprows=1, usecols=(0, 1, 2), ndmin=2)
    keep = np.r_[True, np.diff(table[:, 0]) > 0]  # a repeated logger timestamp carries no new time
    table = table[keep]
    return table[:, 0] - table[0, 0], table[:, 1], table[:, 2]


def _unit_effects(
    case: RunsCase, runs: list[tuple[Array, Array, Array]], cols: list[dict[str, Array]], rng: np.random.Generator
) -> tuple[Callable[[float], list[Array]], dict[str, Any]]:
    """The effect per run as a function of one intensity, and the parameters drawn."""
    u_all = np.concatenate([u for _, u, _ in runs])
    y_all = np.concatenate([y for _, _, y in runs])
    direction = float(np.sign(np.polyfit(u_all, y_all, 1)[0]) or 1.0)
    span = float(np.ptp(y_all))
    y_ref = float(np.percentile(y_all, 2))
    p: dict[str, Any] = {"direction": direction}
    if case.form == "kelvin_y":
        edges = np.linspace(np.log(CREEP_TAUS_S[0]), np.log(CREEP_TAUS_S[1]), 4)
        taus = [float(np.exp(rng.uniform(a, b))) for a, b in zip(edges[:-1], edges[1:])]
        w = rng.uniform(0.5, 1.5, 3)
        w = w / w.sum()
        p.update(taus_s=taus, weights=w.tolist())
        relax = [sum(wi * lowpass(t, y - y[0], tau, 0.0) for wi, tau in zip(w, taus)) for t, _, y in runs]
        return lambda c: [c * r for r in relax], p
    if case.form in ("viscous", "rate_lag"):
        rates = [lowpass(t, np.gradient(u, t), RATE_LOWPASS_S) for t, u, _ in runs]
        scale = max(float(np.percentile(np.abs(np.concatenate(rates)), 99)), 1e-12)
        rates = [r / scale for r in rates]
        if case.form == "viscous":
            return lambda k: [k * direction * span * r for r in rates], p
        return lambda tau: [
            _lag(t, y, tau * np.minimum(np.abs(r), 3.0), float(y[0])) - y for (t, _, y), r in zip(runs, rates)
        ], p
    if case.form == "shift":
        return lambda d: [np.interp(t - d, t, y, left=y[0]) - y for t, _, y in runs], p
    name = "load" if case.effect == "load_dependence" else "temperature"
    reference = float(min(c[name].min() for c in cols))
    sign = -direction if case.effect == "load_dependence" else float(rng.choice([-1.0, 1.0]))
    p.update(sign=sign)
    changes = [c[name] - reference for c in cols]
    if case.form in ("compliance", "offset"):
        return lambda a: [sign * a * ch for ch in changes], p
    return lambda g: [sign * g * ch * (y - y_ref) for ch, (_, _, y) in zip(changes, runs)], p


def _smoothed(t: Array, y: Array) -> Array:
    """``y`` smoothed over :data:`ORACLE_SMOOTHING_S` (cubic Savitzky-Golay over the run's median step)."""
    from scipy.signal import savgol_filter

    step = float(np.median(np.diff(t))) if t.size > 1 else 1.0
    window = min(2 * int(ORACLE_SMOOTHING_S / step / 2) + 1, y.size - (1 - y.size % 2))
    return np.asarray(savgol_filter(y, window, 3), dtype=np.float64) if window > 3 else y


def _rms(parts: list[Array]) -> float:
    x = np.concatenate(parts)
    return float(np.sqrt(np.mean(x * x)))


def injected_runs(case: RunsCase, data_root: Path) -> tuple[list[Measurement], dict[str, Any]]:
    """The runs of ``case`` (each t from 0 [s], u [bar], y [mm], ``load`` [kg], ``temperature``
    [degC]) and its truth (effect, form, parameters, size over span and noise, files)."""
    campaign = next(c for c in CAMPAIGNS if c.key == case.campaign)
    paths = run_paths(data_root, campaign)
    if not paths:
        raise FileNotFoundError(f"no runs of {campaign.key} under {Path(data_root) / FOLDER}")
    runs = [_read(p) for p in paths]
    rng = np.random.default_rng(case.seed)
    # the campaign's clock: runs laid end to end with a pause of 10 s between them
    starts = np.cumsum([0.0] + [float(t[-1]) + 10.0 for t, _, _ in runs[:-1]])
    clock = np.concatenate([t + s for (t, _, _), s in zip(runs, starts)])
    temperature, pattern = temperature_column(clock, rng)
    masses = np.round(rng.uniform(0.0, 6.0, len(runs)) * 2) / 2
    cols = []
    offset = 0
    for (t, _, _), mass in zip(runs, masses):
        cols.append({"load": np.full(t.size, mass), "temperature": temperature[offset : offset + t.size]})
        offset += t.size
    y_all = np.concatenate([y for _, _, y in runs])
    span = float(np.ptp(y_all))
    noise = float(np.median([noise_estimate(y, resolution(y)) for _, _, y in runs]))
    target = float(np.clip(rng.uniform(*TARGET_OVER_SPAN) * span, MIN_OVER_NOISE * noise, 0.12 * span))
    effects = [np.zeros_like(y) for _, _, y in runs]
    parameters: dict[str, Any] = {}
    oracle = effects
    if case.effect != "none":
        state = rng.bit_generator.state
        make, parameters = _unit_effects(case, runs, cols, rng)
        intensity = _solve(make, _rms, target, case.form not in ("rate_lag", "shift"))
        effects = make(intensity)
        parameters["intensity"] = intensity
        rng.bit_generator.state = state  # the same draws, on the noise-free run
        smooth = [(t, u, _smoothed(t, y)) for t, u, y in runs]
        oracle = _unit_effects(case, smooth, cols, rng)[0](intensity)
    noise_rng = np.random.default_rng(case.seed + 50_000)  # column sensor noise
    out = []
    for path, (t, u, y), e, c in zip(paths, runs, effects, cols):
        extras = {
            "load": np.round(c["load"] + noise_rng.normal(0.0, 0.005, t.size), 3),
            "temperature": np.round(c["temperature"] + noise_rng.normal(0.0, 0.03, t.size), 1),
        }
        out.append(Measurement(t, u, y + e, extras, source=f"{FOLDER}/{path.parent.name}/{path.name} ({case.name})"))
    size = _rms(effects)
    truth = {
        "case": case.name,
        "effect": case.effect,
        "form": case.form,
        "runs": len(out),
        "samples": int(sum(len(m) for m in out)),
        "parameters": parameters,
        "effect_size": size,
        "effect_size_over_span": size / span,
        "effect_size_over_noise": size / noise if noise > 0 else float("inf"),
        "temperature_pattern": pattern,
        "waveforms": effects,  # the injected effect per run on the run's own time [mm]
        # the same effect made from the smoothed y (no copy of the record's own noise): the oracle's regressor
        "oracle_waveforms": oracle,
    }
    return out, truth
