"""First-order-plus-dead-time models ``G(s) = K e^{-sL} / (1 + sT)`` from measured data (PAMInertial).

Two ways in, one result (:class:`FOTDFit`):

* **Frequency response** (:func:`fit_frequency_response`): PAMInertial's method. The first harmonics
  of input and output at two or more frequencies (:mod:`host.identify.harmonics`) give
  ``G(jw_i)``; ``K, T, L`` minimise the weighted complex error
  ``sum_i |K e^{-jw_i L} / (1 + jw_i T) - G_i|^2 / s_i^2`` (real and imaginary parts stacked),
  ``s_i`` the harmonic's standard error floored at 2 % of ``|G_i|`` (hysteresis and other
  model error, not noise, dominate a real rig). Standard errors: ``(J^T J)^-1`` at the optimum
  scaled by the reduced chi-square ``chi2 / (2n - 3)``, so a model that does not fit says so
  in its uncertainties. PAMInertial fitted ``k / (1 + jTw)`` to one harmonic and read the delay off
  a plot; with two or more frequencies the three parameters are identified together.
* **Step / ramp response** (:func:`fit_time_response`): the fallback for records that are not
  sinusoidal (an inflation ramp, a step). The output is simulated as
  ``y0 + K (x(t) - u(0))``, ``T dx/dt = u(t - L) - x`` with ``x(0) = u(0)``, the delayed input
  interpolated linearly between samples, and ``K, T, L, y0`` are fitted by nonlinear least
  squares (one offset per record when several share one model). Residuals of a time fit are
  correlated, so the Jacobian's standard errors are inflated by ``sqrt((1 + r) / (1 - r))``,
  ``r`` the lag-1 autocorrelation of the residuals (the AR(1) effective-sample-size correction).

Units: ``gain`` in output units per input unit, ``time_constant_s`` and ``dead_time_s`` in s.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares
from scipy.signal import lfilter

from edge.errors import DataError
from host.data import Measurement
from host.identify.harmonics import Harmonic, harmonics_of
from host.identify.threads import blas_threads

Method = Literal["auto", "harmonic", "time"]
RELATIVE_ERROR_FLOOR = 0.02
MAX_TIME_CONSTANT_S = 1e3


@dataclass
class FOTDFit:
    """``K e^{-sL} / (1 + sT)`` and how it was found.

    Attributes:
        gain: static gain K (output units per input unit); ``gain_se`` its standard error.
        time_constant_s: T [s]; ``time_constant_se_s`` its standard error.
        dead_time_s: L [s]; ``dead_time_se_s`` its standard error.
        method: ``harmonic`` (frequency response) or ``time`` (step / ramp response).
        rms_error: RMS misfit (of ``G`` for harmonic fits, of ``y`` for time fits).
        harmonics: the frequency-response points used (harmonic fits only).
        notes: what the fit could not identify or assumed.
        hysteresis_loss_angle_rad: the rate-independent loss angle ``delta_h`` [rad] when it was
            fitted (see :func:`fit_frequency_response`), with its standard error.
    """

    gain: float
    time_constant_s: float
    dead_time_s: float
    gain_se: float
    time_constant_se_s: float
    dead_time_se_s: float
    method: str
    rms_error: float
    harmonics: list[Harmonic] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    hysteresis_loss_angle_rad: float | None = None
    hysteresis_loss_angle_se_rad: float | None = None

    def response(self, frequency_hz: NDArray[np.float64] | float) -> NDArray[np.complex128]:
        """The model's ``G(j 2 pi f)``, the hysteresis loss angle included when fitted."""
        omega = 2 * np.pi * np.asarray(frequency_hz, float)
        rotation = np.exp(-1j * (self.hysteresis_loss_angle_rad or 0.0))
        return np.asarray(
            fotd_response(omega, self.gain, self.time_constant_s, self.dead_time_s) * rotation, np.complex128
        )

    def as_dict(self) -> dict[str, object]:
        """The JSON form printed by ``pmactl identify fotd --json``."""
        return {
            "method": self.method,
            "gain": self.gain,
            "gain_se": self.gain_se,
            "time_constant_s": self.time_constant_s,
            "time_constant_se_s": self.time_constant_se_s,
            "dead_time_s": self.dead_time_s,
            "dead_time_se_s": self.dead_time_se_s,
            "hysteresis_loss_angle_rad": self.hysteresis_loss_angle_rad,
            "hysteresis_loss_angle_se_rad": self.hysteresis_loss_angle_se_rad,
            "rms_error": self.rms_error,
            "harmonics": [
                {
                    "frequency_hz": h.frequency_hz,
                    "amplitude_ratio": h.gain,
                    "amplitude_ratio_se": h.gain_se,
                    "phase_rad": h.phase_rad,
                    "phase_se_rad": h.phase_se_rad,
                    "loss_angle_rad": h.loss_angle_rad,
                    "input_amplitude": h.input_amplitude,
                    "output_amplitude": h.output_amplitude,
                    "output_mean": h.output_mean,
                    "distortion": h.distortion,
                    "periods": h.periods,
                    "model_amplitude_ratio": float(abs(self.response(h.frequency_hz))),
                    "model_phase_rad": float(np.angle(self.response(h.frequency_hz))),
                }
                for h in self.harmonics
            ],
            "notes": list(self.notes),
        }


def fotd_response(
    omega: NDArray[np.float64], gain: float, time_constant_s: float, dead_time_s: float
) -> NDArray[np.complex128]:
    """``K e^{-j w L} / (1 + j w T)`` at angular frequencies ``omega`` [rad/s]."""
    return np.asarray(gain * np.exp(-1j * omega * dead_time_s) / (1.0 + 1j * omega * time_constant_s), np.complex128)


def _standard_errors(jacobian: NDArray[np.float64], scale: float) -> NDArray[np.float64]:
    covariance = np.linalg.pinv(jacobian.T @ jacobian) * scale
    return np.asarray(np.sqrt(np.clip(np.diag(covariance), 0.0, None)), dtype=np.float64)


FREQUENCY_TOLERANCE = 0.02  # relative: two runs "at 0.5 Hz" are estimated a few 0.01 % apart


def distinct_frequencies(harmonics: list[Harmonic]) -> list[float]:
    """The different frequencies [Hz] among ``harmonics``: ones within :data:`FREQUENCY_TOLERANCE`
    of the previous (sorted) count once, so two runs at the same frequency are one point."""
    groups: list[float] = []
    for frequency in sorted(h.frequency_hz for h in harmonics):
        if not groups or frequency > groups[-1] * (1.0 + FREQUENCY_TOLERANCE):
            groups.append(frequency)
    return groups


def fit_frequency_response(harmonics: list[Harmonic], hysteresis_phase: bool = True) -> FOTDFit:
    """Weighted nonlinear least squares of ``K, T, L`` on measured ``G(jw)`` (module docstring).

    With ``hysteresis_phase`` the model is ``K e^{-j delta_h} e^{-jwL} / (1 + jwT)``: PAMInertial's
    equivalent elliptic hysteresis as a loss angle ``delta_h`` (0..90 degrees) that does not depend
    on the frequency, since rate-independent hysteresis lags the output by the same angle at
    every rate. Without it a hysteretic plant's phase at low frequency is blamed on T and L.
    """
    frequencies = distinct_frequencies(harmonics)
    # two real equations per frequency; at least one degree of freedom left for the standard errors
    parameters = 4 if hysteresis_phase else 3
    needed = parameters // 2 + 1
    if len(frequencies) < needed:
        loss = (
            " and the hysteresis loss angle need at least 3 (or pass --no-hysteresis-phase for 2)"
            if hysteresis_phase and len(frequencies) == 2
            else f" need at least {needed} frequencies"
        )
        raise DataError(
            f"found sinusoids at {len(frequencies)} distinct frequency/ies "
            f"({', '.join(f'{f:g} Hz' for f in frequencies) or 'none'}; runs within "
            f"{FREQUENCY_TOLERANCE:.0%} of each other count once); K, T and L{loss}: record a stepped sine "
            "(pmactl hil record --scenario stepped-sine), pass one run per frequency, or use --method time"
        )
    omega = np.array([2 * np.pi * h.frequency_hz for h in harmonics])
    measured = np.array([h.response for h in harmonics])
    noise = np.array([np.hypot(h.gain_se, h.gain * h.phase_se_rad) / np.sqrt(2.0) for h in harmonics])
    sigma = np.maximum(noise, RELATIVE_ERROR_FLOOR * np.abs(measured))
    lowest = int(np.argmin(omega))
    sign = 1.0 if abs(np.angle(measured[lowest])) < np.pi / 2 else -1.0
    extra = 1 if hysteresis_phase else 0

    def model(theta: NDArray[np.float64]) -> NDArray[np.complex128]:
        rotation = np.exp(-1j * theta[3]) if hysteresis_phase else 1.0
        return fotd_response(omega, theta[0], theta[1], theta[2]) * rotation

    def residuals(theta: NDArray[np.float64]) -> NDArray[np.float64]:
        error = (model(theta) - measured) / sigma
        return np.concatenate([error.real, error.imag])

    k_bounds = (0.0, np.inf) if sign > 0 else (-np.inf, 0.0)
    lower = np.array([k_bounds[0], 0.0, 0.0, 0.0][: 3 + extra])
    upper = np.array([k_bounds[1], MAX_TIME_CONSTANT_S, 10.0 / omega.min(), np.pi / 2][: 3 + extra])
    best = None
    k0 = sign * float(np.abs(measured[lowest]))
    for t0 in np.geomspace(0.2, 20.0, 5) / omega.max():
        for l0 in (0.0, 0.3, 1.0, 3.0):
            start = np.array([k0 * np.hypot(1.0, omega[lowest] * t0), t0, l0 / omega.max(), 0.1][: 3 + extra])
            start = np.clip(start, lower, np.where(np.isfinite(upper), upper * 0.99, upper))
            result = least_squares(residuals, start, bounds=(lower, upper), x_scale="jac")
            if best is None or result.cost < best.cost:
                best = result
    assert best is not None
    dof = 2 * omega.size - best.x.size
    chi2 = 2.0 * best.cost
    reduced = chi2 / dof if dof > 0 else float("nan")
    se = _standard_errors(best.jac, max(reduced, 1.0) if dof > 0 else 1.0)
    K, T, L = (float(v) for v in best.x[:3])
    notes = []
    if dof <= 0:
        notes.append("as many parameters as data: no degrees of freedom left, standard errors are not scaled")
    elif reduced > 4.0:
        notes.append(
            f"reduced chi-square {reduced:.1f}: the model does not explain the frequency response within its "
            "errors (standard errors are scaled up by it)"
        )
    return FOTDFit(
        gain=K,
        time_constant_s=T,
        dead_time_s=L,
        gain_se=float(se[0]),
        time_constant_se_s=float(se[1]),
        dead_time_se_s=float(se[2]),
        method="harmonic",
        rms_error=float(np.sqrt(np.mean(np.abs(model(best.x) - measured) ** 2))),
        harmonics=sorted(harmonics, key=lambda h: h.frequency_hz),
        notes=notes,
        hysteresis_loss_angle_rad=float(best.x[3]) if hysteresis_phase else None,
        hysteresis_loss_angle_se_rad=float(se[3]) if hysteresis_phase else None,
    )


def simulate_fotd(
    t: NDArray[np.float64], u: NDArray[np.float64], gain: float, time_constant_s: float, dead_time_s: float
) -> NDArray[np.float64]:
    """``K (x(t) - u(0))`` for ``T dx/dt = u(t - L) - x``, ``x(0) = u(0)`` (input held at ``u(0)`` before ``t0``).

    The delayed input is interpolated linearly; the lag is discretised exactly for an input
    that is constant at the mean of each step's end points (second-order accurate).
    """
    delayed = np.interp(t - dead_time_s, t, u, left=u[0])
    dt = float(np.median(np.diff(t)))
    if time_constant_s <= 1e-9:
        state = delayed
    else:
        a = np.exp(-dt / time_constant_s)
        drive = np.concatenate([[delayed[0]], 0.5 * (delayed[1:] + delayed[:-1])]) - u[0]
        state = lfilter([1.0 - a], [1.0, -a], drive, zi=[a * 0.0])[0] + u[0]
    return np.asarray(gain * (state - u[0]), dtype=np.float64)


def fit_time_response(records: list[Measurement]) -> FOTDFit:
    """Fit ``K, T, L`` (shared) and one output offset per record to step / ramp responses."""
    if not records:
        raise DataError("no records given; pass at least one CSV with t, u, y")
    for m in records:
        if float(np.ptp(m.u)) <= 0.0:
            raise DataError(f"{m.source}: the input u never changes; a step or ramp response needs u to move")
    span = min(float(m.t[-1] - m.t[0]) for m in records)
    dt = max(m.dt for m in records)
    count = len(records)

    def residuals(theta: NDArray[np.float64]) -> NDArray[np.float64]:
        K, T, L = theta[:3]
        return np.concatenate([simulate_fotd(m.t, m.u, K, T, L) + theta[3 + i] - m.y for i, m in enumerate(records)])

    slope = np.polyfit(np.concatenate([m.u for m in records]), np.concatenate([m.y for m in records]), 1)[0]
    lower = [-np.inf, 0.0, 0.0] + [-np.inf] * count
    upper = [np.inf, 10.0 * span, 0.5 * span] + [np.inf] * count
    best = None
    for t0 in np.geomspace(2 * dt, 0.3 * span, 4):
        for l0 in (0.0, 2 * dt, 0.05 * span):
            start = [float(slope), t0, l0] + [float(m.y[0]) for m in records]
            result = least_squares(residuals, start, bounds=(lower, upper), x_scale="jac")
            if best is None or result.cost < best.cost:
                best = result
    assert best is not None
    r = best.fun
    n = r.size
    rho = float(np.clip(np.corrcoef(r[:-1], r[1:])[0, 1], 0.0, 0.99)) if n > 3 else 0.0
    scale = 2.0 * best.cost / max(n - best.x.size, 1) * (1 + rho) / (1 - rho)
    se = _standard_errors(best.jac, scale)
    K, T, L = (float(v) for v in best.x[:3])
    notes = [
        f"time-domain fit on {count} record(s): standard errors corrected for residual autocorrelation "
        f"(lag-1 {rho:.2f})"
    ]
    T, L = (value if value > 1e-9 else 0.0 for value in (T, L))
    unresolved = [f"{name} = {value:.3g} s" for name, value in (("T", T), ("L", L)) if value < 2 * dt]
    if unresolved:
        notes.append(
            f"{' and '.join(unresolved)} below two sample periods ({2 * dt:.3g} s): the data cannot resolve "
            "them; read them as upper bounds"
        )
    return FOTDFit(
        K, T, L, float(se[0]), float(se[1]), float(se[2]), "time", float(np.sqrt(np.mean(r**2))), notes=notes
    )


def identify_fotd(records: list[Measurement], method: Method = "auto", hysteresis_phase: bool = True) -> FOTDFit:
    """``K, T, L`` from one or more records: by harmonics when they hold sinusoids at >= 2
    frequencies, else (``auto``) from the time response."""
    if not records:
        raise DataError("no records given; pass at least one CSV with t, u, y")
    # small least-squares problems: one BLAS thread unless they are large (host.identify.threads)
    with blas_threads(sum(len(m) for m in records) * 64.0):
        if method == "time":
            return fit_time_response(records)
        found: list[Harmonic] = []
        for m in records:
            found += harmonics_of(m.t, m.u, m.y, m.source)
        distinct = distinct_frequencies(found)
        if method == "auto" and len(distinct) < 2:
            fit = fit_time_response(records)
            fit.notes.insert(
                0,
                f"no stepped sine found (steady sinusoids at {len(distinct)} distinct frequency/ies, K, T, L need "
                "2); fell back to the step / ramp response fit",
            )
            return fit
        if method == "auto" and hysteresis_phase and len(distinct) == 2:
            fit = fit_frequency_response(found, hysteresis_phase=False)
            fit.notes.insert(0, "2 distinct frequencies: K, T, L fitted without the hysteresis loss angle (needs 3)")
            return fit
        return fit_frequency_response(found, hysteresis_phase)
