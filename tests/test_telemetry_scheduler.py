"""Telemetry ring and file, the scheduler's deadlines and lateness accounting, real-time setup."""

from __future__ import annotations

import csv
import json
import time

import numpy as np
import pytest

from edge.errors import DataError
from edge.runtime.scheduler import LatenessStats, TickScheduler, apply_realtime
from edge.runtime.telemetry import TelemetryWriter, read_telemetry
from hil.clock import SimClock
from host.cli import main

DTYPE = np.dtype([("t", "<f8"), ("reference_mm", "<f8"), ("contraction_mm", "<f8"), ("u_bar", "<f8"),
                  ("u_ff_bar", "<f8"), ("u_nn_bar", "<f8"), ("u_fb_bar", "<f8"), ("lateness_us", "<f8"),
                  ("state", "<i4"), ("fault", "<i4")])  # fmt: skip
COLUMNS = DTYPE.names


def row(i: int) -> np.ndarray:
    value = np.zeros((), dtype=DTYPE)
    for name in COLUMNS:
        value[name] = i
    value["t"] = i * 0.001
    return value


def writer_with(path, n: int, **kwargs) -> TelemetryWriter:
    writer = TelemetryWriter(path, {"rate_hz": 1000, "reference": "const:value=1"}, DTYPE, **kwargs)
    for i in range(n):
        writer.record_array(row(i))
    return writer


def test_every_row_reaches_the_file_in_order_across_ring_wraps(tmp_path):
    writer = TelemetryWriter(tmp_path / "t.pmt", {"rate_hz": 1000}, DTYPE, ring_ticks=1024, flush_interval_s=0.001)
    for i in range(10_000):
        writer.record_array(row(i))
        if i % 500 == 0:
            # ticks are spread in time: give the writer thread its turn, however loaded the
            # machine (a fixed sleep let a busy scheduler overrun the ring; that is not a defect)
            deadline = time.monotonic() + 10.0
            while writer._tail < writer._head and time.monotonic() < deadline:
                time.sleep(0.001)
    writer.event(10.0, "note", "done")
    writer.close()
    record = read_telemetry(tmp_path / "t.pmt")
    assert len(record.rows) == 10_000 and writer.dropped == 0 and record.columns == list(COLUMNS)
    assert np.array_equal(record.column("reference_mm"), np.arange(10_000, dtype=float))
    assert record.rows["state"].dtype == np.int32 and record.rows["state"][-1] == 9999
    assert record.events == [{"t": 10.0, "kind": "note", "text": "done"}]


def test_a_writer_that_falls_behind_drops_the_oldest_rows_and_counts_them(tmp_path):
    writer = writer_with(tmp_path / "t.pmt", 3000, ring_ticks=1024, flush_interval_s=60.0)  # the ring overflows
    writer.close()
    record = read_telemetry(tmp_path / "t.pmt")
    assert writer.dropped == 3000 - 1024 and len(record.rows) == 1024
    assert record.column("reference_mm")[0] == 3000 - 1024  # the newest survive


def test_a_second_run_to_the_same_path_is_refused_and_the_first_is_kept(tmp_path):
    writer_with(tmp_path / "t.pmt", 10).close()
    before = (tmp_path / "t.pmt").read_bytes()
    with pytest.raises(DataError, match="exists, and a run never overwrites another"):
        writer_with(tmp_path / "t.pmt", 5)
    assert (tmp_path / "t.pmt").read_bytes() == before


def test_a_full_disk_becomes_a_failure_not_a_dead_thread(tmp_path):
    """/dev/full answers every write with ENOSPC, as a full disk does."""
    writer = writer_with(tmp_path / "t.pmt", 10, flush_interval_s=0.001)
    writer._file.close()
    writer._file = open("/dev/full", "wb")  # noqa: SIM115 - the disk fills up mid-run
    for i in range(10, 2000):
        writer.record_array(row(i))
    deadline = time.monotonic() + 5
    while writer.failure is None and time.monotonic() < deadline:
        time.sleep(0.005)
    writer.close()  # does not raise either
    assert writer.failure is not None and "No space left on device" in writer.failure
    assert not writer._thread.is_alive()


def test_a_partial_last_row_is_ignored_and_reported(tmp_path):
    writer_with(tmp_path / "t.pmt", 10).close()
    with (tmp_path / "t.pmt").open("ab") as handle:
        handle.write(b"\x00" * 20)  # power cut in the middle of a row
    record = read_telemetry(tmp_path / "t.pmt")
    assert (
        len(record.rows) == 10
        and record.truncated_bytes == 20
        and "20 bytes of a partial last row" in record.problems[0]
    )


def test_a_file_that_is_not_telemetry_is_refused(tmp_path):
    (tmp_path / "x.csv").write_text("t,u\n")
    with pytest.raises(DataError, match="not a pmactl telemetry file"):
        read_telemetry(tmp_path / "x.csv")


def damage(path, how):
    data = path.read_bytes()
    magic_end = data.index(b"\n") + 1
    header_end = data.index(b"\n", magic_end)
    header = json.loads(data[magic_end:header_end])
    if how == "cut in header":
        path.write_bytes(data[: magic_end + 30])
    elif how == "bad header json":
        path.write_bytes(data[:magic_end] + b"{not json" + data[header_end:])
    elif how == "no columns":
        header["columns"] = []
        path.write_bytes(data[:magic_end] + json.dumps(header).encode() + data[header_end:])
    elif how == "bad dtype":
        header["dtype"] = [["t", "<q99"]]
        path.write_bytes(data[:magic_end] + json.dumps(header).encode() + data[header_end:])


@pytest.mark.parametrize(
    ("how", "message"),
    [
        ("cut in header", "cut off inside its header"),
        ("bad header json", "header is not valid JSON"),
        ("no columns", "header has no column list"),
        ("bad dtype", "is not a row type"),
    ],
)
def test_pmactl_edge_telemetry_on_an_unreadable_file_says_why_in_one_line(tmp_path, capsys, how, message):
    path = tmp_path / "t.pmt"
    writer_with(path, 10).close()
    damage(path, how)
    assert main(["edge", "telemetry", str(path)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and err.count("\n") == 0 and "Traceback" not in err


def test_pmactl_edge_telemetry_on_a_directory_is_one_line(tmp_path, capsys):
    assert main(["edge", "telemetry", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err


def test_a_corrupt_event_line_is_skipped_and_named_the_rest_read(tmp_path, capsys):
    path = tmp_path / "t.pmt"
    writer = writer_with(path, 10)
    writer.event(0.001, "arm", "armed")
    writer.event(0.009, "fault", "e-stop pressed")
    writer.close()
    log = tmp_path / "t.pmt.events.jsonl"
    lines = log.read_text().splitlines()
    log.write_text("\n".join([lines[0], '{"t": 0.005, "kind": "no', lines[1]]) + "\n")
    assert main(["edge", "telemetry", str(path)]) == 0
    captured = capsys.readouterr()
    assert "t=0.009 s fault: e-stop pressed" in captured.out and "10 ticks" in captured.out
    assert "events.jsonl line 2 is damaged and was skipped" in captured.err


def test_pmactl_edge_telemetry_writes_csv_mcap_and_a_plot(tmp_path, capsys):
    from mcap.reader import make_reader

    writer = writer_with(tmp_path / "t.pmt", 100)
    writer.event(0.05, "fault", "e-stop pressed")
    writer.close()
    args = ["edge", "telemetry", str(tmp_path / "t.pmt"), "--csv", str(tmp_path / "t.csv")]
    assert main([*args, "--plot", str(tmp_path / "t.png"), "--mcap", str(tmp_path / "t.mcap")]) == 0
    assert "t=0.050 s fault: e-stop pressed" in capsys.readouterr().out
    with (tmp_path / "t.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 100 and list(rows[0]) == list(COLUMNS) and float(rows[99]["t"]) == pytest.approx(0.099)
    assert (tmp_path / "t.png").stat().st_size > 10_000
    with (tmp_path / "t.mcap").open("rb") as handle:
        messages = [(c.topic, json.loads(m.data), m.log_time) for _, c, m in make_reader(handle).iter_messages()]
    ticks = [m for topic, m, _ in messages if topic == "/pmactl/tick"]
    events = [m for topic, m, _ in messages if topic == "/pmactl/events"]
    assert len(ticks) == 100 and ticks[42]["reference_mm"] == 42.0 and ticks[42]["t"] == pytest.approx(0.042)
    assert events == [{"t": 0.05, "kind": "fault", "text": "e-stop pressed"}]
    tick_times = [stamp for topic, _, stamp in messages if topic == "/pmactl/tick"]
    assert tick_times == sorted(tick_times) and tick_times[1] - tick_times[0] == 1_000_000  # ns


class JumpyClock(SimClock):
    """A simulated clock whose sleeps overshoot by a scripted amount [s]."""

    def __init__(self, overshoot_s: dict[int, float]) -> None:
        super().__init__()
        self.calls, self.overshoot_s = 0, overshoot_s

    def sleep_until(self, deadline: float) -> None:
        super().sleep_until(deadline + self.overshoot_s.get(self.calls, 0.0))
        self.calls += 1


def test_deadlines_are_absolute_and_an_overrun_skips_the_missed_slots():
    scheduler = TickScheduler(JumpyClock({3: 0.0002, 5: 0.0025}), period_s=0.001)
    scheduler.start()
    ticks = [scheduler.wait() for _ in range(8)]
    times = [round(t, 6) for t, _ in ticks]
    assert times == [0.0, 0.001, 0.002, 0.003, 0.004, 0.007, 0.008, 0.009]  # 5 and 6 skipped
    assert ticks[3][1] == pytest.approx(0.0002)  # late but within the period: no overrun
    stats = scheduler.stats
    assert stats.overruns == 1 and stats.skipped_ticks == 2 and stats.worst_us == pytest.approx(2500, abs=1e-3)


def test_lateness_percentiles_come_from_the_histogram():
    stats = LatenessStats()
    for value in list(range(1000)) + [5000.0] * 10:
        stats.add(float(value))
    summary = stats.summary()
    assert summary["lateness_median_us"] == pytest.approx(505, abs=1)
    assert summary["lateness_p99_us"] == pytest.approx(1000, abs=1)  # the 1000th of 1010 values is 999
    assert summary["lateness_max_us"] == 5000.0 and summary["ticks"] == 1010


def test_realtime_settings_say_what_was_done_and_are_given_back():
    settings = apply_realtime(priority=10, cpu=0, lock_memory=False)
    try:
        assert any(n.startswith("SCHED_FIFO") for n in settings.notes)
        assert any("CPU 0" in n for n in settings.notes)
    finally:
        settings.restore()
    import os

    assert os.sched_getscheduler(0) == os.SCHED_OTHER
