"""Rows of the results table and the Markdown summary: pass/fail per cell and the aggregate.

Thresholds are applied here, when the table is written, not when a cell runs: changing a
limit and running the sweep again re-scores every finished cell without running it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fnmatch import fnmatch
from typing import Any

from host.sweep.matrix import ROW_COLUMNS, Cell, Matrix
from host.sweep.thresholds import evaluate


def cell_row(matrix: Matrix, cell: Cell, record: dict[str, Any]) -> dict[str, Any]:
    """One row: the cell's labels, its outcome and every metric its steps reported."""
    metrics = record.get("metrics", {})
    if record["outcome"] == "error":
        status, reasons = "error", [f"{record['error_kind']}: {record['error']}"]
    else:
        reasons = evaluate(matrix.thresholds, cell.labels, metrics)
        if record["exit_code"] != 0:
            reasons.insert(0, f"exit status {record['exit_code']}: {record['error']}")
        status = "fail" if reasons else "pass"
    row: dict[str, Any] = {"cell": cell.key, "index": cell.index, **cell.labels}
    row.update(
        seed=cell.seed,
        status=status,
        reasons="; ".join(reasons),
        attempts=record["attempts"],
        exit_code=record["exit_code"],
        error=record["error"],
        elapsed_s=record["elapsed_s"],
        cpu_s=record["cpu_s"],
        host=record["host"],
    )
    row.update(metrics)
    return row


def table_columns(matrix: Matrix, rows: Sequence[dict[str, Any]]) -> list[str]:
    fixed = list(ROW_COLUMNS[:2]) + [a for a in matrix.axes if a != "seed"] + list(ROW_COLUMNS[2:])
    metrics = sorted({key for row in rows for key in row} - set(fixed))
    return fixed + metrics


def comparable(row: dict[str, Any], timing_columns: Sequence[str]) -> dict[str, Any]:
    """``row`` without the columns that measure time or place (they differ between any two runs)."""
    return {k: v for k, v in row.items() if not any(fnmatch(k, pattern) for pattern in timing_columns)}


def markdown_summary(matrix: Matrix, rows: Sequence[dict[str, Any]], wall_s: float, backend: str) -> str:
    """The human summary: totals, thresholds, pass rate and means per axis value, one line per cell."""
    total = len(matrix.cells)
    counts = {s: sum(r["status"] == s for r in rows) for s in ("pass", "fail", "error")}
    cpu = sum(float(r["cpu_s"] or 0) for r in rows)
    lines = [
        f"# Sweep `{matrix.name}` ({matrix.kind.name})",
        "",
        f"{total} cells: **{counts['pass']} pass, {counts['fail']} fail, {counts['error']} error**"
        + (f", {total - len(rows)} not run yet (run the same command again to resume)" if len(rows) < total else "")
        + f". Backend {backend}; this run {wall_s:.1f} s wall; cells {cpu:.1f} s CPU in total.",
        "",
    ]
    if matrix.thresholds:
        lines += ["Thresholds: " + "; ".join(t.describe() for t in matrix.thresholds) + ".", ""]
    shown = list(dict.fromkeys(t.metric for t in matrix.thresholds))[:4]
    lines += _aggregate(matrix, rows, shown)
    axes = [a for a in matrix.axes if a != "seed"]
    lines += ["## Cells", "", "| # | " + " | ".join(axes + ["seed", "status"] + shown + ["why"]) + " |"]
    lines.append("|" + "---|" * (len(axes) + len(shown) + 4))
    for row in sorted(rows, key=lambda r: int(r["index"])):
        values = [str(row.get(a)) for a in axes] + [str(row["seed"]), row["status"]]
        values += [_number(row.get(m)) for m in shown] + [str(row["reasons"]).replace("|", "/")[:160]]
        lines.append(f"| {row['index']} | " + " | ".join(values) + " |")
    return "\n".join(lines) + "\n"


def _aggregate(matrix: Matrix, rows: Sequence[dict[str, Any]], shown: list[str]) -> list[str]:
    lines = [
        "## By axis value",
        "",
        "| axis | value | cells | pass | fail | error | " + " | ".join(f"mean {m}" for m in shown) + " |",
    ]
    lines.append("|" + "---|" * (6 + len(shown)))
    for axis, values in matrix.axes.items():
        if len(values) < 2:
            continue
        for value in values:
            group = [r for r in rows if str(r.get(axis)) == str(value)]
            if not group:
                continue
            stats = [sum(r["status"] == s for r in group) for s in ("pass", "fail", "error")]
            means = [_number(_mean([r.get(m) for r in group])) for m in shown]
            lines.append(f"| {axis} | {value} | {len(group)} | " + " | ".join(map(str, stats + means)) + " |")
    return lines + [""]


def _mean(values: list[Any]) -> float | None:
    numbers = [float(v) for v in values if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)]
    return sum(numbers) / len(numbers) if numbers else None


def _number(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.4g}"
    return "" if value is None else str(value)
