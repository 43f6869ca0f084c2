"""The Bouc-Wen hysteretic benchmark (Noël & Schoukens 2016), regenerated from its equations.

The system (force ``u`` [N] in, displacement ``y`` [m] out)::

    m_L y'' + c_L y' + k_L y + z(y, y') = u
    z' = alpha y' - beta (gamma |y'| |z|^(nu-1) z + delta y' |z|^nu)

What was checked, and where (``search`` over public repositories, 2026-12-05):

* parameter values ``m_L = 2 kg, c_L = 10 N s/m, k_L = 5e4 N/m, alpha = 5e4 N/m,
  beta = 1e3 1/m, gamma = 0.8, delta = -1.1, nu = 1`` and the equations above: deepSI's
  ``Bouc_wen`` system (Beintema, ``deepSI/systems``), which writes ``z'`` for ``nu = 1``;
* the protocol of the official generator (``BoucWen_ExampleIntegration.m``, Noël & Schoukens
  2015, as copied in dynoNet's ``examples/BW``): working rate ``fs = 750 Hz``, integration at
  ``upsamp = 20`` times that (15 kHz), ``N = 8192`` samples per period, ``P = 5`` periods plus
  one extra period removed after the low-pass filter, a random-phase multisine on the DFT lines
  ``floor(fmin/fres) .. ceil(fmax/fres)`` of the fine grid (``fres = fs/N``, band 5-150 Hz), with
  flat amplitude, scaled to a standard deviation ``A = 50 N``; rest initial state; the output
  decimated by the prime factors of 20 (2, 2, 5) with a FIR low-pass each (MATLAB ``decimate(...,
  'fir')``; here ``scipy.signal.decimate(ftype='fir', zero_phase=True)``), the input down-sampled;
* the benchmark's data loader (nonlinear_benchmarks, Beintema): the test data are one multisine
  period (``uval_multisine``, 8192 samples, scored in steady state) and a sine sweep
  (``uval_sinesweep``); figure of merit RMSE [m].

Not verified here (the benchmark's PDF could not be read from this machine), our stated
choices: the training-output noise ``NOISE_STD_M = 8e-6 m`` (white, Gaussian; about 40 dB below
the response, the level we recall for the benchmark) and the sine sweep (:data:`SWEEP`: linear,
20 -> 40 Hz over 60 s at 50 N, across the 35.6 Hz linearised resonance), so the sweep numbers
are ours and not comparable with published sweep results.

Integration: classical Runge-Kutta 4 at the published fine step ``h = 1/15000 s`` (the brief
allows Newmark or RK); its midpoint inputs come from the same band-limited signal evaluated at
``2 x 15 kHz`` (the multisine is exact there, the sweep is analytic), so nothing is interpolated.
One 15 kHz step costs a few microseconds in plain Python floats; a 6-period realisation
(983 040 steps) takes about 5 s of CPU.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FS_HZ = 750.0
UPSAMPLE = 20
PERIOD_SAMPLES = 8192
TRAIN_PERIODS = 5
BAND_HZ = (5.0, 150.0)
RMS_N = 50.0
NOISE_STD_M = 8e-6


@dataclass(frozen=True)
class BoucWenParameters:
    """The published parameter values (SI units)."""

    m_l: float = 2.0  # kg
    c_l: float = 10.0  # N s/m
    k_l: float = 5e4  # N/m
    alpha: float = 5e4  # N/m
    beta: float = 1e3  # 1/m
    gamma: float = 0.8
    delta: float = -1.1
    nu: float = 1.0


@dataclass(frozen=True)
class Sweep:
    """A linear sine sweep from rest (our definition; the official one could not be checked)."""

    f_start_hz: float = 20.0
    f_end_hz: float = 40.0  # brackets the 35.6 Hz linearised resonance sqrt((k_L + alpha) / m_L)
    duration_s: float = 60.0
    amplitude_n: float = 50.0


PARAMETERS = BoucWenParameters()
SWEEP = Sweep()


def integrate_rk4(u_half: NDArray[np.float64], h: float, p: BoucWenParameters = PARAMETERS) -> NDArray[np.float64]:
    """Displacement [m] at the fine steps for the force ``u_half`` [N] sampled every ``h/2`` s.

    ``u_half[2k]`` is the force at step ``k``, ``u_half[2k+1]`` at its midpoint; the result has
    ``(len(u_half) + 1) // 2`` samples, starting at rest (``y = y' = z = 0``).
    """
    n = (len(u_half) + 1) // 2
    out = np.empty(n)
    uu = u_half.tolist()
    inv_m, c, k, a, b, g, d, nu = 1.0 / p.m_l, p.c_l, p.k_l, p.alpha, p.beta, p.gamma, p.delta, p.nu
    linear_nu = nu == 1.0

    def zdot(v: float, z: float) -> float:
        if linear_nu:
            return a * v - b * (g * abs(v) * z + d * v * abs(z))
        az = abs(z)
        return a * v - b * (g * abs(v) * az ** (nu - 1.0) * z + d * v * az**nu)

    y = v = z = 0.0
    half = 0.5 * h
    out[0] = 0.0
    for i in range(n - 1):
        u0, um, u1 = uu[2 * i], uu[2 * i + 1], uu[2 * i + 2]
        k1y, k1v, k1z = v, (u0 - k * y - c * v - z) * inv_m, zdot(v, z)
        y2, v2, z2 = y + half * k1y, v + half * k1v, z + half * k1z
        k2y, k2v, k2z = v2, (um - k * y2 - c * v2 - z2) * inv_m, zdot(v2, z2)
        y3, v3, z3 = y + half * k2y, v + half * k2v, z + half * k2z
        k3y, k3v, k3z = v3, (um - k * y3 - c * v3 - z3) * inv_m, zdot(v3, z3)
        y4, v4, z4 = y + h * k3y, v + h * k3v, z + h * k3z
        k4y, k4v, k4z = v4, (u1 - k * y4 - c * v4 - z4) * inv_m, zdot(v4, z4)
        y += h / 6.0 * (k1y + 2.0 * k2y + 2.0 * k3y + k4y)
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v)
        z += h / 6.0 * (k1z + 2.0 * k2z + 2.0 * k3z + k4z)
        out[i + 1] = y
    return out


def multisine_half(rng: np.random.Generator, periods: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """One random-phase multisine realisation, ``periods`` periods: (u at 750 Hz, u every h/2).

    As the official generator: flat amplitude on the fine grid's lines inside ``BAND_HZ``,
    uniform random phases, scaled to standard deviation ``RMS_N``.
    """
    n_fine = PERIOD_SAMPLES * UPSAMPLE
    f_res = FS_HZ / PERIOD_SAMPLES
    lines = np.arange(1, math.ceil(BAND_HZ[1] / f_res) + 1)
    lines = lines[lines >= math.floor(BAND_HZ[0] / f_res)]
    phases = rng.uniform(0.0, 2.0 * np.pi, lines.size)
    spectrum = np.zeros(2 * n_fine // 2 + 1, dtype=complex)  # rfft of the signal at 2 x fine rate
    spectrum[lines] = np.exp(1j * phases)
    u_half = np.fft.irfft(spectrum, 2 * n_fine)
    scale = RMS_N / float(np.std(u_half[::2]))
    u_half = np.tile(u_half * scale, periods)
    u_half = np.append(u_half, u_half[0])  # the periodic signal's next sample closes the last step
    return u_half[: -1 : 2 * UPSAMPLE].copy(), u_half


def sweep_half(sweep: Sweep = SWEEP) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The sine sweep: (u at 750 Hz, u every h/2), from rest."""
    n = int(round(sweep.duration_s * FS_HZ))
    t = np.arange(2 * n * UPSAMPLE + 1) / (2 * FS_HZ * UPSAMPLE)
    rate = (sweep.f_end_hz - sweep.f_start_hz) / sweep.duration_s
    u_half = sweep.amplitude_n * np.sin(2 * np.pi * (sweep.f_start_hz * t + 0.5 * rate * t**2))
    return u_half[: -1 : 2 * UPSAMPLE].copy(), u_half


def respond(u_half: NDArray[np.float64]) -> NDArray[np.float64]:
    """Displacement [m] at 750 Hz: RK4 at 15 kHz, decimated by 2, 2, 5 (FIR, zero phase)."""
    from scipy.signal import decimate

    y = integrate_rk4(u_half, 1.0 / (FS_HZ * UPSAMPLE))[:-1]
    for factor in (2, 2, 5):
        y = decimate(y, factor, ftype="fir", zero_phase=True)
    return np.asarray(y, dtype=np.float64)


@dataclass
class Record:
    """One benchmark record at 750 Hz: force [N], displacement [m], the scored sample range."""

    name: str
    u: NDArray[np.float64]
    y: NDArray[np.float64]
    score_from: int  # samples before it are transient (model state settles there, not scored)

    @property
    def t(self) -> NDArray[np.float64]:
        return np.arange(self.u.size) / FS_HZ


def multisine_record(seed: int, periods: int, name: str, noise_std_m: float = 0.0) -> Record:
    """``periods`` multisine periods from rest (one extra period is simulated and dropped, as the
    official generator does against the filter's edge); output noise ``noise_std_m`` [m]."""
    rng = np.random.default_rng(seed)
    u, u_half = multisine_half(rng, periods + 1)
    y = respond(u_half)
    keep = periods * PERIOD_SAMPLES
    noise = rng.normal(0.0, noise_std_m, keep) if noise_std_m > 0 else np.zeros(keep)
    return Record(name, u[:keep], y[:keep] + noise, (periods - 1) * PERIOD_SAMPLES)


def training_records(realisations: int, seed: int = 0, noise_std_m: float = NOISE_STD_M) -> list[Record]:
    """``realisations`` multisines of ``TRAIN_PERIODS`` periods each, noisy outputs (seeds ``seed+i``)."""
    return [
        multisine_record(1000 + seed + i, TRAIN_PERIODS, f"train multisine {i}", noise_std_m)
        for i in range(realisations)
    ]


def test_multisine(seed: int = 0) -> Record:
    """The multisine test: a new realisation from rest, noise-free, scored on its last period
    (two periods: the first brings the system to its periodic steady state)."""
    return multisine_record(900_000 + seed, 2, "test multisine")


def test_sweep(sweep: Sweep = SWEEP) -> Record:
    """The sine-sweep test from rest, noise-free, scored over the whole record."""
    u, u_half = sweep_half(sweep)
    y = respond(u_half)[: u.size]
    return Record("test sine sweep", u, y, 0)
