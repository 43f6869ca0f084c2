"""The example data shipped with pmactl, and the script that made it.

Until the HIL emulator exists, the example recordings come from this small quasi-static
muscle simulation, which is deliberately *not* one of the identification models: a Festo
DMSP-20-400N-like McKibben muscle (Tondu-Lopez static force, seed 004 eq 1) pulling against a
spring-and-mass load, with braid/bladder friction as Maxwell-slip elements (seed 004 sec 2.3),
16-bit sensor quantisation and sensor noise. Input ``u``: muscle pressure [bar];
output ``y``: contraction [mm]. Regenerate with ``python -m host.examples [OUT_DIR]``.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass
from importlib import resources
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import brentq

EXAMPLES = {"train": "pma_triangles.csv", "test": "pma_mixed.csv"}


def example_path(role: str) -> Path:
    """Path of a shipped example recording: ``role`` is ``"train"`` or ``"test"``."""
    return Path(str(resources.files("host") / "example_data" / EXAMPLES[role]))


@dataclass(frozen=True)
class MuscleRig:
    """Quasi-static muscle + load parameters (SI units)."""

    rest_length_m: float = 0.400
    radius_m: float = 0.010
    a: float = 16.7  # 3 / tan^2(alpha0), alpha0 ~ 23 deg
    b: float = 6.55  # 1 / sin^2(alpha0)
    k: float = 1.5  # braid shortening factor: max contraction ~25 %
    load_kg: float = 3.5
    spring_n_per_m: float = 6700.0
    slip_stiffness_n_per_m: tuple[float, ...] = (40e3, 25e3, 15e3, 10e3, 6e3, 4e3)
    slip_break_force_n: tuple[float, ...] = (4.0, 5.0, 6.0, 6.0, 5.0, 4.0)

    def muscle_force_n(self, pressure_bar: float, contraction_m: float) -> float:
        """Tondu-Lopez: F = pi r0^2 p [a (1 - k eps)^2 - b]."""
        eps = contraction_m / self.rest_length_m
        return np.pi * self.radius_m**2 * pressure_bar * 1e5 * (self.a * (1 - self.k * eps) ** 2 - self.b)


def simulate_rig(pressure_bar: NDArray[np.float64], rig: MuscleRig = MuscleRig()) -> NDArray[np.float64]:
    """Contraction [m] for a pressure sequence, balancing forces at every sample."""
    stiffness = np.array(rig.slip_stiffness_n_per_m)
    limit = np.array(rig.slip_break_force_n) / stiffness  # max elastic stretch of each element
    stretch = np.zeros_like(stiffness)
    x_prev = 0.0
    out = np.empty_like(pressure_bar)
    weight = rig.load_kg * 9.81

    def imbalance(x: float, p: float) -> float:
        friction = float(stiffness @ np.clip(stretch + (x - x_prev), -limit, limit))
        return rig.muscle_force_n(p, x) - weight - rig.spring_n_per_m * x - friction

    for i, p in enumerate(pressure_bar.tolist()):
        lo, hi = -0.05, 0.3 * rig.rest_length_m
        x = brentq(imbalance, lo, hi, args=(p,), xtol=1e-9) if imbalance(lo, p) > 0 else lo
        stretch = np.clip(stretch + (x - x_prev), -limit, limit)
        x_prev = out[i] = x
    return out


def triangle_protocol(rate_hz: float = 100.0) -> NDArray[np.float64]:
    """Seed 000: triangles 0 -> 1, 2, 3, 4 bar at 0.05 Hz (20 s each)."""
    t = np.arange(0, 20.0, 1.0 / rate_hz)
    tri = 1.0 - np.abs(2.0 * (t / 20.0) - 1.0)
    return np.concatenate([peak * tri for peak in (1.0, 2.0, 3.0, 4.0)])


def mixed_protocol(rate_hz: float = 100.0) -> NDArray[np.float64]:
    """A slow sine with a faster one on top (minor loops), 60 s, within 0.2..3.9 bar."""
    t = np.arange(0, 60.0, 1.0 / rate_hz)
    slow = 2.0 + 1.4 * np.sin(2 * np.pi * 0.04 * t - np.pi / 2)
    return np.clip(slow + 0.45 * np.sin(2 * np.pi * 0.23 * t), 0.2, 3.9)


def quantise(values: NDArray[np.float64], full_scale: float, bits: int = 16) -> NDArray[np.float64]:
    """Round to the resolution of a ``bits`` ADC spanning ``0..full_scale``."""
    lsb = full_scale / 2**bits
    return np.round(values / lsb) * lsb


def make_recording(pressure_bar: NDArray[np.float64], seed: int, rate_hz: float = 100.0) -> str:
    """CSV text ``t,u,y`` (s, bar, mm) with sensor noise and 16-bit quantisation."""
    rng = np.random.default_rng(seed)
    contraction_mm = simulate_rig(pressure_bar) * 1e3
    u = quantise(pressure_bar + rng.normal(0, 0.004, pressure_bar.size), 10.0)
    y = quantise(contraction_mm + rng.normal(0, 0.03, pressure_bar.size), 150.0)
    t = np.arange(pressure_bar.size) / rate_hz
    rows = "\n".join(f"{ti:.3f},{ui:.5f},{yi:.4f}" for ti, ui, yi in zip(t, u, y))
    return "t,u,y\n" + rows + "\n"


def main(argv: list[str] | None = None) -> int:
    """Write the example recordings to ``argv[0]`` (default: the package's example_data)."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else example_path("train").parent
    out.mkdir(parents=True, exist_ok=True)
    (out / EXAMPLES["train"]).write_text(make_recording(triangle_protocol(), seed=1))
    (out / EXAMPLES["test"]).write_text(make_recording(mixed_protocol(), seed=2))
    print(f"wrote {out / EXAMPLES['train']} and {out / EXAMPLES['test']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
