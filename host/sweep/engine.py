"""Run a matrix: skip finished cells, keep the backend busy, retry per policy, journal every result.

The loop keeps at most ``backend.capacity`` attempts in flight (so "running" on the progress
bar is what runs), puts a retried cell at the front of the queue, and journals each finished
cell before it counts it. Ctrl-C or SIGTERM stops the running cells (SIGTERM to their process
groups locally, ``ray.cancel`` on Ray); nothing they half-did is recorded, so the next run
picks them up again.
"""

from __future__ import annotations

import math
import shutil
import sys
import time
import tomllib
from collections import deque
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from edge.errors import ConfigError
from host.sweep.backends import Backend
from host.sweep.journal import JOURNAL, Journal, write_table, write_text
from host.sweep.matrix import Cell, Matrix
from host.sweep.report import cell_row, markdown_summary, table_columns

POLL_S = 0.5
REWRITE_EVERY_S = 2.0
SAVED_MATRIX = "matrix.sweep.toml"


@dataclass
class SweepResult:
    out: Path
    rows: list[dict[str, Any]]
    ran: int  # cells finished in this run
    resumed: int  # cells taken from an earlier run's journal
    retried: int  # failed attempts that were run again
    wall_s: float
    interrupted: bool
    backend: str
    tables: list[Path] = field(default_factory=list)

    def counts(self) -> dict[str, int]:
        return {s: sum(r["status"] == s for r in self.rows) for s in ("pass", "fail", "error")}


def attempt_spec(matrix: Matrix, cell: Cell, attempt: int, backend: Backend, out: Path) -> dict[str, Any]:
    """What a worker needs to run one attempt of ``cell``: plain data, picklable, paths resolved."""
    return {
        "key": cell.key,
        "attempt": attempt,
        "steps": cell.commands(attempt, str(matrix.path)),
        "files": cell.files,
        "env": matrix.env,
        "timeout_s": matrix.timeout_s,
        "threads": math.ceil(matrix.resources.num_cpus),
        "workdir_root": str((out / "cells").resolve()) if backend.shares_filesystem else None,
        "die_with_parent": backend.orphan_guard,
    }


def run_sweep(
    matrix: Matrix, out: Path, backend: Backend, *, progress: bool = False, retry_errors: bool = False
) -> SweepResult:
    """Run every cell of ``matrix`` not finished in ``out`` yet; write the table and summary there."""
    started = time.monotonic()
    check_out(matrix, out)
    with Journal(out) as journal:
        check_out(matrix, out)  # again under the lock: another sweep may have started here meanwhile
        _save_matrix(matrix, out)
        finished = journal.finished()
        todo = [
            c for c in matrix.cells
            if c.key not in finished or (retry_errors and finished[c.key]["outcome"] == "error")
        ]  # fmt: skip
        resumed = len(matrix.cells) - len(todo)
        bar = _progress_bar(len(matrix.cells), resumed, progress)
        queue: deque[tuple[Cell, int]] = deque((cell, 1) for cell in todo)
        inflight: dict[object, tuple[Cell, int]] = {}
        ran = retried = 0
        interrupted = False
        last_write = 0.0

        def tables() -> list[Path]:
            rows = _rows(matrix, journal)
            paths = write_table(out, rows, table_columns(matrix, rows))
            summary = markdown_summary(matrix, rows, time.monotonic() - started, backend.description)
            return [*paths, write_text(out / "summary.md", summary)]

        try:
            while queue or inflight:
                while queue and len(inflight) < backend.capacity:
                    cell, attempt = queue.popleft()
                    inflight[backend.submit(attempt_spec(matrix, cell, attempt, backend, out))] = (cell, attempt)
                for handle, outcome in backend.wait(list(inflight), POLL_S):
                    cell, attempt = inflight.pop(handle)
                    if outcome.get("error_kind") == "cancelled":
                        continue
                    final = _final(matrix, outcome, attempt)
                    journal.append(_record(cell, outcome, attempt, final))
                    if not final:
                        retried += 1
                        queue.appendleft((cell, attempt + 1))
                        continue
                    ran += 1
                    bar.update(1)
                _postfix(bar, matrix, journal, len(inflight))
                if time.monotonic() - last_write > REWRITE_EVERY_S:
                    tables()
                    last_write = time.monotonic()
        except KeyboardInterrupt:
            interrupted = True
            backend.cancel()
        finally:
            bar.close()
        paths = tables()
        rows = _rows(matrix, journal)
    return SweepResult(
        out, rows, ran, resumed, retried, time.monotonic() - started, interrupted, backend.description, paths
    )


def _final(matrix: Matrix, outcome: dict[str, Any], attempt: int) -> bool:
    """Is this attempt the cell's last? Yes unless it failed in a retryable way with retries left."""
    if outcome["outcome"] != "error":
        return True
    return not (outcome["error_kind"] in matrix.retry_on and attempt <= matrix.retries)


def _record(cell: Cell, outcome: dict[str, Any], attempt: int, final: bool) -> dict[str, Any]:
    record: dict[str, Any] = {
        "metrics": {}, "exit_code": None, "elapsed_s": None, "cpu_s": None, "host": None, "error_kind": None,
        "error": "",
    }  # fmt: skip
    record.update(outcome)
    record.update(
        key=cell.key,
        index=cell.index,
        labels=cell.labels,
        seed=cell.seed,
        attempts=attempt,
        final=final,
        finished_at=datetime.now(UTC).isoformat(timespec="seconds"),
    )
    return record


def _rows(matrix: Matrix, journal: Journal) -> list[dict[str, Any]]:
    finished = journal.finished()
    return [cell_row(matrix, c, finished[c.key]) for c in matrix.cells if c.key in finished]


def check_out(matrix: Matrix, out: Path) -> None:
    """Refuse an ``out`` whose files this sweep would overwrite: not a sweep's folder, or another matrix's.

    A sweep folder is one with a journal (``cells.jsonl``); its saved ``matrix.sweep.toml`` must
    have the same kind, axes and steps as ``matrix`` (thresholds, values and the like may change:
    the table is re-scored and changed cells run again). Raises :class:`ConfigError`.
    """
    if not out.is_dir():
        return  # missing: created by the journal; a file there: the journal names it
    others = [p for p in out.iterdir() if p.name != ".lock" and not _same_file(p, matrix.path)]
    if not others:
        return
    if not (out / JOURNAL).exists():
        raise ConfigError(
            f"{out}: is not empty and holds no sweep ({JOURNAL}); choose a new or empty --out so nothing there is "
            "overwritten"
        )
    saved = out / SAVED_MATRIX
    if not saved.exists() or _same_file(saved, matrix.path):
        return
    changed = [key for key in ("kind", "axes", "steps", "before") if _shape(saved, key) != _shape(matrix.path, key)]
    if changed:
        raise ConfigError(
            f"{out}: holds the results of another matrix ({saved}: {', '.join(changed)} differ from "
            f"{matrix.path}); use another --out, or run the matrix that made them (a copy is {saved})"
        )


def _shape(path: Path, key: str) -> object:
    """One top-level table of a matrix file as parsed TOML (``None`` if absent or unreadable)."""
    try:
        return tomllib.loads(path.read_text()).get(key)
    except (OSError, tomllib.TOMLDecodeError):
        return None


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.samefile(b)
    except OSError:
        return False


def _save_matrix(matrix: Matrix, out: Path) -> None:
    """A copy of the matrix beside its results (what produced this table)."""
    try:
        shutil.copyfile(matrix.path, out / SAVED_MATRIX)
    except shutil.SameFileError:
        pass


class _NoBar:
    def update(self, n: int) -> None: ...

    def close(self) -> None: ...


def _progress_bar(total: int, done: int, enabled: bool) -> Any:
    """tqdm on stderr: cells done of total, rate and time left; pass/fail/error/running as postfix."""
    if not enabled:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(
        total=total, initial=done, unit="cell", desc="sweep", file=sys.stderr, dynamic_ncols=True, smoothing=0.1
    )


def _postfix(bar: Any, matrix: Matrix, journal: Journal, running: int) -> None:
    if isinstance(bar, _NoBar):
        return
    rows = _rows(matrix, journal)
    counts = {s: sum(r["status"] == s for r in rows) for s in ("pass", "fail", "error")}
    bar.set_postfix_str(f"pass {counts['pass']} fail {counts['fail']} error {counts['error']} running {running}")
