"""Measured-data CSV loader: ``t`` [s], ``u``, ``y`` plus optional ``load``, ``temperature``, ``p``.

Every problem is one :class:`~edge.errors.DataError` whose message names the file, the line,
the problem and the fix: a row with too few or too many fields, a duplicated column name, NaN or
text in t/u/y or in a named optional column (load, temperature, p: a model fitted on one would
drop it or be poisoned by it; other extra columns may have holes), values too large to fit
(beyond 1e100), time that does not increase, and a time gap of more than ``max_gap_periods``
sample periods (two recordings in one file: resampling across it would invent millions of
samples). A UTF-8 byte-order mark (Excel's "CSV UTF-8") and quoted numbers are read as such.
Irregular sampling beyond ``tolerance`` (relative spread of the time step) is either resampled
onto a uniform grid at the median step, with a warning saying so, or refused.

Files as labs write them (:mod:`host.data_format`): the delimiter (``,`` ``;`` tab) and a decimal
comma are sniffed, ``ReadOptions.columns`` maps the file's own names to t/u/y/load/..., a unit
suffix in the header (``time_ms``, ``length [mm]``) or ``ReadOptions.units`` gives the units
(time is converted to seconds), and a time column without a unit whose step looks like
milliseconds or sample numbers is refused with the fix (``--time-unit ms``).
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
from host.data_format import ReadOptions, check_seconds, header_stem, sniff_layout, time_scale

REQUIRED = ("t", "u", "y")
OPTIONAL = ("load", "temperature", "p")
MAX_GAP_PERIODS = 10.0  # a longer time step is a split record, not jitter to resample over
MAX_MAGNITUDE = 1e100  # squares and sums of a fit overflow float64 long before 1e308


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
        units: role (``t``, ``u``, ``y``, an extra's name) -> unit, where known (``t`` is always s).
    """

    t: NDArray[np.float64]
    u: NDArray[np.float64]
    y: NDArray[np.float64]
    extras: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    source: str = "<memory>"
    notes: list[str] = field(default_factory=list)
    units: dict[str, str] = field(default_factory=dict)

    def unit(self, role: str, default: str = "") -> str:
        """The unit of ``role`` for a printed table or a figure label (``default`` when unknown)."""
        return self.units.get(role, default)

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
            dict(self.units),
        )


def _check_duplicates(path: Path, columns: list[str]) -> None:
    seen: dict[str, int] = {}
    for number, name in enumerate(columns, start=1):
        if name and name in seen:
            raise DataError(
                f"{path}: line 1: column {name!r} appears twice (columns {seen[name]} and {number}); "
                "rename or delete one"
            )
        seen[name] = number


def _roles(path: Path, header: list[str], mapping: dict[str, str]) -> list[str]:
    """The header with the user's names replaced by their roles (``--columns``; a name that is a
    role plus a unit, such as ``u_bar``, takes that role when no column is named so)."""
    missing = [f"{role}={name}" for role, name in mapping.items() if name not in header]
    if missing:
        raise DataError(
            f"{path}: --columns {', '.join(missing)}: no such column; found {header}. Give the names as in the header"
        )
    by_name = {name: role for role, name in mapping.items()}
    for role in (*REQUIRED, *OPTIONAL):  # "u_bar" or "y [mm]" is u or y when nothing else is
        stems = [h for h in header if header_stem(h) == role]
        if role not in mapping and role not in header and len(stems) == 1 and stems[0] not in by_name:
            by_name[stems[0]] = role
    taken = set(by_name.values())
    # a column already named like a mapped role keeps its data under another name
    return [by_name.get(h, f"{h}_unmapped" if h in taken else h) for h in header]


def _decimal_points(path: Path) -> list[str]:
    """The file's lines with decimal commas made points (the delimiter is then ';' or tab)."""
    with path.open(encoding="utf-8-sig") as handle:
        return [line.replace(",", ".") for line in handle]


def _read_table(
    path: Path, width: int, delimiter: str = ",", decimal_comma: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.int64] | None]:
    """Numeric rows and their file line numbers; a row with the wrong number of fields is refused.

    numpy's C parser reads well-formed files (quoted numbers included); anything it rejects is
    read again row by row, so the error can name the line. Cells that are not numbers become NaN
    (the caller refuses them in t/u/y, with their lines).
    """
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "input contained no data" is handled below
            source = _decimal_points(path) if decimal_comma else path
            table = np.loadtxt(
                source, delimiter=delimiter, skiprows=1, quotechar='"', encoding="utf-8-sig", ndmin=2, comments="#"
            )
    except (ValueError, IndexError):
        return _read_rows_one_by_one(path, width, delimiter, decimal_comma)
    if table.size and table.shape[1] != width:
        return _read_rows_one_by_one(path, width, delimiter, decimal_comma)
    return table, None  # line numbers only when a message needs them: see _data_lines


def _data_lines(path: Path) -> NDArray[np.int64]:
    """File line numbers of the data rows (blank and ``#`` lines skipped, as the parser does)."""
    with path.open(encoding="utf-8-sig") as handle:
        next(handle, None)
        numbers = [n for n, text in enumerate(handle, start=2) if text.strip() and not text.lstrip().startswith("#")]
    return np.array(numbers, dtype=np.int64)


def _read_rows_one_by_one(
    path: Path, width: int, delimiter: str = ",", decimal_comma: bool = False
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    values: list[list[float]] = []
    lines: list[int] = []
    with path.open(newline="", encoding="utf-8-sig") as handle:
        reader = csv.reader(handle, delimiter=delimiter)
        next(reader, None)
        for row in reader:
            if not row or all(not cell.strip() for cell in row) or row[0].lstrip().startswith("#"):
                continue  # blank or comment line
            if len(row) != width:
                raise DataError(
                    f"{path}: line {reader.line_num} has {len(row)} field(s) but the header has {width}; "
                    "fix or delete that line (a cut-off or merged row?)"
                )
            values.append([_number(cell.replace(",", ".") if decimal_comma else cell) for cell in row])
            lines.append(reader.line_num)
    return np.array(values, dtype=float).reshape(-1, width), np.array(lines, dtype=np.int64)


def _number(cell: str) -> float:
    try:
        return float(cell)
    except ValueError:
        return float("nan")


class _LazyLines:
    """Row -> file line, read from the file only when an error message asks."""

    def __init__(self, path: Path) -> None:
        self._path = path
        self._lines: NDArray[np.int64] | None = None

    def __getitem__(self, row: int) -> int:
        if self._lines is None:
            self._lines = _data_lines(self._path)
        return int(self._lines[row])


def _line_list(lines: NDArray[np.int64] | _LazyLines, rows: NDArray[np.intp]) -> str:
    return ", ".join(str(int(lines[r])) for r in rows[:5]) + (" ..." if rows.size > 5 else "")


def load_measurement(
    path: str | Path,
    *,
    irregular: Literal["resample", "refuse"] = "resample",
    tolerance: float = 0.05,
    min_samples: int = 10,
    max_gap_periods: float = MAX_GAP_PERIODS,
    options: ReadOptions | None = None,
    require_output: bool = True,
) -> Measurement:
    """Load and validate a measured-data CSV (see module docstring).

    Args:
        path: CSV file with a header row (UTF-8, a BOM allowed; numbers may be quoted).
        irregular: what to do with non-uniform sampling beyond ``tolerance``.
        tolerance: allowed ``(max(dt) - min(dt)) / median(dt)``.
        min_samples: fewer rows than this is an error.
        max_gap_periods: a time step longer than this many median steps is a split record
            (two recordings in one file), refused with its position.
        options: the file's layout as the user gave it (column names, time unit, units).
        require_output: False reads a designed input too (``t, u`` alone): without a ``y``
            column the measurement's ``y`` is all NaN and its rows are kept as they are spaced
            (no resampling, no gap check: ``pmactl simulate``'s designed inputs).
    """
    path = Path(path)
    options = options or ReadOptions()
    layout = sniff_layout(path)
    _check_duplicates(path, layout.header)
    columns = _roles(path, layout.header, options.columns)
    required = REQUIRED if require_output or "y" in columns else ("t", "u")
    missing = [c for c in required if c not in columns]
    if missing:
        raise DataError(
            f"{path}: column(s) {', '.join(repr(m) for m in missing)} missing; found {layout.header}. "
            "Name them with --columns, e.g. --columns t=time_s,u=pressure_bar,y=length_mm "
            "(or rename the columns to t [s], u (input), y (output))"
        )
    units = {role: layout.units[name] for role, name in zip(columns, layout.header) if name in layout.units}
    units.update(options.units)
    time_unit = options.time_unit or units.get("t")
    table, parsed_lines = _read_table(path, len(columns), layout.delimiter, layout.decimal_comma)
    lines = parsed_lines if parsed_lines is not None else _LazyLines(path)
    if table.size == 0:
        raise DataError(f"{path}: no data rows below the header; check the file is complete")
    wanted = [c for c in (*REQUIRED, *OPTIONAL) if c in columns] + [
        c for c in columns if c not in REQUIRED + OPTIONAL and c
    ]
    data = {c: table[:, columns.index(c)] for c in wanted}
    core = np.column_stack([data[c] for c in required])
    bad = np.flatnonzero(~np.all(np.isfinite(core), axis=1))
    if bad.size:
        raise DataError(
            f"{path}: {bad.size} row(s) with NaN, inf or non-numbers in {'/'.join(required)} "
            f"(file lines {_line_list(lines, bad)}); "
            "remove or interpolate them"
        )
    for name in (c for c in OPTIONAL if c in data):
        holes = np.flatnonzero(~np.isfinite(data[name]))
        if holes.size:  # a model fitted on this column would drop it or be poisoned by it, silently
            raise DataError(
                f"{path}: {holes.size} row(s) with NaN, inf or non-numbers in the {name!r} column (file lines "
                f"{_line_list(lines, holes)}); interpolate or remove them, or delete the column if it was not measured"
            )
    huge = np.flatnonzero(np.any(np.abs(table) > MAX_MAGNITUDE, axis=1))
    if huge.size:
        raise DataError(
            f"{path}: {huge.size} row(s) with values beyond +-{MAX_MAGNITUDE:.0e} "
            f"(file lines {_line_list(lines, huge)}); a fit squares and sums them, which overflows: "
            "check the units or the export"
        )
    if len(core) < min_samples:
        raise DataError(f"{path}: only {len(core)} samples; need at least {min_samples}")
    t = data["t"] * time_scale(time_unit, str(path))
    steps = np.diff(t)
    if np.any(steps <= 0):
        first = int(np.argmax(steps <= 0))
        raise DataError(
            f"{path}: time is not strictly increasing at file line {lines[first + 1]} "
            f"(t={t[first]:g} then {t[first + 1]:g}); sort the rows and drop duplicates"
        )
    median = float(np.median(steps))
    if time_unit is None:
        time_name = layout.header[columns.index("t")]
        check_seconds(median, bool(np.all(t == np.round(t))), str(path), time_name)
    units["t"] = "s"
    gap = int(np.argmax(steps))
    if "y" in columns and steps[gap] > max_gap_periods * median:
        raise DataError(
            f"{path}: t jumps by {steps[gap]:.4g} s ({steps[gap] / median:.3g} sample periods of {median:.4g} s) "
            f"between file lines {lines[gap]} and {lines[gap + 1]} (t={t[gap]:g} -> {t[gap + 1]:g}): "
            "two recordings in one file; split it there and use each part on its own"
        )
    extras = {c: data[c] for c in wanted if c not in REQUIRED}
    if "y" not in columns:  # a designed input: its rows are the samples, as the user spaced them
        return Measurement(t, data["u"], np.full_like(t, np.nan), extras, str(path), [], units)
    measurement = Measurement(t, data["u"], data["y"], extras, str(path), [], units)
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
        t_new, np.interp(t_new, m.t, m.u), np.interp(t_new, m.t, m.y), extras, m.source, [*m.notes, note], m.units
    )
