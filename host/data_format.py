"""How a lab's measurement file is laid out: delimiter, decimal comma, column names, units.

:class:`ReadOptions` says what the user told (``--columns``, ``--time-unit``, ``--units``);
:func:`sniff_layout` finds the rest in the file itself: the delimiter (``,`` ``;`` or tab, the
one that splits the header and the first data lines into the same number of fields), a decimal
comma (only with ``;`` or tab: with ``,`` it would be ambiguous), and the unit of each column
from a suffix in its header (``time_s``, ``pressure_bar``, ``length [mm]``, ``force (N)``).
Everything here is the standard library, so the CLI can parse the options on an edge install.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from edge.errors import DataError

DELIMITERS = (",", ";", "\t")
DELIMITER_NAMES = {",": "','", ";": "';'", "\t": "tab"}
SNIFF_LINES = 20
# time units pmactl converts to seconds: name -> seconds per unit
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
# unit suffixes recognised after the last '_' of a header (a bracketed unit is taken whatever it is):
# a closed list, so "load_cell" or "valve_cmd" are not read as units
SUFFIX_UNITS = {
    "s", "ms", "us", "min",
    "bar", "mbar", "kpa", "pa", "mpa", "psi",
    "mm", "cm", "m", "um",
    "n", "kn", "kg", "g",
    "v", "mv", "a", "ma",
    "deg", "rad", "degc", "c", "k", "pct",
}  # fmt: skip
_BRACKET_UNIT = re.compile(r"^(?P<name>.*?)\s*[\[(](?P<unit>[^\])]+)[\])]\s*$")
_DECIMAL_COMMA = re.compile(r"^\s*[-+]?\d+,\d+([eE][-+]?\d+)?\s*$")
ROLE_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")


@dataclass(frozen=True)
class ReadOptions:
    """What the user said about a file's layout (all optional).

    Attributes:
        columns: pmactl role (``t``, ``u``, ``y``, ``load``, ``temperature``, ``p``, ...) -> the
            file's header name for it.
        time_unit: unit of the time column (a key of :data:`TIME_UNITS`); None: the header's
            unit suffix, else seconds (checked for looking like milliseconds or sample numbers).
        units: role -> unit for printed tables and bundles; overrides the header's suffixes.
    """

    columns: dict[str, str] = field(default_factory=dict)
    time_unit: str | None = None
    units: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Layout:
    """What :func:`sniff_layout` found: delimiter, decimal comma, header names, units per name."""

    delimiter: str
    decimal_comma: bool
    header: list[str]
    units: dict[str, str]


def parse_columns(text: str) -> dict[str, str]:
    """``t=time_s,u=pressure_bar,y=length_mm`` -> ``{"t": "time_s", ...}``; DataError with the fix."""
    mapping: dict[str, str] = {}
    for part in (p.strip() for p in text.split(",")):
        role, sep, name = (s.strip() for s in part.partition("="))
        if not sep or not role or not name or not ROLE_NAME.match(role):
            raise DataError(
                f"--columns {text!r}: {part!r} is not ROLE=HEADER; "
                "give e.g. --columns t=time_s,u=pressure_bar,y=length_mm"
            )
        if role in mapping:
            raise DataError(f"--columns {text!r}: {role!r} is given twice; map each role once")
        mapping[role] = name
    return mapping


def parse_units(text: str, roles: tuple[str, ...] = ("u", "y")) -> dict[str, str]:
    """``--units bar,mm`` (units of u and y) or ``--units u=bar,y=mm,load=N`` -> role -> unit."""
    parts = [p.strip() for p in text.split(",")]
    if all("=" in p for p in parts):
        return parse_columns(text.replace("--columns", "--units"))
    if len(parts) != len(roles) or not all(parts) or any("=" in p for p in parts):
        raise DataError(
            f"--units {text!r} must be {len(roles)} names separated by a comma ({', '.join(roles)}), "
            "e.g. --units bar,mm, or ROLE=UNIT pairs such as u=bar,y=mm"
        )
    return dict(zip(roles, parts))


def header_unit(name: str) -> str | None:
    """The unit a header name carries: ``time_s`` -> ``s``, ``length [mm]`` -> ``mm``, ``u`` -> None."""
    bracket = _BRACKET_UNIT.match(name)
    if bracket:
        return bracket.group("unit").strip()
    stem, sep, suffix = name.rpartition("_")
    if sep and stem and suffix.lower() in SUFFIX_UNITS:
        return suffix
    return None


def header_stem(name: str) -> str:
    """The name without its unit: ``u_bar`` -> ``u``, ``y [mm]`` -> ``y``, ``t`` -> ``t``."""
    bracket = _BRACKET_UNIT.match(name)
    if bracket:
        return bracket.group("name").strip()
    return name.rpartition("_")[0] if header_unit(name) else name


def _split(line: str, delimiter: str) -> list[str]:
    import csv

    return next(csv.reader([line], delimiter=delimiter), [])


def sniff_layout(path: Path) -> Layout:
    """Delimiter, decimal comma, header and header units of ``path`` (see module docstring)."""
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:  # -sig: Excel's "CSV UTF-8" BOM
            lines = []
            for text in handle:
                if text.strip() and not text.lstrip().startswith("#"):
                    lines.append(text.rstrip("\r\n"))
                if len(lines) > SNIFF_LINES:
                    break
    except (OSError, UnicodeDecodeError) as exc:
        raise DataError(f"{path}: cannot read file ({exc}); check the path and that it is a text CSV") from exc
    if not lines:
        raise DataError(f"{path}: file is empty; expected a CSV header with columns t,u,y")
    header_line, data = lines[0], lines[1:]
    delimiter = ","
    for candidate in DELIMITERS:
        width = len(_split(header_line, candidate))
        if width > 1 and all(len(_split(line, candidate)) == width for line in data):
            delimiter = candidate
            break
    header = [h.strip() for h in _split(header_line, delimiter)]
    decimal_comma = delimiter != "," and any(
        _DECIMAL_COMMA.match(cell) for line in data for cell in _split(line, delimiter)
    )
    units = {name: unit for name in header if (unit := header_unit(name)) is not None}
    return Layout(delimiter, decimal_comma, header, units)


def time_scale(unit: str | None, source: str) -> float:
    """Seconds per unit of the time column; DataError naming the units pmactl converts."""
    if unit is None:
        return 1.0
    scale = TIME_UNITS.get(unit.lower())
    if scale is None:
        raise DataError(
            f"{source}: time unit {unit!r} is not one pmactl converts; write time in {', '.join(TIME_UNITS)} "
            "or pass --time-unit"
        )
    return scale


def check_seconds(step_s: float, all_integers: bool, source: str, time_name: str) -> None:
    """Refuse a time column whose median step says it is not in seconds (no unit was given).

    A pneumatic-muscle recording samples at 10 Hz or faster; a median step of 0.5 or more is
    milliseconds (or sample numbers, when every value is a whole number).
    """
    if step_s < 0.5:
        return
    what = "sample numbers or milliseconds" if all_integers else "milliseconds"
    raise DataError(
        f"{source}: time column {time_name!r} steps by {step_s:g} per sample, which looks like {what}, not seconds; "
        "pass --time-unit ms (or us), or --time-unit s if it really is seconds"
    )
