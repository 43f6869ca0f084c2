"""Open-loop excitation protocols for ``pmactl edge record``: the valve command u(t) that
identification needs, as a table at the loop rate.

Each named protocol is a shape in 0..1 over time, scaled onto the command range ``low..high``
(bar on a muscle; commanded angle in deg on a joint). ``NAME:key=value,...`` sets a protocol's
parameters (lists separated by ``/``); ``--duration`` repeats the protocol to fill the time (the
default is one pass). A protocol that does not start at ``low`` is led in by a ramp from ``low``
(the muscle starts vented), so no protocol asks the valve for a step it did not mean.

* ``triangles``: Ai2019: triangles 0 -> 1, 2, 3, 4 bar at 0.05 Hz on the
  default 0..4 bar range (``levels``, ``frequency`` [Hz]);
* ``forc``: Schreiber's first-order descending curves for a Preisach / Everett fit: from ``low``
  up to reversal points rising in ``curves`` equal steps to ``high``, each followed by the
  descending branch back to ``low``, at ``rate`` [range per s];
* ``sines``: whole cycles around the middle of the range at every ``frequencies`` [Hz] and
  ``amplitudes`` [share of the half range], ``cycles`` each, starting and ending at the middle;
* ``steps``: a staircase from ``low`` up and back down in ``levels`` steps, each level held
  ``hold`` [s] (dead time, creep);
* ``multisine``: a random-phase multisine, flat spectrum over the harmonics of ``period`` [s]
  up to ``fmax`` [Hz] (``seed`` picks the phases), ``periods`` of it;
* ``chirp``: a logarithmic sweep ``f0`` -> ``f1`` [Hz] over ``length`` [s], full range;
* ``FILE.csv``: the user's own ``t,<command>`` (header row; seconds and the command unit, not
  scaled), linearly interpolated.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from edge.errors import DataError

LEAD_IN_S = 2.0  # the ramp from the range's low end to a protocol's first value [s]
# the longest command table (lead-in + passes) held in memory: 2.2 h at 1 kHz, 64 MB of float64
MAX_TABLE_SAMPLES = 8_000_000
MAX_MULTISINE_WORK = 200_000_000  # samples x harmonics of one multisine period (about 2 s of CPU)

Shape = Callable[[float, dict[str, list[float]]], np.ndarray]  # (dt_s, params) -> samples in 0..1


def _corners(points: list[float], rate: float, dt: float) -> np.ndarray:
    """Piecewise-linear through ``points`` at ``rate`` [range per s], sampled every ``dt``."""
    times = np.concatenate([[0.0], np.cumsum(np.abs(np.diff(points)) / rate)])
    return np.asarray(np.interp(np.arange(int(round(times[-1] / dt))) * dt, times, points), dtype=np.float64)


def _triangles(dt: float, p: dict[str, list[float]]) -> np.ndarray:
    levels, period = int(p["levels"][0]), 1.0 / p["frequency"][0]
    t = np.arange(int(round(levels * period / dt))) * dt
    peak = (np.minimum(t // period, levels - 1) + 1.0) / levels
    return np.asarray(peak * (1.0 - np.abs(2.0 * ((t % period) / period) - 1.0)), dtype=np.float64)


def _forc(dt: float, p: dict[str, list[float]]) -> np.ndarray:
    curves = int(p["curves"][0])
    points = [0.0]
    for k in range(1, curves + 1):
        points += [k / curves, 0.0]
    return _corners(points, p["rate"][0], dt)


def _sines(dt: float, p: dict[str, list[float]]) -> np.ndarray:
    pieces = []
    for amplitude in p["amplitudes"]:
        for frequency in p["frequencies"]:
            local = np.arange(int(round(p["cycles"][0] / frequency / dt))) * dt
            pieces.append(0.5 + 0.5 * amplitude * np.sin(2 * np.pi * frequency * local))
    return np.concatenate(pieces)


def _steps(dt: float, p: dict[str, list[float]]) -> np.ndarray:
    levels = int(p["levels"][0])
    values = [k / levels for k in range(levels + 1)] + [k / levels for k in range(levels - 1, -1, -1)]
    return np.repeat(values, int(round(p["hold"][0] / dt)))


def _multisine(dt: float, p: dict[str, list[float]]) -> np.ndarray:
    period, fmax = p["period"][0], p["fmax"][0]
    harmonics = np.arange(1, max(1, int(fmax * period)) + 1)
    phases = np.random.default_rng(int(p["seed"][0])).uniform(0.0, 2 * np.pi, harmonics.size)
    t = np.arange(int(round(period / dt))) * dt
    signal = np.zeros_like(t)
    for harmonic, phase in zip(harmonics, phases):  # one harmonic at a time: memory of one period
        signal += np.sin(2 * np.pi * harmonic * t / period + phase)
    one = (signal - signal.min()) / (signal.max() - signal.min())
    return np.tile(one, int(p["periods"][0]))


def _chirp(dt: float, p: dict[str, list[float]]) -> np.ndarray:
    f0, f1, length = p["f0"][0], p["f1"][0], p["length"][0]
    t = np.arange(int(round(length / dt))) * dt
    k = math.log(f1 / f0) / length
    phase = 2 * np.pi * f0 * (np.expm1(k * t) / k if k else t)
    return np.asarray(0.5 - 0.5 * np.cos(phase), dtype=np.float64)


@dataclass(frozen=True)
class ProtocolKind:
    shape: Shape
    defaults: dict[str, list[float]]
    positive: tuple[str, ...]  # parameters that must be > 0
    integers: tuple[str, ...] = ()
    length_s: Callable[[dict[str, list[float]]], float] = lambda p: 0.0  # one pass [s], known before the shape
    frequencies: tuple[str, ...] = ()  # parameters in Hz that must stay below the recording's Nyquist rate


PROTOCOLS: dict[str, ProtocolKind] = {
    "triangles": ProtocolKind(
        _triangles,
        {"levels": [4], "frequency": [0.05]},
        ("levels", "frequency"),
        ("levels",),
        lambda p: p["levels"][0] / p["frequency"][0],
        ("frequency",),
    ),
    "forc": ProtocolKind(
        _forc,
        {"curves": [10], "rate": [0.1]},
        ("curves", "rate"),
        ("curves",),
        lambda p: (p["curves"][0] + 1) / p["rate"][0],
    ),
    "sines": ProtocolKind(
        _sines,
        {"frequencies": [0.1, 0.2, 0.5, 1.0, 2.0], "amplitudes": [1.0, 0.5], "cycles": [3]},
        ("frequencies", "amplitudes", "cycles"),
        ("cycles",),
        lambda p: len(p["amplitudes"]) * p["cycles"][0] * sum(1.0 / f for f in p["frequencies"]),
        ("frequencies",),
    ),
    "steps": ProtocolKind(
        _steps,
        {"levels": [5], "hold": [10.0]},
        ("levels", "hold"),
        ("levels",),
        lambda p: (2 * p["levels"][0] + 1) * p["hold"][0],
    ),
    "multisine": ProtocolKind(
        _multisine,
        {"period": [20.0], "fmax": [2.0], "periods": [3], "seed": [0]},
        ("period", "fmax", "periods"),
        ("periods", "seed"),
        lambda p: p["period"][0] * p["periods"][0],
        ("fmax",),
    ),
    "chirp": ProtocolKind(
        _chirp,
        {"f0": [0.05], "f1": [2.0], "length": [60.0]},
        ("f0", "f1", "length"),
        (),
        lambda p: p["length"][0],
        ("f1",),
    ),
}


@dataclass(frozen=True)
class Protocol:
    """A command table ``values`` [command unit] at ``dt_s``, held at its last value after the end."""

    spec: str
    values: np.ndarray
    dt_s: float

    @property
    def duration_s(self) -> float:
        return self.values.size * self.dt_s

    def __call__(self, t: float) -> float:
        i = int(t / self.dt_s + 0.5)
        values = self._list
        return values[i] if i < len(values) else values[-1]

    @property
    def _list(self) -> list[float]:
        cached: list[float] | None = self.__dict__.get("_cache")
        if cached is None:
            cached = self.values.tolist()
            object.__setattr__(self, "_cache", cached)
        return cached


def _parameters(name: str, text: str, spec: str) -> dict[str, list[float]]:
    kind = PROTOCOLS[name]
    values = {k: list(v) for k, v in kind.defaults.items()}
    for item in filter(None, text.split(",")):
        key, _, value = item.partition("=")
        key = key.strip()
        if key not in values:
            raise DataError(f"--protocol {spec!r}: {name} has no parameter {key!r}; it has {', '.join(values)}")
        try:
            numbers = [float(v) for v in value.split("/")]
        except ValueError as exc:
            raise DataError(f"--protocol {spec!r}: {key}={value!r} is not a number (lists: 0.1/0.5/1)") from exc
        if not all(math.isfinite(v) for v in numbers) or (key in kind.positive and min(numbers) <= 0):
            raise DataError(
                f"--protocol {spec!r}: {key}={value!r} must be finite{' and > 0' if key in kind.positive else ''}"
            )
        if key in kind.integers and any(v != int(v) for v in numbers):
            raise DataError(f"--protocol {spec!r}: {key}={value!r} must be a whole number")
        if len(numbers) > 1 and len(kind.defaults[key]) == 1:
            raise DataError(f"--protocol {spec!r}: {key} takes one number, not a list")
        values[key] = numbers
    if name == "sines" and max(values["amplitudes"]) > 1.0:
        raise DataError(f"--protocol {spec!r}: amplitudes are shares of the half range, at most 1")
    if name == "chirp" and values["f0"][0] >= values["f1"][0]:
        raise DataError(f"--protocol {spec!r}: f0 must be below f1")
    return values


def _check_size(spec: str, kind: ProtocolKind, p: dict[str, list[float]], dt: float, nyquist_hz: float | None) -> None:
    """Refuse, before anything is allocated, a pass longer than a table holds, a frequency the
    recording cannot see (aliased) and a multisine too costly to compute."""
    for key in kind.frequencies:
        if nyquist_hz is not None and max(p[key]) >= nyquist_hz:
            raise DataError(
                f"--protocol {spec!r}: {key}={max(p[key]):g} Hz is at or above the recording's Nyquist rate "
                f"{nyquist_hz:g} Hz (half of --sample-hz); lower it or raise --sample-hz"
            )
    length = kind.length_s(p)
    if length / dt > MAX_TABLE_SAMPLES:
        raise DataError(
            f"--protocol {spec!r}: one pass lasts {length:.4g} s, longer than the {MAX_TABLE_SAMPLES * dt:.0f} s "
            "a recording holds at this loop rate; shorten it (and repeat it with --duration)"
        )
    if "fmax" in p and (p["fmax"][0] * p["period"][0]) * (p["period"][0] / dt) > MAX_MULTISINE_WORK:
        raise DataError(f"--protocol {spec!r}: fmax x period is too large to compute; lower fmax or period")


def _from_csv(path: Path, spec: str, dt: float) -> np.ndarray:
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:
            rows = list(csv.reader(handle))
    except OSError as exc:
        raise DataError(f"--protocol {path}: cannot read it ({exc.strerror})") from exc
    except UnicodeDecodeError as exc:
        raise DataError(f"--protocol {path}: not a text CSV; give t,<command> columns") from exc
    if not rows or len(rows[0]) < 2 or rows[0][0].strip() != "t":
        raise DataError(f"--protocol {path}: the first line must be a header 't,<command>' (e.g. t,pressure)")
    times: list[float] = []
    values: list[float] = []
    for number, row in enumerate(rows[1:], start=2):
        if not row or not "".join(row).strip():
            continue
        try:
            t, value = float(row[0]), float(row[1])
        except (ValueError, IndexError) as exc:
            raise DataError(f"--protocol {path}: line {number}: {row!r} is not two numbers t,command") from exc
        if not (math.isfinite(t) and math.isfinite(value)):
            raise DataError(f"--protocol {path}: line {number}: t and the command must be finite numbers")
        if times and t <= times[-1]:
            raise DataError(f"--protocol {path}: line {number}: t={t:g} does not increase; sort the rows")
        times.append(t)
        values.append(value)
    if len(times) < 2:
        raise DataError(f"--protocol {path}: needs at least two rows below the header")
    if times[0] != 0.0:
        raise DataError(f"--protocol {path}: t must start at 0 (it starts at {times[0]:g} s)")
    if times[-1] / dt > MAX_TABLE_SAMPLES:
        raise DataError(
            f"--protocol {path}: lasts {times[-1]:.4g} s, longer than the {MAX_TABLE_SAMPLES * dt:.0f} s a recording "
            "holds at this loop rate; is t in seconds? (shorten the file or split it)"
        )
    return np.asarray(np.interp(np.arange(int(round(times[-1] / dt)) + 1) * dt, times, values), dtype=np.float64)


def build_protocol(
    spec: str,
    low: float,
    high: float,
    dt_s: float,
    duration_s: float | None = None,
    unit: str = "bar",
    nyquist_hz: float | None = None,
) -> Protocol:
    """The command table of ``spec`` (a name, ``name:key=value,...`` or a CSV path) on
    ``low..high`` [``unit``], sampled every ``dt_s`` [s], repeated to ``duration_s`` [s]; a
    named protocol's frequencies must stay below ``nyquist_hz`` (the recording's, when given)."""
    if duration_s is not None and duration_s / dt_s > MAX_TABLE_SAMPLES:
        raise DataError(
            f"--duration {duration_s:g}: longer than the {MAX_TABLE_SAMPLES * dt_s:.0f} s one recording holds at "
            "this loop rate; record several shorter runs (pmactl fit and diagnose take several)"
        )
    name, _, text = spec.partition(":")
    if spec.lower().endswith(".csv"):
        values = _from_csv(Path(spec), spec, dt_s)
        if values.min() < low or values.max() > high:
            raise DataError(
                f"--protocol {spec}: commands {values.min():.3g}..{values.max():.3g} {unit} leave the allowed "
                f"{low:g}..{high:g} {unit} (--range and the config's limits); rescale the file or widen --range"
            )
    elif name in PROTOCOLS:
        parameters = _parameters(name, text, spec)
        _check_size(spec, PROTOCOLS[name], parameters, dt_s, nyquist_hz if nyquist_hz is not None else 0.5 / dt_s)
        shape = PROTOCOLS[name].shape(dt_s, parameters)
        if shape.size == 0:
            raise DataError(f"--protocol {spec!r}: shorter than one tick; lengthen it")
        values = low + (high - low) * shape
    else:
        raise DataError(
            f"--protocol {spec!r} unknown; use one of {', '.join(PROTOCOLS)} (NAME:key=value,...) "
            "or a FILE.csv of t,command"
        )
    lead = np.empty(0)
    if abs(values[0] - low) > 1e-9 * max(1.0, abs(high - low)):
        lead = np.linspace(low, values[0], int(round(LEAD_IN_S / dt_s)), endpoint=False)
    if duration_s is None:
        return Protocol(spec, np.concatenate([lead, values]), dt_s)
    steps = max(1, int(round(duration_s / dt_s)))  # the body repeats; the lead-in comes once
    body = np.tile(values, -(-max(steps - lead.size, 1) // values.size))
    return Protocol(spec, np.concatenate([lead, body])[:steps], dt_s)
