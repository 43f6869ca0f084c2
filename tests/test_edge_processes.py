"""The edge loop as users run it: over the serial DAQ protocol on a real pty with the HIL in
another process, and as a process that gets SIGTERM mid-run."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from edge.runtime.safety import Fault
from edge.runtime.telemetry import read_telemetry
from tests.edge_helpers import REPO, fit_bundle, runtime

SERIAL_EXAMPLE = REPO / "docs" / "examples" / "hil-serial.toml"


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    return fit_bundle(tmp_path_factory.mktemp("bundle") / "preisach")


@pytest.fixture
def hil_server():
    """``pmactl hil serve`` in its own process (real time, 1 kHz); yields (process, pty path)."""
    process = subprocess.Popen(
        [sys.executable, "-m", "host.cli", "hil", "serve", "--duration", "60"], stdout=subprocess.PIPE, text=True
    )
    try:
        line = process.stdout.readline()
        assert line.startswith("pty: "), line
        yield process, line.split()[1]
    finally:
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
        process.communicate(timeout=10)


def serial_config(tmp_path: Path, pty: str) -> Path:
    path = tmp_path / "serial.toml"
    text = SERIAL_EXAMPLE.read_text().replace("serial:///dev/pts/3", f"serial://{pty}")
    path.write_text(text.replace("realtime = true", "realtime = false"))  # no SCHED_FIFO inside pytest
    return path


def test_the_loop_runs_over_the_serial_daq_with_the_hil_in_another_process(bundle, hil_server, tmp_path):
    """Measured: RMS 2.46 mm over 20 s (2.45 mm in lockstep over I2C), lateness p99 ~2 us."""
    from edge.runtime.config import load_config

    _, pty = hil_server
    edge = runtime(bundle, config=load_config(serial_config(tmp_path, pty)), settle_s=5.0)
    summary = edge.run(10.0).as_dict()
    assert summary["faults"] == []
    assert summary["ticks"] + summary["lateness"]["skipped_ticks"] == 10_000
    assert summary["rms_error"] < 3.0  # feedforward + PID on the same plant as the lockstep test
    client = edge.rig.io.client
    assert client.samples > 9_000 and client.crc_errors == 0


def test_a_dead_daq_ends_the_run_in_the_safe_state(bundle, hil_server, tmp_path):
    from edge.runtime.config import load_config

    process, pty = hil_server
    edge = runtime(bundle, config=load_config(serial_config(tmp_path, pty)), telemetry_path=tmp_path / "t.pmt")
    edge.on_tick.append(lambda t: process.kill() if abs(t - 2.0) < 5e-4 else None)
    summary = edge.run(5.0).as_dict()
    record = read_telemetry(tmp_path / "t.pmt")
    t, fault = record.column("t"), record.column("fault")
    assert set(fault[fault > 0]) == {Fault.BUS.value} and "consecutive bus errors" in summary["faults"][0]
    assert t[-1] < 2.0 + 0.05  # the DAQ's output went stale, then 3 ticks of errors


def test_sigterm_mid_run_leaves_a_complete_telemetry_file(bundle, tmp_path):
    config = tmp_path / "rig.toml"
    text = (REPO / "docs" / "examples" / "hil-rig.toml").read_text()
    config.write_text(text.replace("clock=lockstep", "clock=realtime"))
    telemetry = tmp_path / "run.pmt"
    command = [sys.executable, "-m", "host.cli", "edge", "run", "--config", str(config), "--bundle", str(bundle)]
    command += ["--duration", "60", "--telemetry", str(telemetry), "--json"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and (not telemetry.exists() or telemetry.stat().st_size < 100_000):
            time.sleep(0.05)  # running and flushing
        process.send_signal(signal.SIGTERM)
        out, err = process.communicate(timeout=20)
    finally:
        process.kill()
    assert process.returncode == 0, err
    summary = json.loads(out)
    record = read_telemetry(telemetry)
    assert record.truncated_bytes == 0 and summary["telemetry_dropped"] == 0
    assert len(record.rows) == summary["ticks"] > 1000
    assert record.events[-1]["kind"] == "stop" and summary["faults"] == []
