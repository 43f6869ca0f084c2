"""Signing never surprises: every command that writes a release into a bundle store re-signs it
with ``--key`` or says in one line that the new release is unsigned and how to sign it; a
manifest whose ``format_version`` this pmactl does not read is refused wherever one is read."""

from __future__ import annotations

import json
import shlex
from pathlib import Path

import pytest

from edge.errors import BundleError
from edge.runtime.bundle import load_bundle, resolve_release
from host.cli import main
from host.examples import example_path
from models_export.signing import signer_of
from tests.deploy_helpers import cli, keys, release_id
from tests.edge_helpers import HIL_RIG

EPOCHS = "5"  # enough for a real, loadable correction; its accuracy is tested in test_quantise


@pytest.fixture(scope="module")
def fitted(tmp_path_factory) -> Path:
    """A Preisach bundle (bar -> mm) fitted on the example recording, never modified: copy it."""
    root = tmp_path_factory.mktemp("fitted")
    bundle = root / "bundle"
    argv = ["fit", "--model", "preisach", "--train", str(example_path("train")), "--units", "bar,mm"]
    assert main([*argv, "--save", str(bundle)]) == 0
    return bundle


def copy_store(source: Path, target: Path) -> Path:
    import shutil

    shutil.copytree(source, target, symlinks=True)
    return target


def signed_store(fitted: Path, tmp_path: Path, capsys) -> tuple[Path, Path, Path]:
    private, public = keys(tmp_path / "keys")
    store = copy_store(fitted, tmp_path / "store")
    assert cli(capsys, "bundle", "sign", store, "--key", private)[0] == 0
    return store, private, public


def train_correction(store: Path, *extra: object) -> list[str]:
    return ["train", "--model", "correction", "--train", str(example_path("train")), "--bundle", str(store),
            "--epochs", EPOCHS, *map(str, extra)]  # fmt: skip


def test_a_correction_on_a_signed_store_without_key_says_once_how_to_sign(fitted, tmp_path, capsys):
    store, private, public = signed_store(fitted, tmp_path, capsys)
    before = release_id(store)
    status, out, err = cli(capsys, *train_correction(store))
    assert status == 0 and release_id(store) != before
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "UNSIGNED" in lines[0] and release_id(store) in lines[0]
    assert signer_of(store) is None
    with pytest.raises(BundleError, match="unsigned"):
        load_bundle(store, trusted_keys=[public])  # what a rig that trusts the key would do
    command = shlex.split(lines[0].split("sign it: ")[1].split(" (or pass")[0])
    assert command[:3] == ["pmactl", "bundle", "sign"] and Path(command[3]) == store
    command[command.index("--key") + 1] = str(private)  # the user's key file in place of its name
    assert main(command[1:]) == 0  # the printed command works as printed
    assert load_bundle(store, trusted_keys=[public]).correction_spec is not None


def test_a_correction_with_key_re_signs_the_new_release(fitted, tmp_path, capsys):
    store, private, public = signed_store(fitted, tmp_path, capsys)
    status, out, err = cli(capsys, *train_correction(store, "--key", private))
    assert status == 0 and err == ""
    assert f"signed the new release {release_id(store)}" in out
    assert load_bundle(store, trusted_keys=[public]).correction_spec is not None
    status, out, _ = cli(capsys, "bundle", "verify", store, "--trusted", public)
    assert status == 0 and "signed by" in out


def test_json_output_stays_one_object_and_the_notice_goes_to_stderr(fitted, tmp_path, capsys):
    store, _, _ = signed_store(fitted, tmp_path, capsys)
    status, out, err = cli(capsys, *train_correction(store, "--json"))
    assert status == 0 and json.loads(out)["model"] == "correction"
    assert len(err.strip().splitlines()) == 1 and "pmactl bundle sign" in err


def test_an_unsigned_store_stays_quiet_and_key_signs_it(fitted, tmp_path, capsys):
    store = copy_store(fitted, tmp_path / "store")
    status, _, err = cli(capsys, *train_correction(store))
    assert status == 0 and err == "" and signer_of(store) is None
    private, public = keys(tmp_path / "keys")
    assert cli(capsys, *train_correction(store, "--key", private))[0] == 0
    assert load_bundle(store, trusted_keys=[public]).signer is not None


@pytest.mark.parametrize("bad", ["missing.key", "pmactl.pub"])
def test_an_unusable_key_is_refused_before_training_and_nothing_changes(fitted, tmp_path, capsys, bad):
    store, private, _ = signed_store(fitted, tmp_path, capsys)
    before = release_id(store)
    status, out, err = cli(capsys, *train_correction(store, "--key", private.parent / bad))
    assert status == 2 and out == "" and len(err.strip().splitlines()) == 1 and bad in err
    assert release_id(store) == before and signer_of(store) is not None


def test_quantise_on_a_signed_store_re_signs_with_key_and_warns_without(fitted, tmp_path, capsys):
    store, private, public = signed_store(fitted, tmp_path, capsys)
    assert cli(capsys, *train_correction(store, "--key", private))[0] == 0
    calibration = str(example_path("test"))
    status, out, err = cli(capsys, "quantise", store, "--calibration", calibration, "--key", private)
    assert status == 0 and err == "" and "signed the new release" in out
    correction = load_bundle(store, trusted_keys=[public]).manifest["correction"]
    assert correction["quantisation"]["kept"] and correction["coverage"]["reference_mm"]  # coverage kept


def test_quantise_without_key_names_the_unsigned_release(fitted, tmp_path, capsys):
    store, private, _ = signed_store(fitted, tmp_path, capsys)
    assert cli(capsys, *train_correction(store, "--key", private))[0] == 0
    status, _, err = cli(capsys, "quantise", store, "--calibration", str(example_path("test")))
    lines = err.strip().splitlines()
    assert status == 0 and len(lines) == 1 and "UNSIGNED" in lines[0] and "pmactl bundle sign" in lines[0]
    assert signer_of(store) is None


def test_key_with_a_net_that_writes_no_bundle_is_one_line(tmp_path, capsys):
    private, _ = keys(tmp_path / "keys")
    argv = ["train", "--model", "hammerstein", "--train", str(example_path("train")), "--key", str(private)]
    status, _, err = cli(capsys, *argv)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "--key" in err and "drop --key" in err


def test_a_trained_net_saved_into_a_bundle_store_is_a_new_release_and_the_old_one_stays(fitted, tmp_path, capsys):
    store = copy_store(fitted, tmp_path / "store")
    before = resolve_release(store)
    argv = ["train", "--model", "hammerstein", "--train", str(example_path("train")), "--epochs", "2",
            "--save", str(store)]  # fmt: skip
    status, _, _ = cli(capsys, *argv)
    assert status == 0 and resolve_release(store) != before and before.is_dir()
    assert "forward" in json.loads((resolve_release(store) / "manifest.json").read_text())["nets"]


# -- format_version -------------------------------------------------------------------------


def with_format_version(fitted: Path, tmp_path: Path, version: object) -> Path:
    store = copy_store(fitted, tmp_path / "store")
    manifest_path = resolve_release(store) / "manifest.json"
    manifest = json.loads(manifest_path.read_text())
    manifest["format_version"] = version
    manifest_path.write_text(json.dumps(manifest, indent=2) + "\n")
    return store


COMMANDS = {
    "inspect": lambda store, tmp: ["bundle", "inspect", store],
    "verify": lambda store, tmp: ["bundle", "verify", store],
    "sign": lambda store, tmp: ["bundle", "sign", store, "--key", keys(tmp / "keys")[0]],
    "deploy": lambda store, tmp: ["deploy", store, tmp / "target"],
    "quantise": lambda store, tmp: ["quantise", store, "--calibration", example_path("test")],
    "train correction": lambda store, tmp: train_correction(store),
    "edge run": lambda store, tmp: [
        "edge",
        "run",
        "--config",
        HIL_RIG,
        "--bundle",
        store,
        "--reference",
        "const:value=20",
        "--duration",
        "0.1",
    ],  # fmt: skip
}


@pytest.mark.parametrize("command", list(COMMANDS))
def test_a_newer_format_version_is_refused_in_one_line_naming_it_and_the_fix(fitted, tmp_path, capsys, command):
    store = with_format_version(fitted, tmp_path, 3)
    before = sorted(p.name for p in (store / "releases").iterdir())
    status, out, err = cli(capsys, *COMMANDS[command](store, tmp_path))
    lines = err.strip().splitlines()
    assert status == 2 and len(lines) == 1, err
    assert "format_version 3" in lines[0] and "upgrade pmactl" in lines[0]
    assert sorted(p.name for p in (store / "releases").iterdir()) == before  # nothing written
    assert not (tmp_path / "target" / "current").exists()


@pytest.mark.parametrize("version", [0, True, "2", None, 2.5])
def test_a_format_version_that_is_not_a_known_integer_is_refused(fitted, tmp_path, version):
    store = with_format_version(fitted, tmp_path, version)
    with pytest.raises(BundleError, match=r"format_version .* is not one this pmactl reads \(1, 2\)"):
        load_bundle(store)
