"""The decoy column (issue 33, private set v3's false alarm): a temperature that wanders without
touching the physics must not be named ``temperature_drift`` by diagnosis v3."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from bench.diagnose_decoy import CAMPAIGNS, SHAPES, end_to_end, hil_sources, to_degc, with_decoy
from host.data import Measurement, load_measurement
from host.diagnose.v3 import diagnose_runs


def test_a_decoy_spans_20_to_30_degc_over_the_campaign_and_leaves_the_signals_alone():
    runs = [
        Measurement(np.arange(50) * 0.02, np.sin(np.arange(50.0)), np.cos(np.arange(50.0)), {}, f"r{i}")
        for i in range(3)
    ]
    decoyed = with_decoy(runs, "walk", 0)
    column = np.concatenate([m.extras["temperature"] for m in decoyed])
    assert column.min() == pytest.approx(20.0) and column.max() == pytest.approx(30.0)
    assert all(np.array_equal(a.y, b.y) and np.array_equal(a.u, b.u) for a, b in zip(runs, decoyed))
    assert set(SHAPES) == {"walk", "smooth_walk", "sine", "ramp_sine"}
    assert np.ptp(to_degc(np.zeros(5))) == 0.0


@pytest.mark.parametrize("shape", ["walk", "sine"])
def test_an_effect_free_hil_recording_with_a_decoy_temperature_does_not_name_it(shape):
    (runs,) = hil_sources(1, duration_s=30.0).values()
    causes = [diagnose_runs(with_decoy(runs, shape, seed)).cause for seed in (0,)]
    assert "temperature_drift" not in causes, causes


def _campaign(root: Path, name: str) -> list[Measurement]:
    paths = sorted((root / "pam_muscle_sensory" / name).glob("*.csv"))
    if not paths:
        pytest.skip(f"no {name} campaign under {root}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # irregular sampling is resampled, with a warning per file
        return [Measurement(m.t, m.u, m.y, {}, m.source) for m in map(load_measurement, paths)]


@pytest.mark.parametrize("campaign", [CAMPAIGNS[0], pytest.param(CAMPAIGNS[2], marks=pytest.mark.slow)])
def test_an_untouched_muscle_campaign_of_runs_with_a_decoy_temperature_does_not_name_it(shared_data, campaign):
    runs = _campaign(shared_data, campaign)
    causes = [diagnose_runs(with_decoy(runs, shape, 1)).cause for shape in ("walk", "ramp_sine")]
    assert "temperature_drift" not in causes, causes


@pytest.mark.parametrize(
    "campaign, one_file, shape, seed",
    [(CAMPAIGNS[1], False, "sine", 0), (CAMPAIGNS[0], True, "ramp_sine", 1)],
    ids=["31-03 runs", "18-03 one file"],
)
def test_a_slow_decoy_temperature_on_an_untouched_campaign_is_not_named(shared_data, campaign, one_file, shape, seed):
    """Plain circular shifts of the column named these two (their copies jump at the wrap)."""
    decoyed = with_decoy(_campaign(shared_data, campaign), shape, seed)
    assert diagnose_runs([end_to_end(decoyed)] if one_file else decoyed).cause != "temperature_drift"
