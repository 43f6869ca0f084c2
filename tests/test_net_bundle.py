"""The trained nets as a bundle: written by train --save, verified, signed, deployed, run as feedforward.

One short recording made by ``pmactl edge record`` on the emulated rig with rate dependence, a
net trained for a few epochs (small, not good: these tests check the wiring, the number is in
bench/net_feedforward_bench.py), everything through the CLI a user types.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from edge.runtime.bundle import MANIFEST, load_bundle
from host.cli import main

EXAMPLE = Path(__file__).resolve().parent.parent / "docs" / "examples" / "hil-rig.toml"
SINE = "sine:amplitude=20,frequency=0.5,offset=35"


def rig_config(directory: Path, role: str | None, twin: str | None = None) -> Path:
    text = EXAMPLE.read_text().replace(
        'url = "sim://rig?clock=lockstep"', 'url = "sim://rig?clock=lockstep&effect=rate_dependence&seed=1"'
    )
    if role is not None or twin is not None:
        text += "\n[feedforward]\n" + (f'role = "{role}"\n' if role else "") + (f'twin = "{twin}"\n' if twin else "")
    path = directory / f"rig-{role or 'default'}-{twin or 'table'}.toml"
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("netbundle")
    recording = root / "rec.csv"
    protocol = "sines:frequencies=0.2/0.5/1,amplitudes=1/0.5,cycles=2"
    assert main(["edge", "record", "--config", str(rig_config(root, None)), "--protocol", protocol,
                 "--range", "0:6", "--out", str(recording), "--json"]) == 0  # fmt: skip
    assert main(["keygen", "--out", str(root / "keys")]) == 0
    store = root / "store"
    assert main(["train", "--model", "lstm-narmax", "--train", str(recording), "--units", "bar,mm",
                 "--epochs", "4", "--save", str(store), "--key", str(root / "keys" / "pmactl.key")]) == 0  # fmt: skip
    return root, recording, store


def test_the_bundle_holds_tables_both_nets_and_says_which_roles(trained):
    _, _, store = trained
    bundle = load_bundle(store, trusted_keys=[trained[0] / "keys" / "pmactl.pub"])
    assert set(bundle.net_paths) == {"forward", "inverse"}
    assert bundle.manifest["roles"] == {"feedforward": ["table", "net"], "forward": ["table", "net"]}
    assert bundle.signer is not None
    assert main(["bundle", "verify", str(store)]) == 0


def test_the_net_inverse_starts_again_on_reset_and_extrapolates_its_residual_between_net_steps(trained):
    bundle = load_bundle(trained[2])
    inverse = bundle.feedforward("net", 1e-3)
    target = 35.0 + 20.0 * np.sin(2 * np.pi * 0.5 * np.arange(2000) * 1e-3)
    inverse.reset()
    first = inverse.simulate(target)
    inverse.reset()
    again = inverse.simulate(target)
    bundle.inverse.reset()
    table = bundle.inverse.simulate(target)
    assert np.array_equal(first, again) and np.all(np.isfinite(first))
    residual = (first - table).reshape(-1, 10)  # the net steps every 10 ms, the loop every 1 ms
    assert np.allclose(np.diff(residual, n=2, axis=1), 0.0, atol=1e-9)  # a straight line within each net step


def test_the_forward_net_maps_pressure_to_contraction_over_the_recording(trained):
    from host.data import load_measurement

    record = load_measurement(trained[1])
    forward = load_bundle(trained[2]).forward_net(1.0 / 100)
    forward.reset()
    predicted = np.array([forward.step(p) for p in record.u.tolist()])
    rmse = float(np.sqrt(np.mean((predicted - record.y) ** 2)))
    assert rmse < 0.15 * float(np.ptp(record.y))  # a model of this muscle, not a constant


def test_deployed_and_run_from_target_current_with_the_net_feedforward(trained, capsys):
    root, _, store = trained
    target = root / "target"
    assert main(["deploy", str(store), str(target), "--trusted", str(root / "keys" / "pmactl.pub")]) == 0
    capsys.readouterr()
    config = rig_config(root, "net")
    code = main(["edge", "run", "--config", str(config), "--bundle", str(target / "current"), "--reference", SINE,
                 "--duration", "3", "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["faults"] == [] and summary["feedforward_role"] == "net"


def test_a_role_the_bundle_cannot_fill_is_one_line_and_exit_2(trained, tmp_path, capsys):
    root, recording, _ = trained
    table_only = tmp_path / "table"
    assert main(["fit", "--model", "mpi", "--train", str(recording), "--units", "bar,mm", "--save",
                 str(table_only)]) == 0  # fmt: skip
    capsys.readouterr()
    config = rig_config(tmp_path, "net+correction")
    code = main(["edge", "run", "--config", str(config), "--bundle", str(table_only), "--reference", SINE,
                 "--duration", "1"])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "role 'net+correction'" in err[0] and "can fill table" in err[0]


def test_an_edited_net_is_refused_at_load(trained, tmp_path):
    from edge.errors import BundleError

    release = tmp_path / "release"
    shutil.copytree(load_bundle(trained[2]).path, release)
    data = bytearray((release / "inverse_net.onnx").read_bytes())
    data[-20] ^= 0x01
    (release / "inverse_net.onnx").write_bytes(bytes(data))
    with pytest.raises(BundleError, match="checksum mismatch"):
        load_bundle(release)


def test_retraining_into_a_signed_store_without_key_says_unsigned(trained, tmp_path, capsys):
    root, recording, store = trained
    copy = tmp_path / "store"
    shutil.copytree(store, copy, symlinks=True)
    assert main(["train", "--model", "lstm-narmax", "--train", str(recording), "--units", "bar,mm",
                 "--epochs", "2", "--save", str(copy)]) == 0  # fmt: skip
    err = [line for line in capsys.readouterr().err.splitlines() if "UNSIGNED" in line]
    assert len(err) == 1 and "pmactl bundle sign" in err[0]
    assert json.loads((copy / "current" / MANIFEST).read_text())["nets"]["inverse"]["step_s"] == pytest.approx(0.01)


@pytest.mark.parametrize("lag", [0, 3, 11])
def test_the_preview_is_the_lag_of_the_contraction_behind_the_command(lag):
    from host.train.net_inverse import identify_preview

    rng = np.random.default_rng(lag)
    command = np.cumsum(rng.normal(0.0, 0.1, 3000))  # a random walk: no period to alias the lag
    table = np.concatenate([np.full(lag, command[0]), command[: command.size - lag]])  # answers `lag` late
    assert identify_preview(table, command, 2400, 0.01) == lag


def test_the_controller_feeds_a_previewing_inverse_the_reference_ahead():
    from edge.control.pid import PIDGains
    from edge.control.tick import Controller, Readings, ScratchFrame

    class Recording:
        input_range = (0.0, 100.0)
        preview_s = 0.05

        def __init__(self) -> None:
            self.seen: list[float] = []

        def reset(self) -> None:
            self.seen.clear()

        def step(self, target: float) -> float:
            self.seen.append(target)
            return 0.0

    inverse = Recording()
    controller = Controller(lambda t: 100.0 * t, PIDGains(0.0, 0.0, 0.0), inverse)
    controller.arm(Readings(0.0))
    frame = ScratchFrame(0.2, 0.0)
    controller.fill(frame, 1e-3)
    assert inverse.seen == [pytest.approx(25.0)] and frame.reference_mm == pytest.approx(20.0)


@pytest.mark.parametrize(
    ("net", "correction", "default"),
    [(False, False, "table"), (False, True, "table+correction"), (True, False, "net"), (True, True, "net+correction")],
)
def test_the_default_role_is_a_net_when_there_is_one_plus_the_correction_when_there_is_one(net, correction, default):
    from edge.control.net_roles import choose_role, feedforward_roles

    available = feedforward_roles(net, correction)
    assert choose_role(available, "", "rig.toml") == default
    assert choose_role(available, "table", "rig.toml") == "table"  # the table is always there


def test_the_net_feedforward_runs_the_forward_net_as_twin(trained, capsys):
    """With role net and twin net the twin is the forward net, stepped at its own period like the inverse:
    the run's twin_mm is the forward net replayed over the run's measured pressure, and the
    summary says which twin ran. Whether it fits the rate-dependent muscle better than the table
    is a property of the training (this net has 4 epochs), measured in the twin bench."""
    from edge.runtime.telemetry_read import read_telemetry

    root, _, store = trained
    telemetry = root / "net-twin.pmt"
    code = main(["edge", "run", "--config", str(rig_config(root, "net", "net")), "--bundle", str(store), "--reference",
                 "sine:amplitude=20,frequency=1,offset=35", "--duration", "3", "--telemetry", str(telemetry),
                 "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["twin_model"] == "net"
    record = read_telemetry(telemetry)
    running = record.column("state") == 2  # RUNNING: the ticks the law filled
    p, twin_mm = record.column("pressure_bar")[running], record.column("twin_mm")[running]
    forward = load_bundle(store).forward_net(1e-3)
    forward.reset()
    replayed = np.array([forward.step(v) for v in p.tolist()])
    table = load_bundle(store).forward
    table.reset()
    assert np.allclose(twin_mm, replayed, rtol=0, atol=1e-9)
    assert not np.allclose(twin_mm, [table.step(v) for v in p.tolist()], atol=1e-3)  # not the table


def test_the_table_feedforward_keeps_the_table_twin(trained, capsys):
    root, _, store = trained
    code = main(["edge", "run", "--config", str(rig_config(root, "table")), "--bundle", str(store), "--reference",
                 SINE, "--duration", "1", "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["twin_model"] == "table"


def test_the_net_role_keeps_the_table_twin_by_default_and_a_net_twin_needs_a_net_role(trained, capsys):
    root, _, store = trained
    code = main(["edge", "run", "--config", str(rig_config(root, "net")), "--bundle", str(store), "--reference",
                 SINE, "--duration", "1", "--json"])  # fmt: skip
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert code == 0 and summary["twin_model"] == "table"
    code = main(["edge", "run", "--config", str(rig_config(root, "table", "net")), "--bundle", str(store),
                 "--reference", SINE, "--duration", "1"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and 'twin = "net" needs a net feedforward role' in err and "Traceback" not in err
    code = main(["edge", "run", "--config", str(rig_config(root, "net", "model")), "--bundle", str(store),
                 "--reference", SINE, "--duration", "1"])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and 'twin = "model" is unknown' in err and err.count("\n") == 1
