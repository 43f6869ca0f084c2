"""First harmonics of sinusoidal test segments, by least-squares Fourier fit (PAMInertial sec 4).

A record of sinusoids (one frequency, or several one after another: a stepped sine) is cut into
segments of nearly equal input periods, found from the input's upward crossings of its median
(with a Schmitt band so noise cannot make extra crossings). In every segment the first period
is left out (transient, unknown memory) and the rest, a whole number of periods, is fitted by
linear least squares to ``c0 + c1 t + sum_{h=1..3} a_h cos(h w t) + b_h sin(h w t)``: the first
harmonic does not leak into the others or into the mean when the window is not a whole number
of periods (it is, up to sampling, but the fit does not rely on it), a slow drift goes to the
trend, and the residual gives the harmonics' standard errors.

The complex amplitude of ``a cos(wt) + b sin(wt)`` is ``X = a - j b`` (``x = Re{X e^{jwt}}``), and
the frequency response is ``G(jw) = Y / U`` with its standard error by the delta method.

The equivalent elliptic hysteresis (PAMInertial eq 4, equality of the losses, sec 3.1): the loop of
``y`` against ``u`` over the whole periods encloses an area ``A``; the ellipse of the two first
harmonics with the same area has ``sin(delta) = A / (pi U Y)`` (``U``, ``Y`` amplitudes), and
``delta`` is the loss angle. For a pure sinusoidal input it equals the first-harmonic phase lag
folded into [-90, 90] degrees.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError

HARMONICS = 3


@dataclass(frozen=True)
class Harmonic:
    """The first harmonic of one sinusoidal segment.

    Attributes:
        frequency_hz: excitation frequency [Hz], from the input's period.
        start_s, stop_s: the analysed window [s] (whole periods).
        periods: periods in the window.
        input_amplitude, output_amplitude: first-harmonic amplitudes (units of u and y).
        input_mean, output_mean: the continuous components (PAMInertial Table 1, first row).
        gain: ``|G(jw)| = Y/U`` (units of y per unit of u); ``gain_se`` its standard error.
        phase_rad: ``arg G(jw)`` in (-pi, pi]; negative is a lag; ``phase_se_rad`` its standard error.
        loss_angle_rad: equivalent elliptic loss angle (module docstring) [rad].
        distortion: RMS of the output's 2nd and 3rd harmonics relative to its first.
    """

    frequency_hz: float
    start_s: float
    stop_s: float
    periods: int
    input_amplitude: float
    output_amplitude: float
    input_mean: float
    output_mean: float
    gain: float
    gain_se: float
    phase_rad: float
    phase_se_rad: float
    loss_angle_rad: float
    distortion: float

    @property
    def response(self) -> complex:
        """``G(jw)`` as a complex number."""
        return complex(self.gain * np.exp(1j * self.phase_rad))

    def as_dict(self) -> dict[str, float | int]:
        return asdict(self)


def upward_crossings(t: NDArray[np.float64], u: NDArray[np.float64], band: float = 0.25) -> NDArray[np.float64]:
    """Times [s] where ``u`` rises through its median, interpolated between samples.

    A crossing counts only after ``u`` has been below ``median - band * std`` and rises above
    ``median + band * std`` (a Schmitt trigger), so noise near the median is ignored.
    """
    centre = float(np.median(u))
    half = band * float(np.std(u))
    times: list[float] = []
    armed = False
    below_since = 0
    for i in range(u.size):
        if u[i] < centre - half:
            armed = True
            below_since = i
        elif armed and u[i] > centre + half:
            j = below_since
            while j < i and u[j + 1] < centre:
                j += 1
            a, b = u[j] - centre, u[j + 1] - centre
            times.append(float(t[j] + (t[j + 1] - t[j]) * (-a / (b - a) if b != a else 0.0)))
            armed = False
    return np.asarray(times)


def sinusoidal_segments(
    t: NDArray[np.float64], u: NDArray[np.float64], tolerance: float = 0.08, min_periods: int = 2
) -> list[tuple[float, float, int]]:
    """``(start_s, stop_s, periods)`` of each run of nearly equal input periods, first period dropped.

    Consecutive periods belong to one segment while each is within ``tolerance`` of the segment's
    first; a segment needs ``min_periods`` periods (the first is dropped to settle).
    """
    crossings = upward_crossings(t, u)
    if crossings.size < 2:
        return []
    periods = np.diff(crossings)
    segments: list[tuple[float, float, int]] = []
    start = 0
    for i in range(1, periods.size + 1):
        if i == periods.size or abs(periods[i] - periods[start]) > tolerance * periods[start]:
            count = i - start
            if count >= min_periods:
                segments.append((float(crossings[start + 1]), float(crossings[i]), count - 1))
            start = i
    return segments


def _fourier_design(t: NDArray[np.float64], omega: float) -> NDArray[np.float64]:
    tc = t - t.mean()
    columns = [np.ones_like(t), tc / max(float(np.ptp(t)), 1e-12)]
    for h in range(1, HARMONICS + 1):
        columns += [np.cos(h * omega * t), np.sin(h * omega * t)]
    return np.column_stack(columns)


def fourier_fit(
    t: NDArray[np.float64], x: NDArray[np.float64], omega: float
) -> tuple[complex, NDArray[np.float64], float, float, float]:
    """Least-squares Fourier fit of ``x(t)`` at ``omega`` [rad/s].

    Returns the first-harmonic complex amplitude ``X = a - j b``, the 2x2 covariance of
    ``(Re X, Im X)``, the mean, and the RMS of the 2nd and 3rd harmonics relative to ``|X|``,
    and the residual RMS.
    """
    design = _fourier_design(t, omega)
    coef, *_ = np.linalg.lstsq(design, x, rcond=None)
    residual = x - design @ coef
    dof = max(x.size - design.shape[1], 1)
    sigma2 = float(residual @ residual) / dof
    cov_full = sigma2 * np.linalg.pinv(design.T @ design)
    a, b = coef[2], coef[3]
    # (Re X, Im X) = (a, -b)
    jac = np.array([[1.0, 0.0], [0.0, -1.0]])
    cov = jac @ cov_full[2:4, 2:4] @ jac.T
    amplitude = float(np.hypot(a, b))
    higher = float(np.sqrt(np.sum(coef[4:] ** 2) / 2.0)) / amplitude if amplitude > 0 else float("nan")
    return complex(a, -b), cov, float(coef[0]), higher, float(np.sqrt(sigma2))


def _loss_angle(u: NDArray[np.float64], y: NDArray[np.float64], u_amp: float, y_amp: float, periods: int) -> float:
    """Equivalent elliptic loss angle from the mean loop area per period (positive when y lags u)."""
    # -(closed integral of y du) per period: > 0 for a lag (pi U Y sin(delta) for an ellipse)
    area = -float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(u))) / periods
    ratio = area / (np.pi * u_amp * y_amp) if u_amp > 0 and y_amp > 0 else 0.0
    return float(np.arcsin(np.clip(ratio, -1.0, 1.0)))


def harmonic(
    t: NDArray[np.float64], u: NDArray[np.float64], y: NDArray[np.float64], start_s: float, stop_s: float, periods: int
) -> Harmonic:
    """The first harmonic of ``u`` and ``y`` on ``[start_s, stop_s)`` (``periods`` whole periods)."""
    window = (t >= start_s) & (t < stop_s)
    tw, uw, yw = t[window], u[window], y[window]
    if tw.size < 4 * (2 + 2 * HARMONICS):
        raise DataError(
            f"segment {start_s:.3g}-{stop_s:.3g} s has only {tw.size} samples; sample faster than "
            f"{8 * periods / (stop_s - start_s):.3g} Hz or record more periods"
        )
    omega = 2 * np.pi * periods / (stop_s - start_s)
    U, cov_u, u_mean, _, _ = fourier_fit(tw, uw, omega)
    Y, cov_y, y_mean, distortion, _ = fourier_fit(tw, yw, omega)
    G = Y / U

    # delta method: dG/dY = 1/U, dG/dU = -G/U, written on (Re, Im) pairs as 2x2 real matrices
    def as_matrix(z: complex) -> NDArray[np.float64]:
        return np.array([[z.real, -z.imag], [z.imag, z.real]])

    cov_g = as_matrix(1 / U) @ cov_y @ as_matrix(1 / U).T + as_matrix(-G / U) @ cov_u @ as_matrix(-G / U).T
    gain, phase = abs(G), float(np.angle(G))
    d_gain = np.array([G.real, G.imag]) / gain
    d_phase = np.array([-G.imag, G.real]) / gain**2
    return Harmonic(
        frequency_hz=omega / (2 * np.pi),
        start_s=float(tw[0]),
        stop_s=float(tw[-1]),
        periods=periods,
        input_amplitude=abs(U),
        output_amplitude=abs(Y),
        input_mean=u_mean,
        output_mean=y_mean,
        gain=gain,
        gain_se=float(np.sqrt(max(float(d_gain @ cov_g @ d_gain), 0.0))),
        phase_rad=phase,
        phase_se_rad=float(np.sqrt(max(float(d_phase @ cov_g @ d_phase), 0.0))),
        loss_angle_rad=_loss_angle(uw, yw, abs(U), abs(Y), periods),
        distortion=distortion,
    )


def harmonics_of(
    t: NDArray[np.float64], u: NDArray[np.float64], y: NDArray[np.float64], source: str = "record"
) -> list[Harmonic]:
    """The first harmonic of every sinusoidal segment of a record, in time order."""
    return [harmonic(t, u, y, *segment) for segment in sinusoidal_segments(t, u)]
