"""The correction states which references its training data covers (range [mm], rate [mm/s]),
in its output and in the manifest, and the edge warns in one line before arming when a run's
reference leaves that coverage, with the share outside."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from edge.errors import BundleError
from edge.runtime.bundle import load_bundle
from edge.runtime.coverage import MARGIN, Coverage, outside_coverage, read_coverage
from host.cli import main
from host.examples import example_path
from host.train.correction import coverage_of
from tests.edge_helpers import HIL_RIG
from tests.neural_data import hil_csv


def sine(amplitude: float, frequency: float, offset: float):
    return lambda t: offset + amplitude * math.sin(2 * math.pi * frequency * t)


def share_in(line: str | None) -> float:
    """The share of the run the warning says is outside [0..1]."""
    assert line is not None
    return float(re.search(r"for (\d+)% of the run", line).group(1)) / 100  # type: ignore[union-attr]


def test_coverage_is_the_range_and_rate_range_of_the_features():
    rng = np.random.default_rng(3)
    features = np.column_stack([rng.uniform(-2, 40, 1000), rng.uniform(-70, 55, 1000), rng.uniform(0, 4, 1000)])
    coverage = coverage_of(features)
    assert coverage["reference_mm"] == [features[:, 0].min(), features[:, 0].max()]
    assert coverage["reference_rate_mm_s"] == [features[:, 1].min(), features[:, 1].max()]


def test_a_reference_inside_the_coverage_gives_no_warning():
    coverage = Coverage((0.0, 60.0), (-100.0, 100.0))
    assert outside_coverage(sine(20, 0.5, 30), 10.0, coverage) is None  # rate peak 62.8 mm/s


@pytest.mark.parametrize(("amplitude", "top"), [(30.0, 50.0), (25.0, 60.0)])
def test_the_share_outside_the_range_is_the_share_of_the_run_above_it(amplitude, top):
    coverage = Coverage((0.0, top), (-1000.0, 1000.0))
    line = outside_coverage(sine(amplitude, 0.2, 40), 5.0, coverage)
    bound = top + MARGIN * top
    expected = (math.pi - 2 * math.asin((bound - 40) / amplitude)) / (2 * math.pi)
    assert abs(share_in(line) - expected) <= 0.015 and "rate" in line


def test_a_reference_faster_than_the_training_data_is_named_by_its_rate():
    coverage = Coverage((0.0, 60.0), (-50.0, 50.0))
    line = outside_coverage(sine(20, 1.0, 30), 5.0, coverage)  # rate peak 125.7 mm/s
    bound = 50 + MARGIN * 100
    expected = 1 - 2 * math.asin(bound / (2 * math.pi * 20)) / math.pi  # |cos| above bound/peak
    assert abs(share_in(line) - expected) <= 0.015
    assert line is not None and "0% outside; rate -125." in line and "pmactl edge record --protocol sines" in line


def test_no_coverage_recorded_means_no_check_and_a_malformed_one_is_one_error():
    assert read_coverage(None, "b") is None and read_coverage({"features": []}, "b") is None
    good = {"coverage": {"reference_mm": [0, 50], "reference_rate_mm_s": [-10.5, 12]}}
    assert read_coverage(good, "b") == Coverage((0.0, 50.0), (-10.5, 12.0))
    for bad in ([0, 50], {"reference_mm": [50, 0], "reference_rate_mm_s": [-1, 1]},
                {"reference_mm": [0, 50]}, {"reference_mm": [0, None], "reference_rate_mm_s": [-1, 1]},
                {"reference_mm": [0, True], "reference_rate_mm_s": [-1, 1]}):  # fmt: skip
        with pytest.raises(BundleError, match="coverage"):
            read_coverage({"coverage": bad}, "b")


@pytest.fixture(scope="module")
def corrected(tmp_path_factory) -> tuple[Path, dict[str, object], str]:
    """A Preisach bundle from the example recording, corrected on an HIL sines recording."""
    root = tmp_path_factory.mktemp("coverage")
    bundle = root / "bundle"
    fit = ["fit", "--model", "preisach", "--train", str(example_path("train")), "--units", "bar,mm"]
    assert main([*fit, "--save", str(bundle)]) == 0
    train = hil_csv(root, "sines", 4, 40.0)
    argv = ["train", "--model", "correction", "--train", str(train), "--bundle", str(bundle), "--epochs", "20"]
    assert main([*argv, "--json"]) == 0
    return bundle, load_bundle(bundle).correction_spec or {}, str(train)


def test_the_manifest_and_the_json_output_record_what_the_recording_covers(corrected, tmp_path, capsys):
    bundle, spec, train = corrected
    coverage = spec["coverage"]
    assert isinstance(coverage, dict)
    data = np.genfromtxt(train, delimiter=",", names=True)
    lo, hi = coverage["reference_mm"]
    assert abs(lo - data["y"].min()) < 1.0 and abs(hi - data["y"].max()) < 1.0  # smoothed, so within noise
    rate = np.gradient(data["y"], data["t"])
    rlo, rhi = coverage["reference_rate_mm_s"]
    assert rlo < 0 < rhi and rhi <= np.abs(rate).max()  # smoothing only lowers the noisy peaks
    capsys.readouterr()
    argv = ["train", "--model", "correction", "--train", train, "--bundle", str(bundle), "--epochs", "3"]
    assert main([*argv, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["coverage"] == load_bundle(bundle).correction_spec["coverage"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert f"covers references {lo:.1f}..{hi:.1f} mm at rates {rlo:.1f}..{rhi:.1f} mm/s" in out


def edge_run(bundle: Path, reference: str, *extra: str) -> list[str]:
    return ["edge", "run", "--config", str(HIL_RIG), "--bundle", str(bundle), "--reference", reference,
            "--duration", "1", "--json", *extra]  # fmt: skip


def test_edge_run_warns_once_before_arming_when_the_reference_is_faster_than_the_data(corrected, capsys):
    bundle, spec, _ = corrected
    coverage = read_coverage(spec, "b")
    assert coverage is not None
    (lo, hi), (_, rhi) = coverage.reference_mm, coverage.rate_mm_s
    amplitude, offset = 0.3 * (hi - lo), 0.5 * (lo + hi)  # well inside the range
    slow = f"sine:amplitude={amplitude:.3f},frequency={0.5 * rhi / (2 * math.pi * amplitude):.4f},offset={offset:.3f}"
    fast = f"sine:amplitude={amplitude:.3f},frequency={2.0 * rhi / (2 * math.pi * amplitude):.4f},offset={offset:.3f}"
    capsys.readouterr()
    assert main(edge_run(bundle, slow)) == 0
    captured = capsys.readouterr()
    assert captured.err == "" and json.loads(captured.out)["warnings"] == []
    assert main(edge_run(bundle, fast)) == 0
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and "leaves what the correction was trained on" in lines[0] and "% of the run" in lines[0]
    assert json.loads(captured.out)["warnings"] == [lines[0].split("warning: ", 1)[1]]
    assert main(edge_run(bundle, fast, "--no-correction")) == 0  # no correction, nothing to warn about
    assert capsys.readouterr().err == ""
