"""The sweep's output folder: an append-only journal of results, a lock, the results table.

``cells.jsonl`` is the source of truth: one line per attempt, written and fsynced as it
finishes, so a sweep killed at any moment loses at most the cells that were running. A torn
last line (killed mid-write) is cut off on the next start. ``results.csv`` (and
``results.parquet`` when pyarrow is installed) are rewritten from it atomically (temporary
file + rename) after every cell, so a reader never sees half a table.

A second ``pmactl sweep`` on the same folder is refused while the first holds the lock.
"""

from __future__ import annotations

import csv
import fcntl
import json
import os
import warnings
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from edge.errors import ConfigError

JOURNAL = "cells.jsonl"
TABLE = "results.csv"
PARQUET = "results.parquet"


class Journal:
    """Append-only JSON-lines journal in ``out``; holds an exclusive lock on the folder while open."""

    def __init__(self, out: Path) -> None:
        self.out = out
        try:
            out.mkdir(parents=True, exist_ok=True)
            self._lock = open(out / ".lock", "a+")  # noqa: SIM115 - held for the journal's lifetime
        except OSError as exc:
            raise ConfigError(f"{out}: cannot create the output folder ({exc.strerror}); choose another --out") from exc
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock.close()
            raise ConfigError(
                f"{out}: another pmactl sweep is writing here; wait for it or use another --out"
            ) from None
        self.path = out / JOURNAL
        self._cut_torn_tail()
        self._fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)

    def records(self) -> list[dict[str, Any]]:
        """Every record written so far, oldest first."""
        if not self.path.exists():
            return []
        records = []
        with open(self.path) as f:
            for line in f:
                try:
                    records.append(json.loads(line))
                except ValueError:  # torn by an interrupt during this run's last write; cut on the next start
                    if line.endswith("\n"):
                        raise ConfigError(f"{self.path}: a line is corrupt; remove it to resume") from None
        return records

    def finished(self) -> dict[str, dict[str, Any]]:
        """The final record of every cell that has one, by cell key (the latest wins)."""
        return {r["key"]: r for r in self.records() if r.get("final")}

    def append(self, record: dict[str, Any]) -> None:
        """Write one record and force it to disk before returning."""
        os.write(self._fd, (json.dumps(record, sort_keys=True) + "\n").encode())
        os.fsync(self._fd)

    def close(self) -> None:
        os.close(self._fd)
        self._lock.close()

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _cut_torn_tail(self) -> None:
        """Drop a last line without its newline (the sweep was killed while writing it)."""
        if not self.path.exists():
            return
        data = self.path.read_bytes()
        keep = data.rfind(b"\n") + 1
        if keep != len(data):
            with open(self.path, "r+b") as f:
                f.truncate(keep)


def write_table(out: Path, rows: list[dict[str, Any]], columns: list[str]) -> list[Path]:
    """``results.csv`` (and ``results.parquet`` if pyarrow is importable), each replaced atomically."""
    written = [_atomic(out / TABLE, lambda f: _write_csv(f, rows, columns), text=True)]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    try:
        table = pa.Table.from_pylist([{c: row.get(c) for c in columns} for row in rows])
    except (pa.ArrowInvalid, pa.ArrowTypeError) as exc:  # a column mixing numbers and text
        warnings.warn(f"{out / PARQUET} not written ({exc}); {out / TABLE} has every row", stacklevel=2)
        return written
    written.append(_atomic(out / PARQUET, lambda f: pq.write_table(table, f), text=False))
    return written


def write_text(path: Path, text: str) -> Path:
    return _atomic(path, lambda f: f.write(text), text=True)


def read_table(path: Path) -> list[dict[str, str]]:
    """``results.csv`` as dicts of strings (what ``pandas.read_csv`` would load)."""
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _write_csv(f: Any, rows: Iterable[dict[str, Any]], columns: list[str]) -> None:
    writer = csv.DictWriter(f, fieldnames=columns, extrasaction="ignore", lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: _cell_text(row.get(c)) for c in columns})


def _cell_text(value: Any) -> Any:
    if value is None:
        return ""
    if isinstance(value, float):
        return repr(value)  # round-trips exactly: local and Ray rows compare equal as text
    return value


def _atomic(path: Path, write: Any, text: bool) -> Path:
    tmp = path.with_name(f".{path.name}.tmp")
    with open(tmp, "w", newline="") if text else open(tmp, "wb") as f:
        write(f)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)
    return path
