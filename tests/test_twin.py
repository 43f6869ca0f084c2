"""The forward twin: the bundle's forward table predicts the contraction from the applied
pressure each tick; the residual's windowed RMS warns (or, with ``[safety] twin_mismatch_mm``,
trips) on the HIL's leak, a detached position sensor and a bundle of another muscle, and stays
quiet with the matching bundle."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from edge.control.pid import PIDGains
from edge.control.tick import Controller, Readings, ScratchFrame
from edge.control.twin import TWIN_FAULT, TWIN_OK, TWIN_WARN, ForwardModel, TwinWatch
from edge.errors import ConfigError
from edge.runtime.bundle import load_bundle
from edge.runtime.safety import Fault
from edge.runtime.telemetry_read import read_telemetry
from host.data import load_measurement
from host.examples import example_path
from host.workflow import make_estimator, save_bundle
from tests.edge_helpers import fit_bundle, rig_config, runtime

IN_REACH = "sine:amplitude=20,frequency=0.2,offset=30"  # 10..50 mm: inside the example bundle's reach


@pytest.fixture(scope="module")
def bundle(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return fit_bundle(tmp_path_factory.mktemp("bundle") / "preisach")


def hil_run(bundle: Path, tmp_path: Path, faults: str = "", duration_s: float = 12.0, **sections: dict):
    url = "sim://rig?clock=lockstep" + (f"&faults={faults}" if faults else "")
    config = rig_config(buses={"i2c": {"url": url}}, **sections)
    telemetry = tmp_path / "run.pmt"
    edge = runtime(bundle, IN_REACH, config, telemetry_path=telemetry)
    summary = edge.run(duration_s)
    return summary.as_dict(), read_telemetry(telemetry)


def twin_warnings(record) -> list[float]:
    return [float(e["t"]) for e in record.events if e["kind"] == "warning" and "forward twin" in str(e["text"])]


def test_the_table_is_a_forward_model(bundle):
    assert isinstance(load_bundle(bundle).forward, ForwardModel)


def test_the_watch_ignores_a_fit_error_and_names_a_large_residual_early():
    watch = TwinWatch(warn_mm=2.0, window_s=1.0, period_s=0.01)
    noise = np.random.default_rng(0).normal(0.0, 1.0, 500)  # RMS 1 mm, twice below the bound
    assert all(watch.add(i * 0.01, float(r)) == TWIN_OK for i, r in enumerate(noise))
    verdicts = [watch.add(5.0 + i * 0.01, 6.0) for i in range(300)]
    assert verdicts.count(TWIN_WARN) == 1 and verdicts.index(TWIN_WARN) < 20  # 6 mm: 12 ticks of 100 suffice
    assert watch.warning is not None and "bound 2.00 mm" in watch.warning
    assert watch.warned_at_s == pytest.approx(5.0 + 0.01 * verdicts.index(TWIN_WARN))


def test_the_watch_trips_past_the_fault_bound_and_skips_ticks_without_a_residual():
    watch = TwinWatch(warn_mm=1.0, fault_mm=3.0, window_s=1.0, period_s=0.01)
    assert all(watch.add(i * 0.01, math.nan) == TWIN_OK for i in range(300))
    verdicts = [watch.add(3.0 + i * 0.01, 4.0) for i in range(100)]
    assert TWIN_FAULT in verdicts and watch.fault is not None


def test_the_controller_fills_the_twin_fields_and_resets_the_twin_on_arming(bundle):
    loaded = load_bundle(bundle)
    controller = Controller(lambda t: 20.0, PIDGains(0.05, 0.5, 0.0), loaded.inverse, twin=loaded.forward)
    controller.arm(Readings(0.0, 0.0))
    frame = ScratchFrame(0.001, 5.0, 2.0)
    controller.fill(frame, 0.001)
    predicted = loaded.forward.step(2.0) if loaded.forward.reset() is None else math.nan
    assert frame.twin_mm == pytest.approx(predicted) and frame.twin_residual_mm == pytest.approx(5.0 - predicted)
    controller.arm(Readings(0.0, 0.0))
    frame2 = ScratchFrame(0.001, 5.0, 2.0)
    controller.fill(frame2, 0.001)
    assert frame2.twin_mm == frame.twin_mm  # the same start state after arming again


def test_the_matching_bundle_does_not_warn_over_a_long_run(bundle, tmp_path):
    summary, record = hil_run(bundle, tmp_path, duration_s=60.0)
    assert twin_warnings(record) == [] and summary["faults"] == []
    assert summary["twin_rms_max_mm"] < 0.5 * 0.06 * 58.0  # half the bound (6 % of the bundle's ~58 mm span)
    assert np.isfinite(record.column("twin_mm")).mean() > 0.99


@pytest.mark.parametrize(("fault", "within_s"), [("leak", 5.0), ("sensor_detached", 1.0)])
def test_a_leak_and_a_detached_sensor_are_warned_about(bundle, tmp_path, fault, within_s):
    summary, record = hil_run(bundle, tmp_path, f"{fault}@6", duration_s=12.0)
    times = twin_warnings(record)
    assert len(times) == 1 and 6.0 < times[0] <= 6.0 + within_s, times


def test_a_bundle_of_a_muscle_that_needs_more_pressure_is_warned_about(tmp_path):
    """Fitted on the example recording with its pressure scaled by 1.4 (another muscle)."""
    train = load_measurement(example_path("train"))
    estimator = make_estimator("preisach").fit(1.4 * train.u, train.y)
    other = save_bundle(estimator, train, tmp_path / "other", ("bar", "mm"), {"model": "preisach"})
    summary, record = hil_run(other, tmp_path, duration_s=12.0)
    times = twin_warnings(record)
    assert len(times) == 1 and times[0] <= 3.0 + 2.0 + 0.2, times  # grace + one window + one report period
    assert summary["twin_warning_t"] <= 5.0


def test_with_adapt_a_leak_is_still_warned_about(bundle, tmp_path):
    """The adaptation absorbs the leak into its map, but the residual judges the bundle itself."""
    summary, record = hil_run(bundle, tmp_path, "leak@6", duration_s=12.0, adapt={"enabled": True})
    times = twin_warnings(record)
    assert len(times) == 1 and 6.0 < times[0] <= 11.0 and summary["adapt"]["updates"] > 5000


def test_with_twin_mismatch_mm_a_leak_is_a_fault(bundle, tmp_path):
    summary, record = hil_run(bundle, tmp_path, "leak@6", duration_s=12.0, safety={"twin_mismatch_mm": 4.0})
    assert len(summary["faults"]) == 1 and "twin_mismatch_mm 4 mm" in summary["faults"][0]
    assert record.column("fault").max() == Fault.TWIN_MISMATCH.value and record.column("u_bar")[-1] == 0.0


def test_twin_keys_are_checked():
    with pytest.raises(ConfigError, match=r"\[safety\] twin_window_s = 0.0 must be in"):
        rig_config(safety={"twin_window_s": 0.0})
    with pytest.raises(ConfigError, match="did you mean 'twin_mismatch_mm'"):
        rig_config(safety={"twin_mismatch": 3.0})
