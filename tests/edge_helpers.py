"""Shared set-up for the edge runtime tests: the example rig config and a fitted bundle."""

from __future__ import annotations

import tomllib
from pathlib import Path

from edge.control.reference import parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.config import RigConfig, config_from_dict
from edge.runtime.run import EdgeRuntime
from host.data import load_measurement
from host.examples import example_path
from host.workflow import make_estimator, save_bundle

REPO = Path(__file__).resolve().parents[1]
HIL_RIG = REPO / "docs" / "examples" / "hil-rig.toml"  # a link to hil/configs/hil-rig.toml
SEED_000_SINE = "sine:amplitude=30,frequency=0.2,offset=40"


def rig_config(example: str = "hil-rig.toml", **sections: dict) -> RigConfig:
    """``docs/examples/<example>`` with ``sections`` merged in (e.g. loop={"rate_hz": 200}).

    ``rig={"io": URL}`` (the first config format) sets the URL of the example's first bus;
    ``buses={"i2c": {...}}`` and the like merge one level deeper."""
    path = HIL_RIG.parent / example
    raw = tomllib.loads(path.read_text())
    legacy = sections.pop("rig", None)
    if legacy and "io" in legacy:
        first = next(iter(raw["buses"]))
        raw["buses"][first]["url"] = legacy["io"]
    for name, values in sections.items():
        if name in ("buses", "devices", "channels"):
            for key, table in values.items():
                raw[name].setdefault(key, {}).update(table)
        else:
            raw.setdefault(name, {}).update(values)
    return config_from_dict(raw, str(path))


def fit_bundle(directory: Path, model: str = "preisach") -> Path:
    """What ``pmactl fit --model preisach --train pma_triangles.csv --units bar,mm --save`` writes."""
    train = load_measurement(example_path("train"))
    estimator = make_estimator(model).fit(train.u, train.y)
    return save_bundle(estimator, train, directory, ("bar", "mm"), {"model": model})


def runtime(bundle_dir: Path | None, reference: str = SEED_000_SINE, config: RigConfig | None = None, **kwargs):
    bundle = load_bundle(bundle_dir) if bundle_dir is not None else None
    return EdgeRuntime(config or rig_config(), bundle, parse_reference(reference), **kwargs)
