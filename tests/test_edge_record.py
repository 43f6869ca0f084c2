"""``pmactl edge record``: open-loop recordings on the emulated rig, end to end through the CLI.

The record -> fit -> run path is checked on the property the papers promise (feedforward +
PID tracks Ai2019's sine with at most 0.6x the RMS error of PID alone), on the default
emulated muscle and on a plant variant the protocols were not written against (creep).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from edge.control.protocols import PROTOCOLS, build_protocol
from edge.runtime.telemetry_read import read_telemetry
from host.cli import main
from host.data import load_measurement
from tests.edge_helpers import HIL_RIG, SEED_000_SINE

HIL_JOINT = HIL_RIG.parent / "hil-joint.toml"


def rig_file(tmp_path: Path, url: str, source: Path = HIL_RIG) -> Path:
    """The example config with its first bus URL replaced (faults, effects)."""
    text = source.read_text()
    old = 'url = "sim://rig?clock=lockstep"' if source == HIL_RIG else 'url = "sim://joint?clock=lockstep"'
    assert old in text
    path = tmp_path / "rig.toml"
    path.write_text(text.replace(old, f'url = "{url}"'))
    return path


def run_rms(config: Path, bundle: Path | None, capsys: pytest.CaptureFixture[str], *extra: str) -> float:
    args = ["edge", "run", "--config", str(config), "--reference", SEED_000_SINE, "--duration", "25", "--settle", "5"]
    args += ["--json"]
    args += ["--bundle", str(bundle)] + list(extra)
    assert main(args) == 0
    return float(json.loads(capsys.readouterr().out)["rms_error"])


@pytest.mark.parametrize(
    ("protocol", "fit_options", "url"),
    [
        ("triangles", [], "sim://rig?clock=lockstep"),
        ("forc", ["--preisach-method", "forc"], "sim://rig?clock=lockstep"),
        ("triangles", [], "sim://rig?clock=lockstep&effect=creep&seed=4"),
    ],
)
def test_record_fit_run_feedforward_beats_pid(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], protocol: str, fit_options: list[str], url: str
) -> None:
    config = rig_file(tmp_path, url)
    csv = tmp_path / f"{protocol}.csv"
    assert main(["edge", "record", "--config", str(config), "--protocol", protocol, "--out", str(csv)]) == 0
    capsys.readouterr()
    bundle = tmp_path / "bundle"
    fit = ["fit", "--model", "preisach", "--train", str(csv), "--units", "bar,mm", "--save", str(bundle)]
    assert main(fit + fit_options) == 0
    capsys.readouterr()
    with_model = run_rms(config, bundle, capsys)
    pid_alone = run_rms(config, bundle, capsys, "--no-feedforward")
    assert with_model <= 0.6 * pid_alone, (with_model, pid_alone)


def test_record_csv_is_what_the_host_tools_read(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv = tmp_path / "run.csv"
    args = ["edge", "record", "--config", str(HIL_RIG), "--protocol", "steps:levels=2,hold=2", "--out", str(csv)]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "next: pmactl fit" in out
    data = load_measurement(csv)
    assert csv.read_text().splitlines()[0] == "t,u,y,p"
    assert np.allclose(np.diff(data.t), 0.01)
    assert len(data.t) == 1000  # 0, 2, 4, 2, 0 bar, each held 2 s, at 100 Hz
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["complete"] and meta["rows"] == 1000 and meta["faults"] == []
    assert meta["columns"]["u"]["unit"] == "bar" and meta["columns"]["y"]["unit"] == "mm"
    assert data.u[np.searchsorted(data.t, 1.9)] == 0.0 and data.u[np.searchsorted(data.t, 2.5)] == 2.0
    # the contraction follows the held pressure: higher steps, more contraction
    held = [data.y[(data.t > t0 + 1.5) & (data.t < t0 + 2.0)].mean() for t0 in (0.0, 2.0, 4.0, 6.0)]
    assert held[1] > held[0] + 5 and held[2] > held[1] + 5 and held[3] < held[2] - 5


@pytest.mark.parametrize(
    ("fault", "at_s", "reason"),
    [
        ("sensor_stuck", 30.0, "contraction sensor stuck"),
        ("estop", 12.0, "e-stop pressed"),
        ("adc_nack", 21.0, "consecutive ticks with a device error; adc read failed"),
        ("pressure_high", 7.0, "overpressure"),
    ],
)
def test_fault_mid_record_keeps_rows_and_vents(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], fault: str, at_s: float, reason: str
) -> None:
    config = rig_file(tmp_path, f"sim://rig?clock=lockstep&faults={fault}@{at_s:g}")
    csv, telemetry = tmp_path / "run.csv", tmp_path / "run.pmt"
    args = ["edge", "record", "--config", str(config), "--protocol", "triangles", "--out", str(csv)]
    assert main(args + ["--telemetry", str(telemetry)]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "FAULT" in err[0] and reason in err[0] and "vented" in err[0], err
    data = load_measurement(csv)
    record = read_telemetry(telemetry)
    rows = record.rows
    assert rows["valve_enable"][-1] == 0.0 and rows["u_bar"][-1] == 0.0  # vented in the fault's tick
    fault_t = float(rows["t"][-1])
    assert at_s - 0.01 <= fault_t < at_s + 3.0  # the rig's clock starts a tick before the loop's
    # every sampled tick before the fault is in the CSV, on the 10 ms grid, none after it
    assert data.t[0] == 0.0 and np.allclose(np.diff(data.t), 0.01)
    assert fault_t - 0.02 < data.t[-1] < fault_t  # (a failed read before a bus fault is no row)
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["complete"] and reason in meta["faults"][0] and meta["stopped"] == "fault"


def test_joint_record_is_fitted_and_run(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv = tmp_path / "joint.csv"
    args = ["edge", "record", "--config", str(HIL_JOINT), "--protocol", "forc", "--out", str(csv)]
    assert main(args) == 0
    capsys.readouterr()
    assert csv.read_text().splitlines()[0] == "t,u,y,u1,u2,p1,p2"
    data = load_measurement(csv)
    assert data.u.min() == pytest.approx(-30.0, abs=0.01) and data.u.max() == pytest.approx(30.0, abs=0.5)
    assert np.corrcoef(data.u, data.y)[0, 1] > 0.9  # the angle follows the commanded angle
    bundle = tmp_path / "joint-bundle"
    fit = ["fit", "--model", "preisach", "--preisach-method", "forc", "--train", str(csv), "--units", "deg,deg"]
    assert main(fit + ["--save", str(bundle)]) == 0
    capsys.readouterr()
    run = ["edge", "run", "--config", str(HIL_JOINT), "--bundle", str(bundle), "--json", "--duration", "10"]
    assert main(run + ["--reference", "sine:amplitude=12,frequency=0.2,offset=-12", "--settle", "5"]) == 0
    assert json.loads(capsys.readouterr().out)["faults"] == []


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--protocol", "triangle"], "unknown; use one of triangles"),
        (["--protocol", "triangles", "--range", "0:9"], "leaves the config's 0..6 bar"),
        (["--protocol", "triangles", "--range", "3:1"], "LOW < HIGH"),
        (["--protocol", "sines:amplitudes=2"], "at most 1"),
        (["--protocol", "chirp:f0=-1"], "must be finite and > 0"),
        (["--protocol", "triangles", "--sample-hz", "300"], "must divide the loop rate"),
        (["--protocol", "triangles", "--duration", "0"], "--duration 0"),
    ],
)
def test_bad_record_options_are_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], extra: list[str], message: str
) -> None:
    csv = tmp_path / "run.csv"
    assert main(["edge", "record", "--config", str(HIL_RIG), "--out", str(csv), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err
    assert not csv.exists()


def test_existing_recording_is_never_overwritten(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    csv = tmp_path / "run.csv"
    csv.write_text("precious\n")
    args = ["edge", "record", "--config", str(HIL_RIG), "--protocol", "triangles", "--out", str(csv)]
    assert main(args) == 2
    assert "exists" in capsys.readouterr().err
    assert csv.read_text() == "precious\n"


def test_protocol_csv_out_of_range_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    own = tmp_path / "own.csv"
    own.write_text("t,pressure\n0,0\n5,2\n10,7\n")
    args = ["edge", "record", "--config", str(HIL_RIG), "--protocol", str(own), "--out", str(tmp_path / "r.csv")]
    assert main(args + ["--range", "0:6"]) == 2
    assert "leave the allowed 0..6 bar" in capsys.readouterr().err
    own.write_text("t,pressure\n0,0\n5,2\n10,1\n")
    assert main(args + ["--range", "0:6"]) == 0
    data = load_measurement(tmp_path / "r.csv")
    assert data.u[np.searchsorted(data.t, 5.0)] == pytest.approx(2.0, abs=1e-3)


def test_triangles_are_seed_000s() -> None:
    protocol = build_protocol("triangles", 0.0, 4.0, 0.001)
    values = protocol.values
    assert protocol.duration_s == pytest.approx(80.0)
    peaks = [values[int(round((10.0 + 20.0 * k) / 0.001))] for k in range(4)]
    assert peaks == pytest.approx([1.0, 2.0, 3.0, 4.0], abs=1e-3)
    assert values[::20_000] == pytest.approx([0.0] * 4, abs=1e-9)


@pytest.mark.parametrize("name", list(PROTOCOLS))
def test_every_protocol_starts_low_and_stays_in_range(name: str) -> None:
    values = build_protocol(name, 0.5, 3.5, 0.001).values
    assert values[0] == pytest.approx(0.5)
    assert values.min() >= 0.5 - 1e-9 and values.max() <= 3.5 + 1e-9
    assert values.max() - values.min() > 1.0  # it excites


def test_duration_repeats_the_protocol_and_cuts() -> None:
    protocol = build_protocol("triangles:levels=2", 0.0, 2.0, 0.01, duration_s=100.0)
    assert protocol.duration_s == pytest.approx(100.0)
    assert protocol(50.0) == pytest.approx(protocol(10.0), abs=1e-6) == pytest.approx(1.0, abs=1e-3)


@pytest.mark.realtime
@pytest.mark.parametrize("signal_name", ["SIGTERM", "SIGINT"])
def test_a_signal_mid_record_keeps_every_row_and_closes_the_sidecar(tmp_path: Path, signal_name: str) -> None:
    """SIGTERM (a service stop) or SIGINT (Ctrl-C) mid-record: exit 0, the valve vented, every row
    written before the stop is in the CSV and the sidecar says it stopped and is complete."""
    import signal
    import subprocess
    import sys
    import time

    config = rig_file(tmp_path, "sim://rig?clock=realtime")
    csv = tmp_path / "run.csv"
    command = [sys.executable, "-m", "host.cli", "edge", "record", "--config", str(config)]
    command += ["--protocol", "steps", "--out", str(csv), "--json"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and (not csv.exists() or len(csv.read_text().splitlines()) < 100):
            time.sleep(0.05)  # recording and flushing
        process.send_signal(getattr(signal, signal_name))
        out, err = process.communicate(timeout=20)
    finally:
        process.kill()
    assert process.returncode == 0, err
    summary = json.loads(out)
    assert "stopped (valve vented)" in err and summary["faults"] == []
    rows = np.loadtxt(csv, delimiter=",", skiprows=1, ndmin=2)  # as written (a loaded machine spaces them unevenly)
    assert len(rows) == summary["rows"] >= 100 and np.all(np.isfinite(rows)) and np.all(np.diff(rows[:, 0]) > 0)
    meta = json.loads((tmp_path / "run.meta.json").read_text())
    assert meta["stopped"] == "stop" and meta["complete"] is True and meta["rows"] == summary["rows"]
