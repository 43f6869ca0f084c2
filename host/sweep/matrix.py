"""A sweep matrix (``*.sweep.toml``): loaded, checked, and expanded into cells.

The file names a job kind (:mod:`host.sweep.presets`), the axes to cross, fixed values
(``[values]``, or ``[paths]`` resolved against the matrix file), named choices, files to render
per cell (``[files.NAME]``: a template with ``set`` keys), the steps (``[[steps]]`` replaces the
preset's, ``[[before]]`` runs ahead of them), thresholds and a retry policy; see
``docs/examples/*.sweep.toml``. Every mistake is one :class:`ConfigError` line naming the file,
the key and the fix. Axis values are a TOML list, ``"A..B"`` (integers A to B inclusive) or
``"glob:PATTERN"`` (files, relative to the matrix file).

Each cell has a key: a hash of everything that decides what it runs (its commands, rendered
files and environment). The results table is keyed by it, so a resumed sweep skips finished
cells, and a cell whose command changed since is run again.
"""

from __future__ import annotations

import difflib
import glob as globlib
import hashlib
import itertools
import json
import sys
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from edge.errors import ConfigError
from host.sweep.presets import COMMON_TIMING, KINDS, JobKind, Resources, Step
from host.sweep.template import Value, render_args, render_text, render_value, set_toml_key
from host.sweep.thresholds import Threshold, parse_thresholds

TOP_LEVEL = {
    "kind", "name", "description", "timeout_s", "retries", "retry_on", "seed", "axes", "values", "paths",
    "choices", "files", "steps", "before", "thresholds", "resources", "env", "timing_columns",
}  # fmt: skip
RETRY_KINDS = ("timeout", "signal", "error")
# columns of the results table besides axes and metrics; an axis may not take one of these names
ROW_COLUMNS = (
    "cell", "index", "seed", "status", "reasons", "attempts", "exit_code", "error", "elapsed_s", "cpu_s", "host",
)  # fmt: skip


@dataclass(frozen=True)
class Cell:
    """One job of the sweep: its axis labels, its seed and what it runs."""

    index: int
    key: str
    labels: dict[str, Value]
    seed: int
    values: dict[str, Value]
    steps: tuple[Step, ...]
    files: dict[str, str]  # file name in the cell's directory -> text

    def commands(self, attempt: int, where: str) -> list[dict[str, Any]]:
        """The steps of one attempt as plain data (what a worker runs)."""
        values = {**self.values, "attempt": attempt}
        return [
            {
                "name": step.name,
                "argv": render_args(list(step.args), values, f"{where}: step {step.name!r}"),
                "program": step.program,
                "json": step.json,
            }
            for step in self.steps
        ]


@dataclass(frozen=True)
class Matrix:
    path: Path
    name: str
    kind: JobKind
    axes: dict[str, list[Value]]
    cells: list[Cell]
    thresholds: list[Threshold]
    retries: int
    retry_on: tuple[str, ...]
    timeout_s: float
    resources: Resources
    env: dict[str, str]
    timing_columns: tuple[str, ...] = field(default=COMMON_TIMING)


def load_matrix(path: str | Path) -> Matrix:
    """Read and check ``path``; every cell expanded. Raises :class:`ConfigError` on any mistake."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text())
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read the matrix ({exc.strerror})") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML ({exc})") from exc
    where = str(path)
    _check_keys(doc, TOP_LEVEL, where)
    kind_name = doc.get("kind")
    if kind_name not in KINDS:
        raise ConfigError(f"{where}: kind = {kind_name!r}; use one of {list(KINDS)}")
    kind = KINDS[kind_name]
    base = path.resolve().parent
    steps = _steps(doc.get("steps"), kind, where)
    if "before" in doc:  # steps of the matrix's own run before the preset's (e.g. fit the bundle first)
        steps = _steps(doc["before"], kind, f"{where}: before") + steps
        if len({s.name for s in steps}) != len(steps):
            raise ConfigError(f"{where}: step names {[s.name for s in steps]} repeat; name each [[before]] step")
    axes = {name: _axis_values(name, spec, base, where) for name, spec in _table(doc, "axes", where).items()}
    clash = sorted(set(axes) & (set(ROW_COLUMNS) - {"seed"}) | set(axes) & {"attempt", "cell_dir"})
    if clash:
        raise ConfigError(f"{where}: axis name(s) {clash} are result columns; rename the axis")
    if not axes:
        raise ConfigError(f'{where}: [axes] is empty; name at least one axis, e.g. seed = "1..5"')
    choices = {**kind.choices, **{k: _table(doc["choices"], k, where) for k in doc.get("choices", {})}}
    fixed = _fixed_values(doc, kind, base, where)
    file_specs = {**kind.files, **_table(doc, "files", where)}
    env = {str(k): str(v) for k, v in _table(doc, "env", where).items()}
    base_seed = _number(doc, "seed", 0, int, where)
    cells = []
    cache: dict[str, str] = {}
    for index, combo in enumerate(itertools.product(*axes.values())):
        labels = dict(zip(axes, combo))
        seed = _cell_seed(labels, base_seed, where)
        values = _cell_values(fixed, labels, seed, choices, where)
        files = {}
        for file_id, spec in file_specs.items():
            name, text = _render_file(file_id, spec, values, base, cache, where)
            files[name] = text
            values[file_id] = name
        key = _cell_key(kind.name, steps, values, files, env, where)  # an unknown placeholder fails here
        cells.append(Cell(index, key, labels, seed, values, steps, files))
    resources = _resources(doc, kind.resources, where)
    retry_on = tuple(doc.get("retry_on", RETRY_KINDS))
    if not set(retry_on) <= set(RETRY_KINDS):
        raise ConfigError(f"{where}: retry_on = {list(retry_on)}; use any of {list(RETRY_KINDS)}")
    return Matrix(
        path=path,
        name=str(doc.get("name", path.name.removesuffix(".toml").removesuffix(".sweep"))),
        kind=kind,
        axes=axes,
        cells=cells,
        thresholds=parse_thresholds(doc.get("thresholds", {}), set(axes), where),
        retries=_number(doc, "retries", 1, int, where, minimum=0),
        retry_on=retry_on,
        timeout_s=_number(doc, "timeout_s", 600.0, float, where, minimum=1e-3),
        resources=resources,
        env=env,
        timing_columns=COMMON_TIMING + kind.timing_columns + tuple(doc.get("timing_columns", ())),
    )


def builtin_values(base: Path) -> dict[str, Value]:
    """Names every matrix can use: the matrix's folder, this Python, the shipped examples."""
    from importlib import resources

    from host.examples import example_path

    return {
        "matrix_dir": str(base),
        "python": sys.executable,
        "example_train": str(example_path("train")),
        "example_test": str(example_path("test")),
        "hil_config": str(resources.files("hil") / "configs" / "hil-rig.toml"),
    }


def _steps(raw: object, kind: JobKind, where: str) -> tuple[Step, ...]:
    if raw is None:
        if not kind.steps:
            raise ConfigError(f"{where}: kind {kind.name!r} has no default command; give it as [[steps]] args = [...]")
        return kind.steps
    if not isinstance(raw, list) or not raw:
        raise ConfigError(f"{where}: steps must be a list of tables ([[steps]] name = ..., args = [...])")
    steps = []
    for i, entry in enumerate(raw):
        here = f"{where}: steps[{i}]"
        if not isinstance(entry, dict):
            raise ConfigError(f"{here}: must be a table with args = [...]")
        _check_keys(entry, {"name", "args", "json", "program"}, here)
        args = entry.get("args")
        if not isinstance(args, list) or not args or not all(isinstance(a, str) for a in args):
            raise ConfigError(f"{here}: args must be a non-empty list of strings")
        json_spec = str(entry.get("json", "stdout"))
        if json_spec not in ("stdout", "none") and not json_spec.startswith("file:"):
            raise ConfigError(f'{here}: json = {json_spec!r}; use "stdout", "none" or "file:NAME"')
        steps.append(
            Step(str(entry.get("name", f"step{i}")), tuple(args), json_spec, bool(entry.get("program", False)))
        )
    names = [s.name for s in steps]
    if len(set(names)) != len(names):
        raise ConfigError(f"{where}: step names {names} repeat; each step needs its own name (it prefixes its metrics)")
    return tuple(steps)


def _axis_values(name: str, spec: object, base: Path, where: str) -> list[Value]:
    here = f"{where}: axes.{name}"
    if isinstance(spec, str) and spec.startswith("glob:"):
        pattern = spec.removeprefix("glob:")
        found = sorted(globlib.glob(str(base / pattern)))
        if not found:
            raise ConfigError(f"{here}: {pattern!r} matches no file under {base}")
        return list(found)
    if isinstance(spec, str) and ".." in spec:
        lo, _, hi = spec.partition("..")
        try:
            first, last = int(lo), int(hi)
        except ValueError:
            raise ConfigError(f'{here}: range {spec!r} must be two integers, e.g. "1..20"') from None
        if last < first:
            raise ConfigError(f"{here}: range {spec!r} is empty; write the smaller number first")
        return list(range(first, last + 1))
    if not isinstance(spec, list) or not spec:
        raise ConfigError(f'{here}: give a non-empty list, "A..B" or "glob:PATTERN"')
    if any(isinstance(v, dict | list) for v in spec):
        raise ConfigError(f"{here}: values must be strings or numbers; map labels to flags in [choices.{name}]")
    if len(set(map(str, spec))) != len(spec):
        raise ConfigError(f"{here}: values {spec} repeat")
    return list(spec)


def _fixed_values(doc: dict[str, Any], kind: JobKind, base: Path, where: str) -> dict[str, Value]:
    fixed: dict[str, Value] = {**builtin_values(base), **kind.defaults}
    fixed.update(_table(doc, "values", where))
    for name, raw in _table(doc, "paths", where).items():
        if not isinstance(raw, str):
            raise ConfigError(f"{where}: paths.{name} must be a string (a path relative to the matrix file)")
        fixed[name] = str((base / render_text(raw, fixed, strict=True, where=f"{where}: paths.{name}")).resolve())
    return fixed


def _cell_values(
    fixed: dict[str, Value], labels: dict[str, Value], seed: int, choices: dict[str, dict[str, Value]], where: str
) -> dict[str, Value]:
    values = {**fixed, **labels, "seed": seed}
    for name, mapping in choices.items():
        label = values.get(name)
        if label is None or isinstance(label, list):
            continue
        if str(label) not in mapping:
            raise ConfigError(f"{where}: {name} = {label!r} is not one of the choices {list(mapping)}")
        values[name] = mapping[str(label)]
    for name, value in list(values.items()):  # one level of indirection: train = "{example_train}"
        if isinstance(value, str):
            values[name] = render_text(value, values, strict=False, where=where)
    return values


def _render_file(
    file_id: str, spec: object, values: dict[str, Value], base: Path, cache: dict[str, str], where: str
) -> tuple[str, str]:
    here = f"{where}: files.{file_id}"
    if not isinstance(spec, dict):
        raise ConfigError(f'{here}: must be a table with template = "PATH" or text = "..."')
    _check_keys(spec, {"template", "text", "name", "set"}, here)
    if "text" in spec:
        text = str(spec["text"])
    elif "template" in spec:
        source = base / render_text(str(spec["template"]), values, strict=True, where=here)
        if str(source) not in cache:
            try:
                cache[str(source)] = source.read_text()
            except OSError as exc:
                raise ConfigError(f"{here}: cannot read template {source} ({exc.strerror})") from exc
        text = cache[str(source)]
    else:
        raise ConfigError(f'{here}: give template = "PATH" or text = "..."')
    text = render_text(text, values, strict=False, where=here)
    for dotted, raw in dict(spec.get("set", {})).items():
        text = set_toml_key(text, dotted, render_value(raw, values, f"{here}.set.{dotted}"), here)
    name = str(spec.get("name", f"{file_id}.toml"))
    if "/" in name or name.startswith("."):
        raise ConfigError(f"{here}: name {name!r} must be a plain file name (it is written in the cell's folder)")
    return name, text


def _cell_seed(labels: dict[str, Value], base_seed: int, where: str) -> int:
    """The seed axis when there is one; otherwise a hash of the labels (order- and host-independent)."""
    if "seed" in labels:
        if not isinstance(labels["seed"], int) or isinstance(labels["seed"], bool):
            raise ConfigError(f"{where}: axes.seed values must be integers, got {labels['seed']!r}")
        return labels["seed"]
    digest = hashlib.sha256(f"{base_seed}|{json.dumps(labels, sort_keys=True)}".encode()).digest()
    return int.from_bytes(digest[:4], "big") & 0x7FFFFFFF


def _cell_key(
    kind: str, steps: tuple[Step, ...], values: dict[str, Value], files: dict[str, str], env: dict[str, str], where: str
) -> str:
    rendered = [
        render_args(list(s.args), {**values, "attempt": "{attempt}"}, f"{where}: step {s.name!r}") for s in steps
    ]
    identity = {"kind": kind, "steps": rendered, "json": [s.json for s in steps], "files": files, "env": env}
    return hashlib.sha256(json.dumps(identity, sort_keys=True).encode()).hexdigest()[:16]


def _resources(doc: dict[str, Any], preset: Resources, where: str) -> Resources:
    raw = dict(_table(doc, "resources", where))
    num_cpus = float(raw.pop("num_cpus", preset.num_cpus))
    memory_mb = int(raw.pop("memory_mb", preset.memory_mb))
    if num_cpus <= 0 or memory_mb <= 0:
        raise ConfigError(f"{where}: resources num_cpus and memory_mb must be positive")
    custom = dict(preset.custom)
    for name, amount in raw.items():
        if not isinstance(amount, int | float) or isinstance(amount, bool) or amount <= 0:
            raise ConfigError(f"{where}: resources.{name} = {amount!r}; a custom resource needs a positive amount")
        custom[name] = float(amount)
    return Resources(num_cpus=num_cpus, memory_mb=memory_mb, custom=custom)


def _table(doc: dict[str, Any], key: str, where: str) -> dict[str, Any]:
    value = doc.get(key, {})
    if not isinstance(value, dict):
        raise ConfigError(f"{where}: {key} must be a table ([{key}])")
    return value


def _number(doc: dict[str, Any], key: str, default: Any, kind: type, where: str, minimum: float | None = None) -> Any:
    value = doc.get(key, default)
    if isinstance(value, bool) or not isinstance(value, int | float) or (kind is int and not isinstance(value, int)):
        raise ConfigError(f"{where}: {key} = {value!r} must be {'an integer' if kind is int else 'a number'}")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{where}: {key} = {value!r} must be at least {minimum:g}")
    return kind(value)


def _check_keys(table: dict[str, Any], known: set[str], where: str) -> None:
    for key in table:
        if key not in known:
            close = difflib.get_close_matches(key, known, n=1)
            hint = f"; did you mean {close[0]!r}?" if close else f"; known: {sorted(known)}"
            raise ConfigError(f"{where}: unknown key {key!r}{hint}")
