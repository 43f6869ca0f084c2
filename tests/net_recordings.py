"""The recordings the net-bundle tests train on: one short ``edge record`` of the emulated,
rate-dependent muscle to train on and one to hold out, and a key pair to sign with."""

from __future__ import annotations

from pathlib import Path

from host.cli import main
from tests.test_net_bundle import rig_config

PROTOCOLS = (
    ("rec.csv", "sines:frequencies=0.2/0.5/1,amplitudes=1/0.5,cycles=2"),
    ("held.csv", "sines:frequencies=0.3/0.7,amplitudes=0.8,cycles=2"),
)


def record_train_and_held(root: Path) -> tuple[Path, list[Path]]:
    """``root``, [training recording, held-out recording]; keys in ``root/keys``."""
    config = rig_config(root, None)
    recordings = []
    for name, protocol in PROTOCOLS:
        assert main(["edge", "record", "--config", str(config), "--protocol", protocol, "--range", "0:6",
                     "--out", str(root / name), "--json"]) == 0  # fmt: skip
        recordings.append(root / name)
    assert main(["keygen", "--out", str(root / "keys")]) == 0
    return root, recordings


def train_store(root: Path, recording: Path, held: Path, model: str, epochs: int) -> Path:
    """``pmactl train --model MODEL ... --save root/store --key``: the signed store."""
    target = root / "store"
    assert main(["train", "--model", model, "--train", str(recording), "--test", str(held), "--units", "bar,mm",
                 "--epochs", str(epochs), "--save", str(target), "--key", str(root / "keys" / "pmactl.key"),
                 "--json"]) == 0  # fmt: skip
    return target
