"""Every effect in two functional forms, applied around a core of :mod:`bench.plants.cores`.

Input side: dead times (constant; or longer on deflation than on inflation). Width side (the
core's hysteresis width): rate-dependent weight, load widening the loop, temperature narrowing
it. Output side: damping that grows with speed, creep (logarithmic; two time constants), load
and temperature through nonlinear maps on gain and offset. The load and temperature columns
always move: when they are not the effect they are decoys (load steps, a random-walk room).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass

Array = NDArray[np.float64]
FORMS: dict[str, tuple[str, ...]] = {
    "none": ("none",),
    "rate_dependence": ("weight", "damping"),
    "creep": ("log", "two_tau"),
    "transport_delay": ("constant", "asymmetric"),
    "load_dependence": ("gain", "width"),
    "temperature_drift": ("gain", "narrowing"),
}


def load_steps(t: Array, rng: np.random.Generator) -> Array:
    """Hanging mass [kg] stepping between 0 and 8 kg at 4-7 random times."""
    n_steps = int(rng.integers(4, 8))
    times = np.sort(rng.uniform(0.1, 0.95, n_steps)) * t[-1]
    levels = rng.uniform(0.0, 8.0, n_steps + 1)
    return levels[np.searchsorted(times, t)]


def warming(t: Array, rng: np.random.Generator) -> Array:
    """Muscle temperature [degC]: 22 degC plus a 8-25 K rise with a 30-120 s time constant."""
    rise, tau = rng.uniform(8.0, 25.0), rng.uniform(30.0, 120.0)
    return 22.0 + rise * (1 - np.exp(-t / tau))


def random_walk_room(t: Array, rng: np.random.Generator) -> Array:
    """An unrelated, slowly wandering temperature [degC] (smoothed random walk, ~3-8 K span)."""
    dt = float(t[1] - t[0])
    walk = np.cumsum(rng.normal(0.0, 1.0, t.size)) * np.sqrt(dt)
    walk = lowpass(walk, dt, 5.0)
    return 22.0 + rng.uniform(3.0, 8.0) * (walk - walk.mean()) / (np.ptp(walk) or 1.0)


def delayed(u: Array, dt_s: float, rise_s: float, fall_s: float) -> Array:
    """``u`` seen through a line whose dead time is ``rise_s`` while it rises, ``fall_s`` while it falls."""
    n = u.size
    idx = np.arange(n)
    rising = np.gradient(u) >= 0
    lag = np.where(rising, rise_s, fall_s) / dt_s
    lag = lowpass(lag, dt_s, 0.05)  # the line fills and empties continuously, no jumps back in time
    src = np.clip(idx - lag, 0, n - 1)
    return np.interp(src, idx, u)


def speed_damped(x: Array, dt_s: float, c: float, power: float) -> Array:
    """Output that trails ``x`` with a damping force ``c |v|^power`` (explicit, never overshoots)."""
    out = np.empty_like(x)
    y = float(x[0])
    for i, target in enumerate(x.tolist()):
        e = target - y
        step = min(abs(e), dt_s * (abs(e) / c) ** (1.0 / power))
        y += step if e > 0 else -step
        out[i] = y
    return out


def creep(x: Array, dt_s: float, taus: Array, fractions: Array) -> Array:
    """``(1 - sum f) x + sum f_i lowpass(x, tau_i)``: after a step, the rest of the way comes slowly."""
    return (1.0 - fractions.sum()) * x + sum(f * lowpass(x, dt_s, tau) for f, tau in zip(fractions, taus))


Core = Callable[[Array, float, Array, dict[str, float]], Array]


def apply(
    core: Core,
    params: dict[str, float],
    u: Array,
    dt_s: float,
    effect: str,
    form: str,
    rng: np.random.Generator,
) -> tuple[Array, dict[str, Array], dict[str, object]]:
    """Run ``core`` with ``effect`` in ``form``: returns ``y`` (noiseless), the extra columns, the truth."""
    t = np.arange(u.size, dtype=np.float64) * dt_s
    load = load_steps(t, rng)
    temperature = warming(t, rng) if effect == "temperature_drift" else random_walk_room(t, rng)
    width = np.ones_like(u)
    truth: dict[str, object] = {"effect": effect, "form": form}
    drive = u
    if effect == "rate_dependence" and form == "weight":
        speed = np.abs(lowpass(np.gradient(u, dt_s), dt_s, 0.05))
        c, p = rng.uniform(0.8, 1.6), rng.uniform(0.7, 1.5)
        width = 1.0 + c * (speed / np.percentile(speed, 95)) ** p
        truth.update(widening=c, power=p)
    if effect == "transport_delay":
        rise = rng.uniform(0.06, 0.3)
        fall = rise * (rng.uniform(1.5, 2.5) if form == "asymmetric" else 1.0)
        drive = delayed(u, dt_s, rise, fall)
        truth.update(dead_time_rise_s=rise, dead_time_fall_s=fall)
    if effect == "load_dependence" and form == "width":
        a = rng.uniform(0.6, 1.2)
        width = 1.0 + a * np.sqrt(load / 8.0)
        truth.update(width_per_sqrt_load=a)
    if effect == "temperature_drift" and form == "narrowing":
        b = rng.uniform(0.02, 0.04)
        width = np.exp(-b * (temperature - temperature[0]))
        truth.update(width_decay_per_k=b)
    x = core(drive, dt_s, width, params)
    span = float(np.ptp(x)) or 1.0
    if effect == "rate_dependence" and form == "damping":
        v95 = float(np.percentile(np.abs(np.gradient(x, dt_s)), 95)) or 1.0
        share, power = rng.uniform(0.03, 0.08), rng.uniform(1.3, 1.8)
        x = speed_damped(x, dt_s, share * span / v95**power, power)
        truth.update(lag_share_at_speed95=share, power=power)
    if effect == "creep":
        if form == "log":
            taus, total = np.geomspace(0.5, 100.0, 6), rng.uniform(0.05, 0.10)
            fractions = np.full(6, total / 6)
        else:
            taus = np.array([rng.uniform(1.0, 4.0), rng.uniform(20.0, 60.0)])
            fractions = np.array([rng.uniform(0.02, 0.05), rng.uniform(0.03, 0.06)])
        x = creep(x, dt_s, taus, fractions)
        truth.update(creep_taus_s=taus.tolist(), creep_fractions=fractions.tolist())
    if effect == "load_dependence" and form == "gain":
        a, b = rng.uniform(0.05, 0.15), rng.uniform(0.03, 0.08)
        mid = float(np.median(x))
        x = mid + (x - mid) * (1.0 - a * (load / 8.0) ** 1.5) - b * span * (load / 8.0) ** 2
        truth.update(gain_loss=a, offset_share=b)
    if effect == "temperature_drift" and form == "gain":
        a = rng.uniform(0.08, 0.15)
        rise = np.tanh((temperature - temperature[0]) / 10.0)
        lo = float(np.min(x))
        x = lo + (x - lo) * (1.0 + a * rise)
        truth.update(softening=a)
    return x, {"load": load, "temperature": temperature}, truth
