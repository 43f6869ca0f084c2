"""A terminal that talks: ``pmactl edge run`` and ``record`` on a real pseudo-terminal say how
to stop and draw a status line; piped, they stay quiet. Ctrl-C (SIGINT) during a real-time
recording vents and keeps every row."""

from __future__ import annotations

import json
import os
import pty
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

from tests.edge_helpers import HIL_RIG

PMACTL = [sys.executable, "-m", "host.cli"]


def on_pty(args: list[str], interrupt_after_s: float | None = None, timeout_s: float = 120.0) -> tuple[str, int]:
    """Run ``pmactl args`` with stdin, stdout and stderr on a new pseudo-terminal; returns what
    the terminal showed and the exit status (SIGINT sent after ``interrupt_after_s``)."""
    master, slave = pty.openpty()
    process = subprocess.Popen([*PMACTL, *args], stdin=slave, stdout=slave, stderr=slave, close_fds=True)
    os.close(slave)
    shown = b""
    start = time.monotonic()
    interrupted = False
    try:
        while time.monotonic() - start < timeout_s:
            if interrupt_after_s is not None and not interrupted and time.monotonic() - start > interrupt_after_s:
                process.send_signal(signal.SIGINT)
                interrupted = True
            ready, _, _ = select.select([master], [], [], 0.2)
            if ready:
                try:
                    data = os.read(master, 65536)
                except OSError:  # the other side closed
                    break
                if not data:
                    break
                shown += data
            elif process.poll() is not None:
                break
        status = process.wait(timeout=30)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        os.close(master)
    return shown.decode(errors="replace"), status


def realtime_rig(tmp_path: Path) -> Path:
    """The emulated rig on the wall clock at 200 Hz, overruns of a loaded test machine tolerated
    (these tests are about the terminal, not the schedule)."""
    text = HIL_RIG.read_text().replace('url = "sim://rig?clock=lockstep"', 'url = "sim://rig?clock=realtime"')
    text = text.replace("rate_hz = 1000", "rate_hz = 200").replace("overrun_streak = 5", "overrun_streak = 1000")
    path = tmp_path / "rig.toml"
    path.write_text(text)
    return path


def test_record_on_a_terminal_says_how_to_stop_and_shows_status(tmp_path: Path) -> None:
    csv = tmp_path / "run.csv"
    args = ["edge", "record", "--config", str(realtime_rig(tmp_path)), "--protocol", "steps:levels=2,hold=1.5"]
    shown, status = on_pty([*args, "--out", str(csv)])
    assert status == 0, shown
    assert "Ctrl-C stops and vents" in shown
    lines = [part for part in shown.split("\r\x1b[K")[1:] if part.startswith("running")]
    assert len(lines) >= 3, shown  # one a second over 7.5 s
    assert "p " in lines[-1] and "faults none" in lines[-1]


def test_run_status_shows_tracking_error(tmp_path: Path) -> None:
    from tests.edge_helpers import fit_bundle

    bundle = fit_bundle(tmp_path / "bundle")
    args = ["edge", "run", "--config", str(realtime_rig(tmp_path)), "--bundle", str(bundle), "--duration", "4"]
    shown, status = on_pty(args)
    assert status == 0, shown
    assert "Ctrl-C stops and vents" in shown
    assert any("RMS" in part and "max" in part for part in shown.split("\r\x1b[K")), shown


def test_piped_or_json_is_quiet(tmp_path: Path) -> None:
    csv = tmp_path / "run.csv"
    args = [*PMACTL, "edge", "record", "--config", str(HIL_RIG), "--protocol", "steps:levels=1,hold=1"]
    piped = subprocess.run([*args, "--out", str(csv)], capture_output=True, text=True, timeout=120)
    assert piped.returncode == 0 and piped.stderr == "", piped.stderr
    shown, status = on_pty(["edge", "record", "--config", str(HIL_RIG), "--protocol", "steps:levels=1,hold=1",
                            "--out", str(tmp_path / "b.csv"), "--json"])  # fmt: skip
    assert status == 0 and "Ctrl-C" not in shown and shown.lstrip().startswith("{")


def test_ctrl_c_during_a_recording_vents_and_keeps_the_rows(tmp_path: Path) -> None:
    csv = tmp_path / "run.csv"
    args = ["edge", "record", "--config", str(realtime_rig(tmp_path)), "--protocol", "triangles"]
    shown, status = on_pty([*args, "--out", str(csv)], interrupt_after_s=4.0)
    assert status == 0, shown
    rows = csv.read_text().splitlines()[1:]
    last_t = float(rows[-1].split(",")[0])
    assert 1.0 < last_t < 10.0  # stopped early, every row up to the stop kept
    assert f"{len(rows)} rows" in shown and "stopped (valve vented)" in shown
    meta = json.loads(csv.with_name("run.meta.json").read_text())
    assert meta["stopped"] == "stop" and meta["rows"] == len(rows) and meta["complete"]
