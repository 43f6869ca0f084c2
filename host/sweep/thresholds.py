"""Pass/fail per cell: the limits a matrix states on metric columns.

``[thresholds]`` maps a metric column to a limit or a list of limits::

    "run.rms_error" = { max = 4.0 }
    "run.faults.n" = { max = 0 }
    "fit.tests.0.rmse_pct_pp" = [{ max = 15, where = { model = "pi" } }, { max = 5 }]

A limit has ``min``, ``max`` and/or ``equals`` (``equals = "{effect}"`` compares with the
cell's own label); ``where`` restricts it to cells whose axis labels match. A missing or
non-numeric metric fails a numeric limit (never silently passes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from edge.errors import ConfigError
from host.sweep.template import render_text


@dataclass(frozen=True)
class Threshold:
    metric: str
    minimum: float | None = None
    maximum: float | None = None
    equals: object = None
    where: tuple[tuple[str, str], ...] = ()

    def applies(self, labels: dict[str, Any]) -> bool:
        return all(str(labels.get(axis)) == value for axis, value in self.where)

    def check(self, metrics: dict[str, Any], labels: dict[str, Any]) -> str | None:
        """``None`` when the cell passes, else the reason in a few words."""
        if self.metric not in metrics or metrics[self.metric] is None:
            return f"{self.metric} missing"
        value = metrics[self.metric]
        if self.equals is not None:
            expected = self.equals
            if isinstance(expected, str):  # "{effect}": the cell's own label, e.g. the hidden effect to name
                expected = render_text(expected, {k: str(v) for k, v in labels.items()}, strict=False, where="")
            return None if value == expected else f"{self.metric}={value!r} != {expected!r}"
        if isinstance(value, bool) or not isinstance(value, int | float) or math.isnan(value):
            return f"{self.metric}={value!r} is not a number"
        if self.maximum is not None and value > self.maximum:
            return f"{self.metric}={value:.4g} > {self.maximum:g}"
        if self.minimum is not None and value < self.minimum:
            return f"{self.metric}={value:.4g} < {self.minimum:g}"
        return None

    def describe(self) -> str:
        parts = []
        if self.minimum is not None:
            parts.append(f">= {self.minimum:g}")
        if self.maximum is not None:
            parts.append(f"<= {self.maximum:g}")
        if self.equals is not None:
            parts.append(f"== {self.equals!r}")
        scope = f" where {', '.join(f'{k}={v}' for k, v in self.where)}" if self.where else ""
        return f"{self.metric} {' and '.join(parts)}{scope}"


def parse_thresholds(raw: object, axes: set[str], where: str) -> list[Threshold]:
    if not isinstance(raw, dict):
        raise ConfigError(f'{where}: thresholds must be a table: "metric" = {{ max = ... }}')
    out = []
    for metric, limits in raw.items():
        for limit in limits if isinstance(limits, list) else [limits]:
            out.append(_parse_limit(metric, limit, axes, f"{where}: thresholds.{metric}"))
    return out


def evaluate(thresholds: list[Threshold], labels: dict[str, Any], metrics: dict[str, Any]) -> list[str]:
    """Reasons the cell fails its thresholds (empty: it passes)."""
    return [reason for t in thresholds if t.applies(labels) and (reason := t.check(metrics, labels)) is not None]


def _parse_limit(metric: str, limit: object, axes: set[str], here: str) -> Threshold:
    if not isinstance(limit, dict) or not limit:
        raise ConfigError(f"{here}: give a table such as {{ max = 4.0 }} (keys min, max, equals, where)")
    unknown = set(limit) - {"min", "max", "equals", "where"}
    if unknown:
        raise ConfigError(f"{here}: unknown key(s) {sorted(unknown)}; use min, max, equals, where")
    bounds = {}
    for key in ("min", "max"):
        if key in limit:
            value = limit[key]
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"{here}: {key} = {value!r} must be a number")
            bounds[key] = float(value)
    if "min" in bounds and "max" in bounds and bounds["min"] > bounds["max"]:
        raise ConfigError(f"{here}: min {bounds['min']:g} > max {bounds['max']:g}")
    scope = limit.get("where", {})
    if not isinstance(scope, dict) or not set(scope) <= axes:
        raise ConfigError(f"{here}: where must name axes of this matrix ({sorted(axes)}), got {scope!r}")
    if not bounds and "equals" not in limit:
        raise ConfigError(f"{here}: a limit needs min, max or equals")
    return Threshold(
        metric=metric,
        minimum=bounds.get("min"),
        maximum=bounds.get("max"),
        equals=limit.get("equals"),
        where=tuple(sorted((k, str(v)) for k, v in scope.items())),
    )
