"""Lookup-table form and bundles: parity with the reference models, integrity checks."""

from __future__ import annotations

import json

import numpy as np
import pytest

from edge.errors import BundleError
from edge.hysteresis.lut import CompiledModel, load_compiled, read_table, write_table
from edge.runtime.bundle import load_bundle
from models_export.bundle import write_bundle
from tests.conftest import random_walk
from tests.strategies import random_dpi, random_mpi, random_pi, random_preisach

FACTORIES = {"pi": random_pi, "mpi": random_mpi, "dpi": random_dpi, "preisach": random_preisach}


def in_range_walk(model, rng, n=400):
    lo, hi = model.memory_range
    return random_walk(rng, n, lo, hi, 0.2 * (hi - lo))


@pytest.mark.parametrize("kind", FACTORIES)
@pytest.mark.parametrize("direction", ["forward", "inverse"])
def test_table_file_reproduces_the_reference_model(tmp_path, kind, direction):
    rng = np.random.default_rng(11)
    model = FACTORIES[kind](rng)
    model.reset(model.memory_range[0], "descending")
    if direction == "inverse":
        model = model.inverse()
        model.reset(model.input_range[0], "descending")
    compiled = load_compiled(write_table(model.compile(), tmp_path / "t.npz"))
    u = in_range_walk(model, rng)
    np.testing.assert_allclose(compiled.simulate(u), model.simulate(u), atol=1e-10)


def test_table_is_loaded_without_pickle(tmp_path):
    path = write_table(random_dpi(np.random.default_rng(0)).compile(), tmp_path / "t.npz")
    with np.load(path, allow_pickle=False) as data:
        assert json.loads(str(data["__table__"]))["kind"] == "dpi"


def test_compiled_reset_returns_to_the_compiled_state():
    model = random_preisach(np.random.default_rng(4))
    model.reset(0.5, "centered")
    compiled = CompiledModel(model.compile())
    u = in_range_walk(model, np.random.default_rng(5), 100)
    first = compiled.simulate(u)
    compiled.reset()
    np.testing.assert_array_equal(compiled.simulate(u), first)


def test_garbage_table_gives_a_bundle_error(tmp_path):
    path = tmp_path / "t.npz"
    path.write_bytes(b"not a zip")
    with pytest.raises(BundleError, match="not a pmactl lookup table"):
        read_table(path)


def make_bundle(tmp_path, name="bundle"):
    model = random_dpi(np.random.default_rng(1))
    model.reset(model.input_range[0], "descending")
    return write_bundle(tmp_path / name, model, model.inverse(), units=("bar", "mm"))


def test_bundle_round_trip_and_manifest(tmp_path):
    bundle = load_bundle(make_bundle(tmp_path))
    assert bundle.manifest["model"]["units"] == {"input": "bar", "output": "mm"}
    u = 0.5 * sum(bundle.forward.input_range)
    assert bundle.inverse.step(bundle.forward.step(u)) == pytest.approx(u)


@pytest.mark.parametrize("kind", FACTORIES)
def test_every_model_kind_passes_the_role_and_golden_checks(tmp_path, kind):
    model = FACTORIES[kind](np.random.default_rng(3))
    model.reset(model.memory_range[0], "descending")
    inverse = model.inverse()
    inverse.reset(inverse.input_range[0], "descending")
    bundle = load_bundle(write_bundle(tmp_path / kind, model, inverse, units=("bar", "mm")))
    assert bundle.manifest["model"]["kind"] == kind and "golden.npz" in bundle.manifest["files"]


def test_tampered_bundle_is_refused(tmp_path):
    release = load_bundle(make_bundle(tmp_path)).path
    with (release / "inverse.npz").open("ab") as handle:
        handle.write(b"x")
    with pytest.raises(BundleError, match="checksum mismatch"):
        load_bundle(tmp_path / "bundle")


def test_missing_manifest_is_refused(tmp_path):
    with pytest.raises(BundleError, match="no manifest.json"):
        load_bundle(tmp_path)


def test_failed_write_keeps_the_old_bundle(tmp_path):
    directory = make_bundle(tmp_path)
    before = load_bundle(directory).manifest_sha256

    class Broken:
        kind = "broken"
        input_range = (0.0, 1.0)

        def compile(self):
            raise RuntimeError("export failed")

    with pytest.raises(RuntimeError):
        write_bundle(directory, Broken(), Broken())  # type: ignore[arg-type]
    assert load_bundle(directory).manifest_sha256 == before
    assert [p.name for p in tmp_path.iterdir()] == ["bundle"]
    assert len(list((directory / "releases").iterdir())) == 1  # no staging left behind


def test_a_failed_first_write_leaves_nothing_behind(tmp_path):
    class Broken:
        kind = "broken"
        input_range = (0.0, 1.0)

        def compile(self):
            raise RuntimeError("export failed")

    with pytest.raises(RuntimeError):
        write_bundle(tmp_path / "new", Broken(), Broken())  # type: ignore[arg-type]
    assert list(tmp_path.iterdir()) == []
