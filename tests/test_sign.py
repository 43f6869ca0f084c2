"""Ed25519 keys and signatures, verify and inspect, and load_bundle(trusted_keys=...)."""

from __future__ import annotations

import hashlib
import json
import stat

import numpy as np
import pytest

from edge.errors import BundleError
from edge.runtime.bundle import load_bundle, resolve_release
from models_export.bundle import add_correction, update_manifest
from models_export.signing import keygen, sign_release
from tests.deploy_helpers import bundle, cli, keys
from tests.onnx_models import mlp

SPEC = {"features": ["reference_mm", "feedforward_bar"], "input": "features", "output": "correction_bar"}


@pytest.fixture
def signed(tmp_path):
    private, public = keys(tmp_path / "keys")
    return bundle(tmp_path / "b", key=private), private, public


def test_keygen_writes_a_private_key_only_its_owner_reads_and_never_overwrites(tmp_path, capsys):
    status, out, _ = cli(capsys, "keygen", "--out", tmp_path / "k")
    assert status == 0 and "key id" in out
    assert stat.S_IMODE((tmp_path / "k" / "pmactl.key").stat().st_mode) == 0o600
    assert (tmp_path / "k" / "pmactl.pub").read_text().startswith("-----BEGIN PUBLIC KEY-----")
    before = (tmp_path / "k" / "pmactl.key").read_bytes()
    status, _, err = cli(capsys, "keygen", "--out", tmp_path / "k")
    assert status == 2 and "never overwrites" in err and err.count("\n") == 1
    assert (tmp_path / "k" / "pmactl.key").read_bytes() == before


def test_verify_accepts_the_trusted_signer(signed, capsys):
    directory, _, public = signed
    status, out, _ = cli(capsys, "bundle", "verify", directory, "--trusted", public)
    assert status == 0 and "(trusted)" in out and "512 golden samples" in out
    _, other = keygen(directory.parent / "other")
    assert cli(capsys, "bundle", "verify", directory, "--trusted", other, public)[0] == 0  # one of several


def test_verify_refuses_an_unsigned_bundle_when_keys_are_trusted(tmp_path, capsys):
    _, public = keys(tmp_path / "keys")
    status, _, err = cli(capsys, "bundle", "verify", bundle(tmp_path / "b"), "--trusted", public)
    assert status == 2 and "unsigned" in err and err.count("\n") == 1


def test_verify_refuses_another_signer(signed, tmp_path, capsys):
    directory, _, _ = signed
    _, other = keygen(tmp_path / "other")
    status, _, err = cli(capsys, "bundle", "verify", directory, "--trusted", other)
    assert status == 2 and "not trusted" in err and err.count("\n") == 1


def test_a_manifest_changed_after_signing_is_refused(signed, capsys):
    directory, _, public = signed
    release = resolve_release(directory)
    manifest = json.loads((release / "manifest.json").read_text())
    manifest["model"]["units"]["input"] = "kPa"  # a "harmless" edit of a signed bundle
    (release / "manifest.json").write_text(json.dumps(manifest))
    status, _, err = cli(capsys, "bundle", "verify", directory, "--trusted", public)
    assert status == 2 and "changed after signing" in err
    with pytest.raises(BundleError, match="changed after signing"):
        load_bundle(directory, trusted_keys=[public])


def test_load_bundle_with_trusted_keys_refuses_unsigned_and_foreign_bundles(signed, tmp_path):
    directory, private, public = signed
    assert load_bundle(directory, trusted_keys=[public]).signer is not None
    _, other = keygen(tmp_path / "other")
    with pytest.raises(BundleError, match="not trusted"):
        load_bundle(directory, trusted_keys=[other])
    update_manifest(directory, note="re-released")  # a new release drops the old signature
    with pytest.raises(BundleError, match="unsigned"):
        load_bundle(directory, trusted_keys=[public])
    assert load_bundle(directory).manifest["note"] == "re-released"  # no keys asked: loads
    sign_release(directory, private)
    assert load_bundle(directory, trusted_keys=[other, public]).signer is not None


def test_a_private_key_readable_by_others_is_refused(signed, capsys):
    directory, private, _ = signed
    private.chmod(0o644)
    status, _, err = cli(capsys, "bundle", "sign", directory, "--key", private)
    assert status == 2 and "chmod 600" in err


def test_inspect_json_names_everything_a_reviewer_asks(tmp_path, capsys):
    data = tmp_path / "train.csv"
    data.write_text("t,u,y\n")
    from models_export.bundle import write_bundle
    from tests.strategies import random_dpi

    model = random_dpi(np.random.default_rng(1))
    model.reset(model.input_range[0], "descending")
    write_bundle(tmp_path / "b", model, model.inverse(), units=("bar", "mm"), training_data=[data])
    update_manifest(tmp_path / "b", quantisation={"weights": "int8"})
    status, out, _ = cli(capsys, "bundle", "inspect", tmp_path / "b", "--json")
    record = json.loads(out)
    assert status == 0 and record["kind"] == "dpi" and record["units"] == {"input": "bar", "output": "mm"}
    assert set(record["files"]) == {"forward.npz", "inverse.npz", "golden.npz"}
    assert record["signer"] is None and record["correction"] is None
    assert record["quantisation"] == {"weights": "int8"}
    assert record["provenance"]["training_data"][0]["sha256"] == hashlib.sha256(data.read_bytes()).hexdigest()
    assert record["input_range"] == [pytest.approx(v) for v in model.input_range]
    status, out, _ = cli(capsys, "bundle", "inspect", tmp_path / "b")
    assert status == 0 and "trained on train.csv" in out and "int8" in out


def test_the_correction_replays_its_golden_vectors_and_a_scaled_one_is_refused(tmp_path, capsys):
    import onnx

    directory = bundle(tmp_path / "b")
    path, _ = mlp(tmp_path / "c.onnx", scale=0.05)
    add_correction(directory, path, SPEC)
    status, out, _ = cli(capsys, "bundle", "verify", directory)
    assert status == 0 and "576 golden samples" in out  # 2 x 256 table samples + 64 correction ticks
    release = resolve_release(directory)
    graph = onnx.load(release / "correction.onnx")
    last = graph.graph.initializer[-1]
    values = onnx.numpy_helper.to_array(last) * 1.5
    last.CopyFrom(onnx.numpy_helper.from_array(values.astype(np.float32), last.name))
    onnx.save(graph, release / "correction.onnx")
    manifest = json.loads((release / "manifest.json").read_text())
    manifest["files"]["correction.onnx"]["sha256"] = hashlib.sha256(
        (release / "correction.onnx").read_bytes()
    ).hexdigest()
    (release / "manifest.json").write_text(json.dumps(manifest))
    status, _, err = cli(capsys, "bundle", "verify", directory)
    assert status == 2 and "correction does not reproduce its golden vectors" in err
