"""Residual diagnostics of the baseline: where and when the simulation is wrong.

Each function takes the baseline residual (simulated - measured) and returns plain numbers
for the JSON and the report; none of them decides anything.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.stats import chi2


def correlation(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Pearson correlation, 0 when either side is constant."""
    if np.ptp(a) == 0 or np.ptp(b) == 0:
        return 0.0
    return float(np.corrcoef(a, b)[0, 1])


def ljung_box(residual: NDArray[np.float64], lags: int = 20) -> dict[str, float]:
    """Whiteness test: Q statistic and p-value (small p: the residual still has structure)."""
    r = residual - residual.mean()
    denominator = float(r @ r) or 1.0
    n = r.size
    acf = np.array([float(r[k:] @ r[:-k]) / denominator for k in range(1, lags + 1)])
    q = float(n * (n + 2) * np.sum(acf**2 / (n - np.arange(1, lags + 1))))
    return {"q": q, "lags": lags, "p_value": float(chi2.sf(q, lags))}


def rate_lag(
    residual: NDArray[np.float64], rate: NDArray[np.float64], dt: float, max_lag_s: float = 1.0
) -> dict[str, float]:
    """Lag [s] at which the input rate best explains the residual (positive: residual later)."""
    max_lag = max(1, min(int(max_lag_s / dt), residual.size // 4))
    r = (residual - residual.mean()) / (residual.std() or 1.0)
    v = (rate - rate.mean()) / (rate.std() or 1.0)
    values = [float(np.mean(r[k:] * v[: v.size - k])) for k in range(0, max_lag)]
    best = int(np.argmax(np.abs(values)))
    return {"lag_s": best * dt, "correlation": values[best]}


def hold_drift(
    residual: NDArray[np.float64], rate: NDArray[np.float64], dt: float, min_hold_s: float = 5.0
) -> dict[str, float]:
    """Mean |slope| of the residual [units/s] during holds (input still for >= ``min_hold_s``)."""
    still = np.abs(rate) < 0.002 * (np.percentile(np.abs(rate), 95) or 1.0) + 1e-12
    slopes, start = [], None
    for i, flag in enumerate(np.append(still, False)):
        if flag and start is None:
            start = i
        elif not flag and start is not None:
            if (i - start) * dt >= min_hold_s:
                segment = residual[start + int(1.0 / dt) : i]  # skip the first second
                if segment.size > 10:
                    slopes.append(abs(np.polyfit(np.arange(segment.size) * dt, segment, 1)[0]))
            start = None
    return {"holds": len(slopes), "mean_abs_slope_per_s": float(np.mean(slopes)) if slopes else 0.0}


def per_loop_rmse(residual: NDArray[np.float64], u: NDArray[np.float64]) -> list[float]:
    """RMSE of the residual between consecutive input maxima (one loop each)."""
    moving = np.flatnonzero(np.diff(u) != 0)
    if moving.size < 3:
        return []
    direction = np.sign(np.diff(u)[moving])
    peaks = moving[np.flatnonzero((direction[:-1] > 0) & (direction[1:] < 0)) + 1]
    bounds = np.r_[0, peaks, u.size]
    return [float(np.sqrt(np.mean(residual[a:b] ** 2))) for a, b in zip(bounds[:-1], bounds[1:]) if b - a > 5]


def baseline_evidence(
    residual: NDArray[np.float64],
    u: NDArray[np.float64],
    rate: NDArray[np.float64],
    extras: dict[str, NDArray[np.float64]],
    dt: float,
) -> dict[str, object]:
    """Every diagnostic, as plain numbers."""
    loops = per_loop_rmse(residual, u)
    return {
        "residual_rmse": float(np.sqrt(np.mean(residual**2))),
        "whiteness": ljung_box(residual),
        "correlation_with_abs_rate": correlation(np.abs(residual), np.abs(rate)),
        "rate_lag": rate_lag(residual, rate, dt),
        "hold_drift": hold_drift(residual, rate, dt),
        "correlation_with_load": correlation(residual, extras["load"]) if "load" in extras else None,
        "correlation_with_temperature": (
            correlation(residual, extras["temperature"]) if "temperature" in extras else None
        ),
        "loops": len(loops),
        "worst_loop_rmse": max(loops) if loops else None,
        "residual_first_vs_last_quarter": [
            float(np.sqrt(np.mean(residual[: residual.size // 4] ** 2))),
            float(np.sqrt(np.mean(residual[-residual.size // 4 :] ** 2))),
        ],
    }
