"""The trained correction in the closed loop on the HIL, through the stable CLI only (slow)."""

from __future__ import annotations

import json

import pytest

from host.cli import main
from host.examples import example_path
from host.train.correction import correction_bundle
from tests.conftest import REPO

CONFIG = str(REPO / "docs" / "examples" / "hil-rig.toml")
REFERENCES = {
    "Ai2019 sine": ["--duration", "25", "--settle", "5"],
    "Zhou2022 amplitude ramp": [
        "--reference",
        "ramp-sine:peak=30,frequency=1,offset=40,rise=10,hold=1",
        "--settle",
        "1",
    ],
}


@pytest.fixture(scope="module")
def corrected_bundle(tmp_path_factory):
    bundle = tmp_path_factory.mktemp("loop") / "bundle"
    assert main(["fit", "--model", "preisach", "--train", str(example_path("train")), "--units", "bar,mm",
                 "--save", str(bundle)]) == 0  # fmt: skip
    correction_bundle(bundle)
    return bundle


def rms(bundle, capsys, *flags: str) -> float:
    capsys.readouterr()
    assert main(["edge", "run", "--config", CONFIG, "--bundle", str(bundle), *flags, "--json"]) == 0
    return float(json.loads(capsys.readouterr().out)["rms_error"])


@pytest.mark.slow
@pytest.mark.parametrize("reference", list(REFERENCES))
def test_pid_feedforward_and_correction_reach_a_third_of_pid_alone(corrected_bundle, capsys, reference):
    extra = REFERENCES[reference]
    pid = rms(corrected_bundle, capsys, *extra, "--no-feedforward", "--no-correction")
    feedforward = rms(corrected_bundle, capsys, *extra, "--no-correction")
    corrected = rms(corrected_bundle, capsys, *extra)
    assert corrected <= 0.35 * pid and corrected < feedforward
