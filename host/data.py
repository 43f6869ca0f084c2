"""Measured-data CSV loader: ``t`` [s], ``u``, ``y`` plus optional ``load``, ``temperature``, ``p``.

Every problem is one :class:`~edge.errors.DataError` whose message names the file, the problem
and the fix. Irregular sampling beyond ``tolerance`` (relative spread of the time step) is
either resampled onto a uniform grid at the median step, with a warning saying so, or refused.
"""

from __future__ import annotations

import csv
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from edge.errors import DataError

REQUIRED = ("t", "u", "y")
OPTIONAL = ("load", "temperature", "p")


class ResampledWarning(UserWarning):
    """The loader put irregularly sampled data onto a uniform time grid."""


@dataclass
class Measurement:
    """One recording on a uniform time grid.

    Attributes:
        t: time [s], strictly increasing and uniform.
        u: actuator input (e.g. pressure in bar, voltage in V).
        y: measured output (e.g. contraction in mm, displacement in um).
        extras: optional columns present in the file (``load``, ``temperature``, ``p``, ...).
        source: where it came from (file path or a description).
        notes: what the loader changed, e.g. resampling.
    """

    t: NDArray[np.float64]
    u: NDArray[np.float64]
    y: NDArray[np.float64]
    extras: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    source: str = "<memory>"
    notes: list[str] = field(default_factory=list)

    @property
    def dt(self) -> float:
        """Sample period [s]."""
        return float(self.t[1] - self.t[0]) if self.t.size > 1 else float("nan")

    def __len__(self) -> int:
        return int(self.t.size)

    def slice(self, start: int, stop: int | None = None) -> Measurement:
        """Samples ``start:stop`` as a new measurement."""
        part = slice(start, stop)
        return Measurement(
            self.t[part],
            self.u[part],
            self.y[part],
            {k: v[part] for k, v in self.extras.items()},
            self.source,
            list(self.notes),
        )


def _read_header(path: Path) -> list[str]:
    try:
        with path.open(newline="") as handle:
            header = next(csv.reader(handle), None)
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: cannot read file ({exc}); check the path and that it is a text CSV") from exc
    if not header:
        raise DataError(f"{path}: file is empty; expected a CSV header with columns t,u,y")
    return [h.strip() for h in header]


def load_measurement(
    path: str | Path,
    *,
    irregular: Literal["resample", "refuse"] = "resample",
    tolerance: float = 0.05,
    min_samples: int = 10,
) -> Measurement:
    """Load and validate a measured-data CSV (see module docstring).

    Args:
        path: CSV file with a header row.
        irregular: what to do with non-uniform sampling beyond ``tolerance``.
        tolerance: allowed ``(max(dt) - min(dt)) / median(dt)``.
        min_samples: fewer rows than this is an error.
    """
    path = Path(path)
    columns = _read_header(path)
    missing = [c for c in REQUIRED if c not in columns]
    if missing:
        raise DataError(
            f"{path}: column(s) {', '.join(repr(m) for m in missing)} missing; found {columns}. "
            "Rename the columns to t [s], u (input), y (output)"
        )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table = np.genfromtxt(path, delimiter=",", skip_header=1, dtype=float, invalid_raise=False)
    table = np.atleast_2d(table)
    if table.size == 0 or table.shape[1] != len(columns):
        raise DataError(f"{path}: no data rows with {len(columns)} fields; check the delimiter is ','")
    wanted = [c for c in (*REQUIRED, *OPTIONAL) if c in columns] + [
        c for c in columns if c not in REQUIRED + OPTIONAL and c
    ]
    data = {c: table[:, columns.index(c)] for c in wanted}
    core = np.column_stack([data[c] for c in REQUIRED])
    bad = np.flatnonzero(~np.all(np.isfinite(core), axis=1))
    if bad.size:
        rows = ", ".join(str(int(r) + 2) for r in bad[:5]) + (" ..." if bad.size > 5 else "")
        raise DataError(
            f"{path}: {bad.size} row(s) with NaN, inf or non-numbers in t/u/y (file lines {rows}); "
            "remove or interpolate them"
        )
    if len(core) < min_samples:
        raise DataError(f"{path}: only {len(core)} samples; need at least {min_samples}")
    t = data["t"]
    steps = np.diff(t)
    if np.any(steps <= 0):
        first = int(np.argmax(steps <= 0))
        raise DataError(
            f"{path}: time is not strictly increasing at file line {first + 3} "
            f"(t={t[first]:g} then {t[first + 1]:g}); sort the rows and drop duplicates"
        )
    measurement = Measurement(t, data["u"], data["y"], {c: data[c] for c in wanted if c not in REQUIRED}, str(path))
    return _uniform(measurement, irregular, tolerance)


def _uniform(m: Measurement, irregular: str, tolerance: float) -> Measurement:
    steps = np.diff(m.t)
    median = float(np.median(steps))
    spread = float((steps.max() - steps.min()) / median)
    if spread <= tolerance:
        return m
    if irregular == "refuse":
        raise DataError(
            f"{m.source}: irregular sampling (step {steps.min():.4g}..{steps.max():.4g} s, "
            f"spread {spread:.0%} > {tolerance:.0%}); resample it or load with irregular='resample'"
        )
    t_new = m.t[0] + median * np.arange(int(np.floor((m.t[-1] - m.t[0]) / median)) + 1)
    note = (
        f"resampled from irregular steps {steps.min():.4g}..{steps.max():.4g} s onto a uniform "
        f"{median:.4g} s grid by linear interpolation ({m.t.size} -> {t_new.size} samples)"
    )
    warnings.warn(f"{m.source}: {note}", ResampledWarning, stacklevel=3)
    extras = {k: np.interp(t_new, m.t, v) for k, v in m.extras.items()}
    return Measurement(
        t_new, np.interp(t_new, m.t, m.u), np.interp(t_new, m.t, m.y), extras, m.source, [*m.notes, note]
    )
