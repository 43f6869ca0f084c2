"""The plant families, found by scanning: every ``bench/plants/*_family.py`` module that defines
a ``SPEC`` (:class:`bench.plants.engine.FamilySpec`) is a family, in the order of its seeds (the
order the families were built in). A new family is a module here, not an edit to a list."""

from __future__ import annotations

import importlib
import pkgutil
from functools import cache

import bench.plants
from bench.plants.engine import FamilySpec


@cache
def specs() -> dict[str, FamilySpec]:
    """Every family's spec by name, oldest first; ``ValueError`` if two share a name or seeds."""
    found: list[FamilySpec] = []
    for module in pkgutil.iter_modules(bench.plants.__path__):
        if module.name.endswith("_family"):
            spec = getattr(importlib.import_module(f"bench.plants.{module.name}"), "SPEC", None)
            if isinstance(spec, FamilySpec):
                found.append(spec)
    found.sort(key=lambda spec: spec.seed_base)
    names = [spec.name for spec in found]
    duplicated = sorted({name for name in names if names.count(name) > 1})
    if duplicated:
        raise ValueError(f"two plant families named {', '.join(duplicated)}; rename one in bench/plants")
    return {spec.name: spec for spec in found}
