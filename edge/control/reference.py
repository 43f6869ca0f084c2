"""Desired trajectories y_ref(t) [mm] from a short text spec (``pmactl edge run --reference``).

* ``sine:amplitude=30,frequency=0.2,offset=40`` (mm, Hz, mm; Ai2019 eq 18 / Table 4 by default)
* ``ramp-sine:peak=30,frequency=1,offset=40,rise=10,hold=1``: Zhou2022 eq 33, a sine whose
  amplitude rises linearly to ``peak`` over ``rise`` s, holds for ``hold`` s, falls back to 0
* ``const:value=40``
* ``csv:PATH`` or a path ending in ``.csv``: columns ``t`` [s] and ``y_ref`` [mm], linearly
  interpolated, the last value held
"""

from __future__ import annotations

import bisect
import csv
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from edge.errors import DataError

DEFAULTS: dict[str, dict[str, float]] = {
    "sine": {"amplitude": 30.0, "frequency": 0.2, "offset": 40.0},
    "ramp-sine": {"peak": 30.0, "frequency": 1.0, "offset": 40.0, "rise": 10.0, "hold": 1.0},
    "const": {"value": 40.0},
}


@dataclass(frozen=True)
class Reference:
    """A trajectory and its natural length [s] (None: endless)."""

    spec: str
    function: Callable[[float], float]
    duration_s: float | None

    def __call__(self, t: float) -> float:
        return self.function(t)


def _parameters(kind: str, text: str, spec: str) -> dict[str, float]:
    values = dict(DEFAULTS[kind])
    for item in filter(None, text.split(",")):
        key, _, value = item.partition("=")
        key = key.strip()
        if key not in values:
            raise DataError(f"--reference {spec!r}: {kind} has no parameter {key!r}; it has {', '.join(values)}")
        try:
            values[key] = float(value)
        except ValueError as exc:
            raise DataError(f"--reference {spec!r}: {key}={value!r} is not a number") from exc
    return values


def sine(amplitude: float, frequency: float, offset: float) -> Callable[[float], float]:
    omega = 2 * math.pi * frequency
    return lambda t: amplitude * math.sin(omega * t) + offset


def ramp_sine(
    peak: float, frequency: float, offset: float, rise: float, hold: float
) -> tuple[Callable[[float], float], float]:
    """Zhou2022 eq 33 (there: A = 14 k Ts up to 140 um over 2000 samples of 5 ms, 200 samples
    at 140, then down): the amplitude ramps 0 -> peak over ``rise`` s, holds, ramps back."""
    omega = 2 * math.pi * frequency

    def amplitude(t: float) -> float:
        if t <= rise:
            return peak * t / rise
        if t <= rise + hold:
            return peak
        return max(0.0, peak * (2 * rise + hold - t) / rise)

    return (lambda t: amplitude(t) * math.sin(omega * t) + offset), 2 * rise + hold


def from_csv(path: Path, spec: str) -> tuple[Callable[[float], float], float]:
    """Columns ``t`` [s] and ``y_ref`` [mm], at least two rows, every value a finite number."""
    try:
        text = path.read_bytes()
    except FileNotFoundError as exc:
        raise DataError(f"--reference {spec!r}: no such file") from exc
    except IsADirectoryError as exc:
        raise DataError(f"--reference {spec!r}: is a directory; give a CSV file with columns t,y_ref") from exc
    except OSError as exc:
        raise DataError(f"--reference {spec!r}: cannot read ({exc.strerror})") from exc
    try:
        if b"\x00" in text:
            raise UnicodeDecodeError("utf-8", text, 0, 1, "NUL byte")
        rows = list(csv.DictReader(text.decode("utf-8").splitlines()))
    except (UnicodeDecodeError, csv.Error) as exc:
        raise DataError(
            f"{path}: not a text CSV ({exc.reason if isinstance(exc, UnicodeDecodeError) else exc})"
        ) from exc
    if not rows or not {"t", "y_ref"} <= set(rows[0]):
        raise DataError(f"{path}: needs columns t and y_ref (found {sorted(rows[0]) if rows else 'no rows'})")
    if len(rows) < 2:
        raise DataError(f"{path}: one row is not a trajectory; give at least two rows of t,y_ref")
    times, values = [], []
    for number, row in enumerate(rows, start=2):
        try:
            times.append(float(row["t"]))
            values.append(float(row["y_ref"]))
        except (TypeError, ValueError) as exc:
            raise DataError(
                f"{path}: line {number} has t={row.get('t')!r}, y_ref={row.get('y_ref')!r}; both must be numbers"
            ) from exc
    if any(not math.isfinite(v) for v in times + values) or any(b <= a for a, b in zip(times, times[1:])):
        raise DataError(f"{path}: t must increase strictly and every value must be finite")

    def interpolate(t: float) -> float:
        i = bisect.bisect_right(times, t)
        if i == 0:
            return values[0]
        if i == len(times):
            return values[-1]
        w = (t - times[i - 1]) / (times[i] - times[i - 1])
        return values[i - 1] + w * (values[i] - values[i - 1])

    return interpolate, times[-1]


def parse_reference(spec: str) -> Reference:
    """The trajectory named by ``spec`` (see the module docstring)."""
    kind, _, text = spec.partition(":")
    if kind == "csv" or spec.endswith(".csv"):
        path = Path(text if kind == "csv" else spec)
        function, duration = from_csv(path, spec)
        return Reference(spec, function, duration)
    if kind not in DEFAULTS:
        raise DataError(f"--reference {spec!r}: unknown kind {kind!r}; use sine:, ramp-sine:, const: or a CSV path")
    p = _parameters(kind, text, spec)
    if kind == "sine":
        return Reference(spec, sine(p["amplitude"], p["frequency"], p["offset"]), None)
    if kind == "ramp-sine":
        if p["rise"] <= 0 or p["hold"] < 0:
            raise DataError(f"--reference {spec!r}: rise must be positive and hold non-negative")
        function, duration = ramp_sine(p["peak"], p["frequency"], p["offset"], p["rise"], p["hold"])
        return Reference(spec, function, duration)
    value = p["value"]
    return Reference(spec, lambda t: value, None)


def beyond_reach(
    reference: Callable[[float], float], duration_s: float, reachable: tuple[float, float], unit: str = "mm"
) -> str | None:
    """A warning when ``reference`` leaves the bundle's reachable output range, else None.

    The feedforward (the inverse table) clamps a set-point it cannot reach to the nearest
    reachable one, so the excess is left to the PID and shows as tracking error at the peaks.
    Sampled every 10 ms over ``duration_s``. The edge checks this before arming; the demo
    (``host.demo``) uses the same function.
    """
    import numpy as np

    t = np.arange(0.0, duration_s, 0.01)
    wanted = np.array([reference(float(ti)) for ti in t])
    low, high = float(wanted.min()), float(wanted.max())
    if low >= reachable[0] - 1e-9 and high <= reachable[1] + 1e-9:
        return None
    outside = float(np.mean((wanted < reachable[0]) | (wanted > reachable[1])))
    return (
        f"the reference asks {low:.1f}..{high:.1f} {unit} but the bundle reaches only "
        f"{reachable[0]:.1f}..{reachable[1]:.1f} {unit} ({outside:.0%} of the time outside): the feedforward "
        "clips there and the PID must do the rest; lower the amplitude or offset, or fit on data that reaches further"
    )
