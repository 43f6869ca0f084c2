"""docs/guide/rig.md walked end to end on the emulated rig: wire -> probe -> calibrate ->
record -> fit -> sign -> deploy -> run -> read back -> diagnose, each step the guide's command
(the deploy target a local directory, the calibration's second point the transducer driven to
its rail by an injected fault, since nothing moves an emulated sensor by hand)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest

from host.cli import main
from tests.edge_helpers import HIL_RIG

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide" / "rig.md"
PMACTL = [sys.executable, "-m", "host.cli"]


def guide_commands() -> list[str]:
    """The one-command-per-step table of the guide."""
    rows = re.findall(r"^\| \d+\. [a-z ]+ \| (.+) \|$", GUIDE.read_text(), re.M)
    return [cell for row in rows for cell in re.findall(r"`(pmactl [^`]+)`", row)]


def pmactl(command: str, capsys: pytest.CaptureFixture[str], expect: int = 0) -> str:
    assert command.startswith("pmactl ")
    status = main(command.split()[1:])
    captured = capsys.readouterr()
    assert status == expect, (command, captured.err)
    return captured.out + captured.err


def test_the_guide_walks_from_wire_to_diagnosis(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    commands = guide_commands()
    assert [c.split()[1:3] for c in commands][:3] == [["edge", "probe"], ["edge", "probe"], ["edge", "record"]]
    commands = [c.replace("/opt/pmactl/bundle", str(tmp_path / "target")) for c in commands]
    # 1. wire: the emulated rig's config
    Path("rig.toml").write_text(HIL_RIG.read_text())
    # 2. probe (bounded: the guide's runs until Ctrl-C)
    out = pmactl(commands[0] + " --duration 1", capsys)
    assert "valve disabled" in out and "contraction" in out and "released" in out
    # 3. calibrate (typed into a real process; the second point after the rail fault at 2 s)
    faulty = Path("rig-cal.toml")
    faulty.write_text(HIL_RIG.read_text().replace("clock=lockstep", "clock=lockstep&faults=pressure_high@2"))
    command = commands[1].replace("rig.toml", str(faulty)).replace("contraction", "pressure").split()[1:]
    process = subprocess.Popen([*PMACTL, *command], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    assert process.stdin is not None
    process.stdin.write("0\n")
    process.stdin.flush()
    time.sleep(4.0)  # the probe paces the emulated rig at wall-clock speed
    stdout, _ = process.communicate("7\n", timeout=60)
    assert process.returncode == 0, stdout
    assert float(re.search(r"^zero = (\S+)", stdout, re.M)[1]) == pytest.approx(0.5, abs=0.005)  # type: ignore[index]
    assert float(re.search(r"^scale = (\S+)", stdout, re.M)[1]) == pytest.approx(2.5, rel=0.01)  # type: ignore[index]
    # 4. record, 5. fit
    assert "8000 rows" in pmactl(commands[2], capsys)
    pmactl(commands[3], capsys)
    # 6. sign (keygen once, then sign), and trust the key in the config
    pmactl(commands[4], capsys)
    assert "signed release" in pmactl(commands[5], capsys)
    Path("rig.toml").write_text(
        Path("rig.toml").read_text().replace("trusted_keys = []", 'trusted_keys = ["keys/pmactl.pub"]')
    )
    # 7. deploy to a local directory
    assert "deployed release" in pmactl(commands[6], capsys)
    # 8. run, and the same run with PID alone for the comparison the guide quotes
    run = commands[7]
    pmactl(run, capsys)
    with_model = json.loads(pmactl(run.replace("run.pmt", "run-json.pmt") + " --json", capsys).splitlines()[0])
    pid = json.loads(pmactl(run.replace("run.pmt", "pid.pmt") + " --json --no-feedforward", capsys).splitlines()[0])
    assert with_model["faults"] == [] and with_model["rms_error"] <= 0.3 * pid["rms_error"]
    # 9. read back
    out = pmactl(commands[8], capsys)
    assert "25000 ticks" in out and Path("run-telemetry.csv").stat().st_size > 0
    # 10. diagnose
    out = pmactl(commands[9], capsys)
    assert out.startswith("triangles.csv: cause")
