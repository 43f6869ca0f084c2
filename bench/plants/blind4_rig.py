"""The blind4 rig around a core: what every record has, effect-free ones too (the confounds).

Pressure side: the valve's lag (:func:`valve`, part of every core) and a supply sag
(:func:`supply_droop`), the shop compressor's tank cycling between its cut-in and cut-out
pressures (a sawtooth of 25-60 s) which the regulator passes on as a droop of 0.4-1.2 % of the
set pressure.

Stroke side (:func:`rig_reading`): the rod guide's linkage backlash plus its friction (a play
of 0.08-0.23 mm radius), a compliant mounting plate carrying the muscle (a resonance of
6-20 Hz whose mass the payload adds to), then the stroke transducer: a slow thermal offset of
its own electronics (an Ornstein-Uhlenbeck wander, 0.03-0.1 mm over 20-80 s, *not* the
temperature column's), 1/f (pink) noise of 3-10 um RMS and rare single-sample spikes (0.3-1.5 mm,
0.02-0.06 per s) from the cable's connector, the reading clipped to the transducer's range.
All the confounds are seeded by the plant parameters: the same in a record with its effect on
and off.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from bench.plants.filters import lowpass, resonance

Array = NDArray[np.float64]
G_MS2 = 9.81
RANGE_MM = (-2.0, 90.0)  # the transducer's measuring range


def supply_droop(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """The set pressure [bar] the regulator reaches for the command ``u`` [bar] while the
    compressor cycles: ``u (1 - droop saw(t / compressor_s))``."""
    t = np.arange(u.size, dtype=np.float64) * dt_s
    saw = (t / p["compressor_s"] + p["compressor_phase"]) % 1.0
    return np.asarray(u * (1.0 - p["droop"] * saw), dtype=np.float64)


def valve(u: Array, dt_s: float, p: dict[str, float]) -> Array:
    """Muscle pressure [bar] behind the proportional valve: a first-order lag ``tau_valve_s``."""
    return lowpass(u, dt_s, p["tau_valve_s"])


def stiffness_n_mm(pressure: Array, p: dict[str, float]) -> Array:
    """Tangent axial stiffness [N/mm] of the muscle at ``pressure`` [bar]: ``k0 + k1 p / peak``."""
    return np.asarray(p["k0_n_mm"] + p["k1_n_mm"] * np.clip(pressure, 0.0, None) / p["peak"], dtype=np.float64)


def play(x: Array, radius: Array | float) -> Array:
    """Backlash of half-width ``radius`` [mm] (per sample or fixed): the output moves only when
    ``x`` pushes it, starting centred on ``x[0]``."""
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), x.shape)
    out = np.empty_like(x)
    y = float(x[0])
    for i, (xi, ri) in enumerate(zip(x.tolist(), r.tolist())):
        if y < xi - ri:
            y = xi - ri
        elif y > xi + ri:
            y = xi + ri
        out[i] = y
    return out


def varying_resonance(x: Array, dt_s: float, f_hz: Array, zeta: float) -> Array:
    """``y'' + 2 zeta wn y' + wn^2 y = wn^2 x`` with ``wn = 2 pi f_hz`` per sample, each step the
    exact zero-order-hold transition of that sample's (underdamped) system, starting at rest."""
    wn = 2.0 * np.pi * np.asarray(f_hz, dtype=np.float64)
    sigma, wd = zeta * wn, wn * math.sqrt(1.0 - zeta * zeta)
    decay, c, s = np.exp(-sigma * dt_s), np.cos(wd * dt_s), np.sin(wd * dt_s) / wd
    # Phi = e^{-sigma h} (c I + s (A + sigma I)),  A = [[0, 1], [-wn^2, -2 sigma]]
    p11, p12 = decay * (c + s * sigma), decay * s
    p21, p22 = -decay * s * wn * wn, decay * (c - s * sigma)
    # with the input held over a step, the offset from it, (y - x, y'), evolves by Phi
    out = np.empty_like(x)
    y, v = float(x[0]), 0.0
    for i, (xi, a, b, c_, d) in enumerate(zip(x.tolist(), p11.tolist(), p12.tolist(), p21.tolist(), p22.tolist())):
        out[i] = y  # as filters.resonance: the output at a sample answers the inputs before it
        e = y - xi
        y, v = xi + a * e + b * v, c_ * e + d * v
    return out


def _pink(n: int, rng: np.random.Generator) -> Array:
    """Unit-RMS noise with a 1/f power spectrum (white noise shaped in the frequency domain)."""
    spec = np.fft.rfft(rng.standard_normal(n))
    f = np.arange(spec.size, dtype=np.float64)
    spec *= 1.0 / np.sqrt(np.maximum(f, 1.0))
    spec[0] = 0.0
    x = np.fft.irfft(spec, n)
    return np.asarray(x / max(float(np.std(x)), 1e-12), dtype=np.float64)


def sensor_confounds(n: int, dt_s: float, p: dict[str, float]) -> Array:
    """The transducer's own additive error [mm] over ``n`` samples: thermal offset wander, pink
    noise and spikes (deterministic by ``sensor_seed``)."""
    rng = np.random.default_rng(int(p["sensor_seed"]))
    a = math.exp(-dt_s / p["offset_tau_s"])
    kicks = rng.standard_normal(n) * p["offset_mm"] * math.sqrt(1.0 - a * a)
    offset = np.empty(n)
    o = float(rng.normal(0.0, p["offset_mm"]))
    for i, k in enumerate(kicks.tolist()):
        o = a * o + k
        offset[i] = o
    offset -= offset[0]  # the transducer is zeroed at the start of the record
    spikes = np.zeros(n)
    hit = rng.random(n) < p["spike_rate_hz"] * dt_s
    spikes[hit] = rng.choice([-1.0, 1.0], int(hit.sum())) * rng.uniform(0.3, 1.5, int(hit.sum()))
    return np.asarray(offset + p["pink_mm"] * _pink(n, rng) + spikes, dtype=np.float64)


def rig_reading(
    x: Array,
    dt_s: float,
    p: dict[str, float],
    extra_mass_kg: Array | None = None,
) -> Array:
    """The transducer's reading [mm] of a muscle contraction ``x`` [mm]: through the linkage
    play, the mounting plate (its mass plus
    ``extra_mass_kg``, the payload's change since the start, which also sags the plate by
    ``g m / k_mount``; the plate's mass never below half its own) and the sensor errors."""
    linked = play(x, p["backlash_mm"] + p["guide_mm"])
    if extra_mass_kg is None:
        mounted = resonance(linked, dt_s, p["f_mount_hz"], p["zeta_mount"])
    else:
        mass = np.maximum(p["mount_kg"] + extra_mass_kg, 0.5 * p["mount_kg"])
        f_hz = p["f_mount_hz"] * np.sqrt(p["mount_kg"] / mass)
        sag = G_MS2 * extra_mass_kg / (p["k_mount_n_mm"])
        mounted = varying_resonance(linked - sag, dt_s, f_hz, p["zeta_mount"])
    reading = mounted + sensor_confounds(x.size, dt_s, p)
    return np.asarray(np.clip(reading, *RANGE_MM), dtype=np.float64)


def draw_rig(rng: np.random.Generator, peak: float, k0: float, k1: float) -> dict[str, float]:
    """The rig's constants (the muscle's tangent stiffness ``k0 + k1 p / peak`` [N/mm] given)."""
    return {
        "peak": peak,
        "tau_valve_s": rng.uniform(0.015, 0.045),
        "droop": rng.uniform(0.004, 0.012),
        "compressor_s": rng.uniform(25.0, 60.0),
        "compressor_phase": rng.uniform(0.0, 1.0),
        "k0_n_mm": k0,
        "k1_n_mm": k1,
        "backlash_mm": rng.uniform(0.03, 0.08),
        "guide_mm": rng.uniform(0.05, 0.15),
        "f_mount_hz": rng.uniform(6.0, 20.0),
        "zeta_mount": rng.uniform(0.06, 0.25),
        "mount_kg": rng.uniform(1.5, 4.0),
        "k_mount_n_mm": rng.uniform(20.0, 60.0),
        "sensor_seed": float(rng.integers(1 << 30)),
        "offset_mm": rng.uniform(0.03, 0.1),
        "offset_tau_s": rng.uniform(20.0, 80.0),
        "pink_mm": rng.uniform(0.003, 0.01),
        "spike_rate_hz": rng.uniform(0.02, 0.06),
    }
