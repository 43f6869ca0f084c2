"""``pmactl edge probe``: every input read with the valve disabled, shown live on a real
pseudo-terminal, and the two-point calibration typed at it."""

from __future__ import annotations

import json
import os
import pty
import re
import select
import subprocess
import sys
import time
from pathlib import Path

import pytest

from edge.runtime.probe import two_point
from host.cli import main
from tests.edge_helpers import HIL_RIG

PMACTL = [sys.executable, "-m", "host.cli"]


class Terminal:
    """``pmactl`` on a new pseudo-terminal (stdin, stdout and stderr), read and typed at."""

    def __init__(self, args: list[str]) -> None:
        self.master, slave = pty.openpty()
        self.process = subprocess.Popen([*PMACTL, *args], stdin=slave, stdout=slave, stderr=slave, close_fds=True)
        os.close(slave)
        self.shown = b""

    def read_until(self, marker: bytes | None, timeout_s: float = 60.0) -> bool:
        start = time.monotonic()
        while time.monotonic() - start < timeout_s:
            ready, _, _ = select.select([self.master], [], [], 0.1)
            if ready:
                try:
                    data = os.read(self.master, 65536)
                except OSError:
                    return False
                if not data:
                    return False
                self.shown += data
                if marker is not None and marker in self.shown:
                    return True
            elif self.process.poll() is not None:
                return False
        return False

    def type(self, text: str) -> None:
        os.write(self.master, text.encode())

    def finish(self) -> tuple[str, int]:
        self.read_until(None, 30.0)
        status = self.process.wait(timeout=30)
        os.close(self.master)
        return self.shown.decode(errors="replace"), status


def rig_with(tmp_path: Path, query: str) -> Path:
    path = tmp_path / "rig.toml"
    path.write_text(HIL_RIG.read_text().replace("sim://rig?clock=lockstep", f"sim://rig?clock=lockstep&{query}"))
    return path


def test_probe_draws_every_input_live_with_the_valve_disabled() -> None:
    terminal = Terminal(["edge", "probe", "--config", str(HIL_RIG), "--duration", "1.5"])
    shown, status = terminal.finish()
    assert status == 0, shown
    assert "valve disabled" in shown and "Ctrl-C stops" in shown
    frames = shown.count("\x1b[5F")  # the table (header, titles, 3 channels) redrawn in place
    assert frames >= 5, shown
    last = shown.rsplit("\x1b[5F", 1)[-1]
    contraction = re.search(r"contraction\s+adc:1\s+([\d.]+) V\s+(-?[\d.]+) mm", last)
    assert contraction, last
    volts, value = float(contraction[1]), float(contraction[2])
    assert (volts - 0.20625) * 48.484848 == pytest.approx(value, abs=0.01)  # raw and scaled agree
    assert -2.0 < value < 1.0  # the valve is vented: the muscle rests
    assert re.search(r"pressure\s+adc:0\s+0\.\d+ V", last) and "estop" in last and "released" in last


def test_probe_json_reports_min_max_and_no_overruns(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["edge", "probe", "--config", str(HIL_RIG), "--duration", "0.5", "--json"]) == 0
    report = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert report["overruns"] == 0 and report["ticks"] >= 499
    pressure = report["channels"]["pressure"]
    assert pressure["min"] <= pressure["value"] <= pressure["max"] and abs(pressure["value"]) < 0.05


def test_two_point_calibration_typed_on_a_terminal(tmp_path: Path) -> None:
    """The pressure transducer at rest (0 bar), then driven to its supply rail (3.3 V, which the
    emulator's true wiring 0.5 V + 2.5 bar/V calls 7 bar): the printed lines recover that wiring."""
    config = rig_with(tmp_path, "faults=pressure_high@3")
    terminal = Terminal(["edge", "probe", "--config", str(config), "--calibrate", "pressure"])
    assert terminal.read_until(b"point 1 of 2"), terminal.shown
    terminal.type("0\n")
    assert terminal.read_until(b"point 2 of 2"), terminal.shown
    assert terminal.read_until(b"3.30000 V", timeout_s=30), terminal.shown  # the live value moved
    terminal.type("7\n")
    shown, status = terminal.finish()
    assert status == 0, shown
    scale = float(re.search(r"^scale = (\S+)", shown, re.M)[1])  # type: ignore[index]
    zero = float(re.search(r"^zero = (\S+)", shown, re.M)[1])  # type: ignore[index]
    assert scale == pytest.approx(2.5, rel=0.01) and zero == pytest.approx(0.5, abs=0.005)


def test_two_points_at_the_same_reading_are_refused(tmp_path: Path) -> None:
    args = [*PMACTL, "edge", "probe", "--config", str(HIL_RIG), "--calibrate", "contraction"]
    result = subprocess.run(args, input="0\n50\n", capture_output=True, text=True, timeout=120)
    assert result.returncode == 2
    assert result.stderr.count("\n") == 1 and "within the noise" in result.stderr


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--calibrate", "estop"], "a line (0/1) has no scale"),
        (["--calibrate", "force"], "no such input channel"),
        (["--rate", "5000"], "at most"),
        (["--duration", "-1"], "--duration -1"),
    ],
)
def test_bad_probe_options_are_one_line(capsys: pytest.CaptureFixture[str], extra: list[str], message: str) -> None:
    assert main(["edge", "probe", "--config", str(HIL_RIG), *extra]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_two_point_arithmetic_inverts_the_config_form() -> None:
    scale, zero = two_point(10.0, 0.7, 60.0, 1.9)
    assert (0.7 - zero) * scale == pytest.approx(10.0) and (1.9 - zero) * scale == pytest.approx(60.0)
