"""Placeholders and TOML edits: how a matrix turns one cell's values into commands and files.

``{name}`` in a command argument is replaced by the cell's value for ``name``. An argument that
is exactly ``"{name}"`` and whose value is a list (a choice such as ``pid`` ->
``["--no-feedforward"]``) is spliced into the command, so one axis can add or remove flags.
In file templates only known names are replaced: TOML inline tables (``{ a = 1 }``) and other
braces pass through untouched.

``set_toml_key`` edits one key of a TOML document as text (comments and layout of every other
line kept) and reads the result back to prove the edit took effect; that is how an axis fills
a rig config's ``buses.i2c.url = "sim://rig?effect={effect}"`` without a copy of the file per value.
"""

from __future__ import annotations

import json
import re
import tomllib
from collections.abc import Mapping

from edge.errors import ConfigError

Value = str | int | float | bool | list[str]

PLACEHOLDER = re.compile(r"\{([A-Za-z_][A-Za-z0-9_]*)\}")


def render_text(text: str, values: Mapping[str, Value], *, strict: bool, where: str) -> str:
    """``text`` with every ``{name}`` replaced by ``values[name]``.

    ``strict``: an unknown name is a :class:`ConfigError` naming ``where``; otherwise it is left as is.
    """

    def substitute(match: re.Match[str]) -> str:
        name = match.group(1)
        if name not in values:
            if strict:
                raise ConfigError(
                    f"{where}: placeholder {{{name}}} has no value; give it in [values], [paths] or [axes] "
                    f"(known: {', '.join(sorted(values))})"
                )
            return match.group(0)
        value = values[name]
        if isinstance(value, list):
            raise ConfigError(
                f'{where}: {{{name}}} is a list of arguments ({value}); use it as a whole argument "{{{name}}}"'
            )
        return _scalar_text(value)

    return PLACEHOLDER.sub(substitute, text)


def render_args(args: list[str], values: Mapping[str, Value], where: str) -> list[str]:
    """A command template rendered: whole-argument lists spliced, every other placeholder substituted."""
    out: list[str] = []
    for arg in args:
        whole = PLACEHOLDER.fullmatch(arg)
        spliced = values.get(whole.group(1)) if whole else None
        if isinstance(spliced, list):  # its elements may hold placeholders: extra = ["--operators", "{n}"]
            out.extend(render_text(str(a), values, strict=True, where=where) for a in spliced)
        else:
            out.append(render_text(arg, values, strict=True, where=where))
    return out


def render_value(value: Value, values: Mapping[str, Value], where: str) -> Value:
    """One TOML value rendered; ``"{name}"`` alone keeps the named value's type (an int stays an int)."""
    if isinstance(value, str):
        whole = PLACEHOLDER.fullmatch(value)
        if whole and whole.group(1) in values:
            return values[whole.group(1)]
        return render_text(value, values, strict=True, where=where)
    return value


def set_toml_key(text: str, dotted_key: str, value: Value, where: str) -> str:
    """``text`` (a TOML document) with ``dotted_key`` = ``value``; section created if missing.

    ``"buses.i2c.url"`` is key ``url`` of section ``[buses.i2c]``; ``"sensors.contraction.channel"`` is key
    ``channel`` of ``[sensors.contraction]``; a key without a dot lives before the first section.
    """
    section, _, key = dotted_key.rpartition(".")
    if not key:
        raise ConfigError(f"{where}: empty key in {dotted_key!r}")
    literal = toml_literal(value, where)
    lines = text.splitlines()
    start, end = _section_span(lines, section)
    if start is None:
        lines += ["", f"[{section}]", f"{key} = {literal}"]
    else:
        key_line = re.compile(rf"^\s*{re.escape(key)}\s*=")
        for i in range(start, end):
            if key_line.match(lines[i]):
                lines[i] = f"{key} = {literal}"
                break
        else:
            lines.insert(start, f"{key} = {literal}")
    edited = "\n".join(lines) + "\n"
    try:
        document = tomllib.loads(edited)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{where}: setting {dotted_key} made the file invalid TOML ({exc})") from exc
    node: object = document
    for part in dotted_key.split("."):
        node = node.get(part) if isinstance(node, dict) else None
    if node != value:
        raise ConfigError(
            f"{where}: could not set {dotted_key} (read back {node!r}); quoted or inline keys are not supported"
        )
    return edited


def toml_literal(value: Value, where: str) -> str:
    """``value`` written as a TOML literal (strings as basic strings, JSON escapes are valid TOML)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(toml_literal(v, where) for v in value) + "]"
    raise ConfigError(f"{where}: cannot write {value!r} into TOML")


def _section_span(lines: list[str], section: str) -> tuple[int | None, int]:
    """(first line after the header, end) of ``[section]``; ``""`` is the part before any header."""
    header = re.compile(r"^\s*\[\[?([^\[\]]+)\]\]?\s*(#.*)?$")
    start: int | None = 0 if section == "" else None
    for i, line in enumerate(lines):
        match = header.match(line)
        if not match:
            continue
        if start is not None:
            return start, i
        if match.group(1).strip() == section:
            start = i + 1
    return start, len(lines)


def _scalar_text(value: str | int | float | bool) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    return str(value)
