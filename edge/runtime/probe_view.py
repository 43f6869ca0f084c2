"""What ``pmactl edge probe`` shows: a live table of every input channel (redrawn in place on
a terminal, printed once at the end otherwise), and the two-point calibration dialogue.

The calibration reads the known values from standard input without blocking the reads (a
person types while the live value above the prompt keeps moving; values piped in are taken in
turn). Each point averages ``average_s`` of raw readings after its value is entered.
"""

from __future__ import annotations

import math
import os
import select
import statistics
import time
from collections.abc import Callable
from typing import TextIO

from edge.errors import DataError
from edge.runtime.probe import ChannelStats, Probe, check_points, two_point
from edge.runtime.rigspec import ANALOG_IN


def _number(value: float, digits: int = 4) -> str:
    return f"{value:.{digits}g}" if math.isfinite(value) else "-"


def channel_line(stats: ChannelStats) -> str:
    c = stats.channel
    where = f"{c.device}:{c.input if c.input is not None else '-'}"
    if stats.errors and not math.isfinite(stats.value):
        return f"{c.name:<14}{where:<12}read failed ({stats.last_error}, {stats.errors} times)"
    if c.kind == ANALOG_IN:
        raw = f"{stats.raw:8.4f} V" if math.isfinite(stats.raw) else "       - V"
        text = (
            f"{c.name:<14}{where:<12}{raw}  {_number(stats.value):>9} {c.unit:<5}"
            f" min {_number(stats.minimum):>9}  max {_number(stats.maximum):>9}"
        )
    else:
        state = "-" if not math.isfinite(stats.value) else ("1 (active)" if stats.value else "0")
        if c.name == "estop" and math.isfinite(stats.value):
            state = "PRESSED" if stats.value else "released"
        text = f"{c.name:<14}{where:<12}line {state}"
    return text + (f"  ({stats.errors} read errors, last {stats.last_error})" if stats.errors else "")


def table(probe: Probe) -> list[str]:
    head = (
        f"{probe.config.source}: t {probe.t:6.1f} s at {probe.rate_hz:g} Hz, valve disabled"
        f"{', emulated' if probe.rig.lockstep else ''}"
    )
    return [head, f"{'channel':<14}{'dev:input':<12}{'raw':>10}  {'value':>9} unit", *map(channel_line, probe.channels)]


def as_dict(probe: Probe) -> dict[str, object]:
    stats = probe.scheduler.stats.summary()
    return {
        "t": probe.t,
        "rate_hz": probe.rate_hz,
        "ticks": stats["ticks"],
        "overruns": stats["overruns"],
        "channels": {
            s.channel.name: {
                "unit": s.channel.unit,
                "value": s.value if math.isfinite(s.value) else None,
                "raw": s.raw if math.isfinite(s.raw) else None,
                "min": s.minimum if math.isfinite(s.minimum) else None,
                "max": s.maximum if math.isfinite(s.maximum) else None,
                "read_errors": s.errors,
            }
            for s in probe.channels
        },
    }


def watch(
    probe: Probe, duration_s: float | None, out: TextIO, live: bool, stop: Callable[[], bool], quiet: bool = False
) -> None:
    """Read until the duration or a stop; on a terminal (``live``) redraw the table in place."""
    drawn = 0

    def refresh(p: Probe) -> bool:
        nonlocal drawn
        if live:
            lines = table(p)
            out.write((f"\x1b[{drawn}F" if drawn else "") + "".join(f"\x1b[K{line}\n" for line in lines))
            out.flush()
            drawn = len(lines)
        return True

    if live:
        out.write("pmactl edge probe: reading every input, the valve disabled; Ctrl-C stops\n")
    probe.run(duration_s, refresh, stop=stop)
    if not live and not quiet:
        out.write("\n".join(table(probe)) + "\n")
    out.flush()


class Calibration:
    """The dialogue of ``--calibrate CHANNEL`` (module docstring), driven from the probe's refresh."""

    def __init__(self, probe: Probe, name: str, average_s: float, stdin_fd: int, out: TextIO, live: bool) -> None:
        self.probe, self.stats, self.average_s = probe, probe.channel(name), average_s
        self.fd, self.out, self.live = stdin_fd, out, live
        self.points: list[tuple[float, float, float]] = []
        self._buffer = b""
        self._pending: list[str] = []
        self._until: float | None = None
        self._value = math.nan
        self._eof = False

    @property
    def unit(self) -> str:
        return self.stats.channel.unit

    def prompt(self) -> None:
        n = len(self.points) + 1
        if self.live:
            self.out.write("\n")  # the live value is drawn on this line, above the prompt
        self.out.write(
            f"point {n} of 2: set {self.stats.channel.name} to a known value, type it in {self.unit} and press Enter: "
        )
        self.out.flush()

    def _read_lines(self) -> None:
        while not self._eof:
            ready, _, _ = select.select([self.fd], [], [], 0)
            if not ready:
                return
            chunk = os.read(self.fd, 4096)
            if not chunk:
                self._eof = True
                if self._buffer.strip():
                    self._pending.append(self._buffer.decode(errors="replace"))
                return
            self._buffer += chunk
            *lines, self._buffer = self._buffer.split(b"\n")
            self._pending += [line.decode(errors="replace") for line in lines]

    def refresh(self, probe: Probe) -> bool:
        stats = self.stats
        if self.live and self._until is None:
            live = f"  live: {stats.raw:.5f} V = {_number(stats.value)} {self.unit}"
            self.out.write(f"\x1b7\x1b[1A\r\x1b[K{live}\x1b8")
            self.out.flush()
        if self._until is not None:
            if probe.t < self._until:
                return True
            return self._finish_point()
        self._read_lines()
        while self._pending and self._until is None:
            text = self._pending.pop(0).strip()
            try:
                value = float(text)
                if not math.isfinite(value):
                    raise ValueError
            except ValueError:
                self.out.write(f"{text!r} is not a number; type the known value in {self.unit}\n")
                self.prompt()
                continue
            self._value, self._until = value, probe.t + self.average_s
            stats.samples = []
            probe.averaging = stats
            if not self.live:
                self.out.write(f"{text}\n")
        if self._until is None and self._eof and not self._pending:
            raise DataError(f"--calibrate {stats.channel.name}: input ended before both points were entered")
        return True

    def _finish_point(self) -> bool:
        samples = self.stats.samples
        self.probe.averaging, self._until = None, None
        if len(samples) < 2:
            raise DataError(
                f"--calibrate {self.stats.channel.name}: no readings while averaging (read errors: "
                f"{self.stats.errors}, last {self.stats.last_error or 'none'}); check the wiring"
            )
        mean, sd = statistics.fmean(samples), statistics.stdev(samples)
        self.points.append((self._value, mean, sd))
        self.out.write(
            f"  point {len(self.points)}: {mean:.5f} V (sd {sd:.5f} V over {len(samples)} readings) = "
            f"{self._value:g} {self.unit}\n"
        )
        if len(self.points) == 2:
            return False
        self.prompt()
        return True

    def result(self) -> tuple[float, float]:
        c = self.stats.channel
        check_points(c.name, self.unit, self.points)
        (v1, m1, _), (v2, m2, _) = self.points
        return two_point(v1, m1, v2, m2)


def calibrate(
    probe: Probe, name: str, average_s: float, stdin_fd: int, out: TextIO, live: bool, stop: Callable[[], bool]
) -> tuple[float, float] | None:
    """Run the dialogue; ``(scale, zero)``, or None when stopped before both points."""
    dialogue = Calibration(probe, name, average_s, stdin_fd, out, live)
    c = dialogue.stats.channel
    out.write(
        f"two-point calibration of {c.name} ({c.device} input {c.input}; now scale = {c.scale:g}, zero = {c.zero:g}); "
        "the valve is disabled, move the sensor by hand or with a reference; Ctrl-C stops\n"
    )
    dialogue.prompt()
    probe.run(None, dialogue.refresh, refresh_s=0.05, stop=stop)
    if len(dialogue.points) < 2:
        return None
    scale, zero = dialogue.result()
    out.write(
        f"# in [channels.{c.name}] of {probe.config.source}, replace scale and zero with "
        f"(two-point calibration, {time.strftime('%Y-%m-%d')}):\nscale = {scale:.6g}\nzero = {zero:.6g}\n"
    )
    out.flush()
    return scale, zero
