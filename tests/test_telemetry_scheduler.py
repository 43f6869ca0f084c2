"""Telemetry ring and file, the scheduler's deadlines and lateness accounting, real-time setup."""

from __future__ import annotations

import csv
import time

import numpy as np
import pytest

from edge.errors import DataError
from edge.runtime.scheduler import LatenessStats, TickScheduler, apply_realtime
from edge.runtime.telemetry import COLUMNS, TelemetryWriter, read_telemetry
from hil.clock import SimClock
from host.cli import main


def row(i: int) -> tuple[float, ...]:
    return (i * 0.001,) + (float(i),) * (len(COLUMNS) - 1)


def test_every_row_reaches_the_file_in_order_across_ring_wraps(tmp_path):
    writer = TelemetryWriter(tmp_path / "t.pmt", {"rate_hz": 1000}, ring_ticks=1024, flush_interval_s=0.001)
    for i in range(10_000):
        writer.record(row(i))
        if i % 500 == 0:
            time.sleep(0.01)  # ticks are spread in time; give the writer thread its turn
    writer.event(10.0, "note", "done")
    writer.close()
    record = read_telemetry(tmp_path / "t.pmt")
    assert record.rows.shape == (10_000, len(COLUMNS)) and writer.dropped == 0
    assert np.array_equal(record.column("reference_mm"), np.arange(10_000, dtype=float))
    assert record.events == [{"t": 10.0, "kind": "note", "text": "done"}]


def test_a_writer_that_falls_behind_drops_the_oldest_rows_and_counts_them(tmp_path):
    writer = TelemetryWriter(tmp_path / "t.pmt", {}, ring_ticks=1024, flush_interval_s=60.0)
    for i in range(3000):  # the thread sleeps for a minute: the ring overflows
        writer.record(row(i))
    writer.close()
    record = read_telemetry(tmp_path / "t.pmt")
    assert writer.dropped == 3000 - 1024 and len(record.rows) == 1024
    assert record.column("reference_mm")[0] == 3000 - 1024  # the newest survive


def test_a_partial_last_row_is_ignored_and_reported(tmp_path):
    writer = TelemetryWriter(tmp_path / "t.pmt", {}, ring_ticks=1024)
    for i in range(10):
        writer.record(row(i))
    writer.close()
    with (tmp_path / "t.pmt").open("ab") as handle:
        handle.write(b"\x00" * 20)  # power cut in the middle of a row
    record = read_telemetry(tmp_path / "t.pmt")
    assert len(record.rows) == 10 and record.truncated_bytes == 20


def test_a_file_that_is_not_telemetry_is_refused(tmp_path):
    (tmp_path / "x.csv").write_text("t,u\n")
    with pytest.raises(DataError, match="not a pmactl telemetry file"):
        read_telemetry(tmp_path / "x.csv")


def test_pmactl_edge_telemetry_writes_csv_and_a_plot(tmp_path, capsys):
    writer = TelemetryWriter(tmp_path / "t.pmt", {"rate_hz": 1000, "reference": "const:value=1"}, ring_ticks=1024)
    for i in range(100):
        writer.record(row(i))
    writer.event(0.05, "fault", "e-stop pressed")
    writer.close()
    args = ["edge", "telemetry", str(tmp_path / "t.pmt"), "--csv", str(tmp_path / "t.csv")]
    assert main([*args, "--plot", str(tmp_path / "t.png")]) == 0
    assert "t=0.050 s fault: e-stop pressed" in capsys.readouterr().out
    with (tmp_path / "t.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 100 and list(rows[0]) == list(COLUMNS) and float(rows[99]["t"]) == pytest.approx(0.099)
    assert (tmp_path / "t.png").stat().st_size > 10_000


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
