"""A plant that is not our emulator, for the diagnosis: a rate-dependent Prandtl-Ishlinskii model.

Play operators whose thresholds widen with the input rate, ``r_i (1 + c (|du/dt| / rate95)^p)``
(the modified rate-dependent PI of Ang et al.), then a 30 ms first-order output lag and sensor
noise. Variants: ``none`` (fixed thresholds), ``rate`` (widening thresholds), ``delay`` (fixed
thresholds, the input delayed). Driven by the mixed protocol at 100 Hz; it starts at rest, every
play on its descending branch, as a vented muscle does.
"""

from __future__ import annotations

import numpy as np

from hil.scenarios import mixed
from host.data import Measurement
from host.diagnose.features import first_order, smoothed_rate

DT_S = 0.01
THRESHOLDS_BAR = np.linspace(0.0, 1.8, 10)
WEIGHTS_MM_PER_BAR = 4.0 * np.exp(-THRESHOLDS_BAR)


def rate_dependent_pi(
    kind: str, seed: int, *, widening: float = 1.0, power: float = 1.0, delay_s: float = 0.12
) -> Measurement:
    rng = np.random.default_rng(seed)
    u = mixed(300.0, 0.001, rng)[::10]
    rate = np.abs(smoothed_rate(u, DT_S))
    relative = rate / np.percentile(rate, 95)
    scale = 1.0 + widening * relative**power if kind == "rate" else np.ones_like(u)
    steps = int(round(delay_s / DT_S)) if kind == "delay" else 0
    drive = np.concatenate([np.full(steps, u[0]), u[: u.size - steps]])
    z = drive[0] + THRESHOLDS_BAR
    y = np.empty_like(u)
    for k in range(u.size):
        r = THRESHOLDS_BAR * scale[k]
        z = np.clip(z, drive[k] - r, drive[k] + r)
        y[k] = WEIGHTS_MM_PER_BAR @ z
    y = first_order(y, DT_S, 0.03) + rng.normal(0.0, 0.02, y.size)
    return Measurement(np.arange(u.size) * DT_S, u, y, source=f"rate-dependent PI plant ({kind}, seed {seed})")
