"""What a bundle refuses: other people's directories, half-written re-saves, paths out of the
bundle, swapped roles, edited tables with re-computed checksums, malformed manifests."""

from __future__ import annotations

import hashlib
import json
import multiprocessing
import os
import shutil
from pathlib import Path

import numpy as np
import pytest

from edge.errors import BundleError
from edge.hysteresis.lut import read_table, write_table
from edge.hysteresis.table import LookupTable
from edge.runtime.bundle import load_bundle, resolve_release
from models_export.bundle import check_save_target, update_manifest, write_bundle
from tests.strategies import random_dpi, random_preisach


def models(seed=1, factory=random_dpi):
    model = factory(np.random.default_rng(seed))
    model.reset(model.input_range[0], "descending")
    inverse = model.inverse()
    inverse.reset(inverse.input_range[0], "descending")
    return model, inverse


def save(directory: Path, seed=1, **kwargs) -> Path:
    return write_bundle(directory, *models(seed), units=("bar", "mm"), **kwargs)


def rewrite_manifest(release: Path, change) -> None:
    """Edit the manifest as an attacker or a careless hand would, re-hashing what it lists."""
    manifest = json.loads((release / "manifest.json").read_text())
    change(manifest)
    for name, entry in manifest["files"].items() if isinstance(manifest.get("files"), dict) else ():
        if isinstance(entry, dict) and (release / name).is_file():
            entry["sha256"] = hashlib.sha256((release / name).read_bytes()).hexdigest()
    (release / "manifest.json").write_text(json.dumps(manifest))


# -- the destination of --save -----------------------------------------------------------------


def test_saving_over_a_directory_that_is_not_a_bundle_is_refused_and_nothing_is_touched(tmp_path):
    mine = tmp_path / "thesis"
    (mine / "chapter").mkdir(parents=True)
    (mine / "notes.txt").write_text("years of work")
    with pytest.raises(BundleError, match="not a pmactl bundle.*nothing written") as info:
        save(mine)
    assert "\n" not in str(info.value)
    assert sorted(p.name for p in mine.iterdir()) == ["chapter", "notes.txt"]
    assert (mine / "notes.txt").read_text() == "years of work"


def test_saving_over_a_regular_file_is_refused_and_the_file_stays(tmp_path):
    target = tmp_path / "results.csv"
    target.write_text("t,u,y\n")
    with pytest.raises(BundleError, match="not a directory"):
        save(target)
    assert target.read_text() == "t,u,y\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]


def test_an_empty_directory_and_an_existing_bundle_are_accepted(tmp_path):
    (tmp_path / "empty").mkdir()
    save(tmp_path / "empty")
    first = load_bundle(tmp_path / "empty").release_id
    save(tmp_path / "empty", seed=2)
    second = load_bundle(tmp_path / "empty")
    assert second.release_id != first
    assert os.readlink(tmp_path / "empty" / "previous") == f"releases/{first}"
    assert check_save_target(tmp_path / "empty") == tmp_path / "empty"


def test_old_releases_are_pruned_but_current_and_previous_stay(tmp_path):
    for seed in range(4):
        save(tmp_path / "b", seed=seed, keep=2)
    releases = sorted(p.name for p in (tmp_path / "b" / "releases").iterdir())
    assert len(releases) == 2
    assert {Path(os.readlink(tmp_path / "b" / n)).name for n in ("current", "previous")} == set(releases)


# -- atomic re-save -------------------------------------------------------------------------------


def _load_loop(directory: str, ready, stop, counts) -> None:
    failures = loads = 0
    while not stop.is_set() or loads < 10:
        try:
            load_bundle(directory)
        except Exception:  # noqa: BLE001 - every failure counts, whatever it is
            failures += 1
        loads += 1
        ready.set()
    counts.put((loads, failures))


def test_a_reader_never_sees_a_half_written_bundle_during_re_saves(tmp_path):
    directory = save(tmp_path / "b")
    context = multiprocessing.get_context("spawn")
    ready, stop, counts = context.Event(), context.Event(), context.Queue()
    reader = context.Process(target=_load_loop, args=(str(directory), ready, stop, counts))
    reader.start()
    try:
        assert ready.wait(timeout=60)
        for seed in range(30):
            save(directory, seed=seed, keep=2)
    finally:
        stop.set()
        loads, failures = counts.get(timeout=60)
        reader.join(timeout=30)
    assert loads >= 10 and failures == 0


def test_a_release_pruned_while_it_is_read_is_followed_to_the_new_current(tmp_path, monkeypatch):
    """The race the reader above hits by chance, made certain: two re-saves prune the release a
    load resolved, between its checksums and its table reads."""
    import edge.runtime.bundle as loader

    directory = save(tmp_path / "b", seed=0)
    first = resolve_release(directory)
    real_read_table, calls = loader.read_table, []

    def read_table_after_two_re_saves(path):
        if not calls:
            save(directory, seed=1, keep=2)
            save(directory, seed=2, keep=2)
            assert not first.exists()  # pruned: neither current nor previous any more
        calls.append(path)
        return real_read_table(path)

    monkeypatch.setattr(loader, "read_table", read_table_after_two_re_saves)
    bundle = load_bundle(directory)
    assert bundle.path == resolve_release(directory) != first
    assert calls[0].parent == first


def test_a_broken_current_release_is_reported_at_once_not_retried(tmp_path, monkeypatch):
    import edge.runtime.bundle as loader

    directory = save(tmp_path / "b")
    (resolve_release(directory) / "forward.npz").unlink()
    monkeypatch.setattr(loader.time, "sleep", lambda s: pytest.fail("retried a bundle nobody rewrites"))
    with pytest.raises(BundleError, match="forward.npz listed in the manifest is missing; re-copy"):
        load_bundle(directory)


# -- paths, roles, malformed manifests ----------------------------------------------------------


@pytest.mark.parametrize("name", ["../outside.npz", "/tmp/outside.npz", "sub/forward.npz", ".."])
def test_manifest_names_outside_the_bundle_are_refused(tmp_path, name):
    release = resolve_release(save(tmp_path / "b"))
    outside = tmp_path / "outside.npz"
    shutil.copyfile(release / "forward.npz", outside)

    def point_out(manifest):
        manifest["files"][name] = manifest["files"].pop("forward.npz")
        manifest["files"][name]["sha256"] = hashlib.sha256(outside.read_bytes()).hexdigest()

    rewrite_manifest(release, point_out)
    with pytest.raises(BundleError, match="not a plain name inside the bundle"):
        load_bundle(tmp_path / "b")


def test_a_symlink_out_of_the_bundle_is_refused(tmp_path):
    release = resolve_release(save(tmp_path / "b"))
    shutil.move(release / "forward.npz", tmp_path / "forward.npz")
    (release / "forward.npz").symlink_to(tmp_path / "forward.npz")
    with pytest.raises(BundleError, match="symbolic link"):
        load_bundle(tmp_path / "b")


def test_swapped_roles_are_refused(tmp_path):
    release = resolve_release(save(tmp_path / "b"))

    def swap(manifest):
        files = manifest["files"]
        files["forward.npz"]["role"], files["inverse.npz"]["role"] = "inverse", "forward"

    rewrite_manifest(release, swap)
    with pytest.raises(BundleError, match="roles swapped"):
        load_bundle(tmp_path / "b")


def test_tables_that_are_not_each_others_inverse_are_refused(tmp_path):
    """A consistent-looking manifest whose inverse table belongs to another model."""
    release = resolve_release(save(tmp_path / "b"))
    _, other_inverse = models(seed=7, factory=random_preisach)
    write_table(other_inverse.compile(), release / "inverse.npz")
    lo, hi = other_inverse.input_range
    rewrite_manifest(release, lambda m: m["model"].update(reachable_output_range=[lo, hi]))
    with pytest.raises(BundleError, match="not each other's inverse"):
        load_bundle(tmp_path / "b")


@pytest.mark.parametrize("manifest", [[], ["files"], {"format": "pmactl-bundle", "format_version": 2, "files": []}])
def test_a_manifest_of_the_wrong_shape_is_one_line(tmp_path, manifest):
    release = resolve_release(save(tmp_path / "b"))
    (release / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(BundleError, match="not an object|must map file names") as info:
        load_bundle(tmp_path / "b")
    assert "\n" not in str(info.value)


def test_a_table_scaled_and_re_hashed_is_refused_by_its_golden_vectors(tmp_path):
    release = resolve_release(save(tmp_path / "b"))
    table = read_table(release / "inverse.npz")
    # the DPI inverse's output end points (anchors y0, y1) 1 % larger: same input range, 1 % more pressure
    scaled = dict(table.arrays)
    scaled["0.anchors"] = table.arrays["0.anchors"] * np.array([1.0, 1.01, 1.0, 1.01])
    write_table(LookupTable(table.kind, table.stages, scaled, table.input_range, table.meta), release / "inverse.npz")
    rewrite_manifest(release, lambda m: None)
    with pytest.raises(BundleError, match="golden vectors.*changed after export"):
        load_bundle(tmp_path / "b")


def test_update_manifest_makes_a_new_release_and_refuses_pmactl_fields(tmp_path):
    directory = save(tmp_path / "b")
    before = load_bundle(directory)
    update_manifest(directory, quantisation={"weights": "int8", "max_error_bar": 0.002})
    after = load_bundle(directory)
    assert after.manifest["quantisation"]["weights"] == "int8"
    assert after.release_id != before.release_id and after.manifest["derived_from"] == before.manifest_sha256
    assert load_bundle(before.path).release_id == before.release_id  # the old release is intact
    with pytest.raises(BundleError, match="files are written by pmactl"):
        update_manifest(directory, files={})


def test_provenance_records_the_training_data_hash(tmp_path):
    data = tmp_path / "train.csv"
    data.write_text("t,u,y\n0,0,0\n")
    bundle = load_bundle(save(tmp_path / "b", training_data=[data]))
    record = bundle.manifest["provenance"]
    assert record["training_data"] == [
        {"file": "train.csv", "sha256": hashlib.sha256(data.read_bytes()).hexdigest(), "bytes": data.stat().st_size}
    ]
    assert record["pmactl_version"]
    assert bundle.identity["bundle_id"] == hashlib.sha256((bundle.path / "manifest.json").read_bytes()).hexdigest()


def test_fit_save_onto_a_users_file_is_one_line_and_keeps_the_file(tmp_path, capsys):
    from host.cli import main
    from host.examples import example_path

    target = tmp_path / "results.csv"
    target.write_text("t,u,y\n")
    status = main(["fit", "--model", "pi", "--train", str(example_path("train")), "--save", str(target)])
    err = capsys.readouterr().err
    assert status == 2 and "not a directory" in err and err.count("\n") == 1
    assert target.read_text() == "t,u,y\n" and sorted(p.name for p in tmp_path.iterdir()) == ["results.csv"]


def test_a_bundle_in_the_previous_flat_layout_still_loads(tmp_path):
    """What pmactl wrote before releases existed: manifest v1 and tables in one directory."""
    release = resolve_release(save(tmp_path / "b"))
    flat = tmp_path / "flat"
    flat.mkdir()
    for name in ("forward.npz", "inverse.npz"):
        shutil.copyfile(release / name, flat / name)
    manifest = json.loads((release / "manifest.json").read_text())
    manifest["format_version"] = 1
    del manifest["files"]["golden.npz"]
    (flat / "manifest.json").write_text(json.dumps(manifest))
    assert load_bundle(flat).path == flat
    with pytest.raises(BundleError, match="older single-directory layout"):
        save(flat)  # never rewritten in place: nothing of it is moved


# -- a folder that merely has a releases/ is not a store (review finding: data loss) --------


def test_a_user_folder_with_releases_is_refused_and_nothing_of_it_is_deleted(tmp_path):
    folder = tmp_path / "proj2"
    old = folder / "releases" / "old"
    old.mkdir(parents=True)
    (old / "manifest.json").write_text('{"title": "my thesis"}')
    (old / "thesis.tex").write_text("\\documentclass{article}")
    model, inverse = models()
    for _ in range(6):
        with pytest.raises(BundleError, match="not a pmactl bundle"):
            write_bundle(folder, model, inverse, units=("bar", "mm"))
    assert (old / "thesis.tex").read_text() == "\\documentclass{article}"
    assert sorted(p.name for p in folder.rglob("*")) == ["manifest.json", "old", "releases", "thesis.tex"]


def test_prune_keeps_entries_in_a_store_that_are_not_pmactl_releases(tmp_path):
    model, inverse = models()
    write_bundle(tmp_path / "b", model, inverse, units=("bar", "mm"))
    foreign = {
        "notes": {"format": "pmactl-bundle", "created_utc": "2000-01-01"},  # not a release id
        "0123456789abcdef": {"format": "someone-else", "created_utc": "2000-01-01"},  # not our format
    }
    for name, manifest in foreign.items():
        (tmp_path / "b" / "releases" / name).mkdir()
        (tmp_path / "b" / "releases" / name / "manifest.json").write_text(json.dumps(manifest))
    for seed in range(2, 9):
        write_bundle(tmp_path / "b", *models(seed), units=("bar", "mm"))
    names = {p.name for p in (tmp_path / "b" / "releases").iterdir()}
    assert set(foreign) <= names and len(names - set(foreign)) == 5


def test_a_regular_file_named_current_is_never_replaced(tmp_path):
    folder = tmp_path / "proj"
    (folder / "releases").mkdir(parents=True)
    (folder / "current").write_text("my current notes")
    with pytest.raises(BundleError):
        write_bundle(folder, *models(), units=("bar", "mm"))
    assert not (folder / "current").is_symlink() and (folder / "current").read_text() == "my current notes"


def test_a_regular_file_named_previous_in_a_store_is_never_replaced(tmp_path):
    write_bundle(tmp_path / "b", *models(1), units=("bar", "mm"))
    (tmp_path / "b" / "previous").write_text("mine")
    with pytest.raises(BundleError, match="previous: is not a pmactl link"):
        write_bundle(tmp_path / "b", *models(2), units=("bar", "mm"))
    assert (tmp_path / "b" / "previous").read_text() == "mine"
