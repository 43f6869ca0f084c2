"""A terminal that talks: how to stop, then one status line a second while a run or a
recording goes on (``pmactl edge run`` / ``record`` when stderr is a terminal and ``--json`` is
not given).

The line is drawn by its own thread from what the loop already publishes (the frame, the
running error sums), so the tick never formats or writes text. On a terminal the line is
redrawn in place; :meth:`StatusLine.stop` ends it with a newline so the summary starts clean.
"""

from __future__ import annotations

import math
import sys
import threading
from collections.abc import Callable
from typing import TextIO

from edge.runtime.safety import STATE_CODES, Fault, State

STOP_HINT = "Ctrl-C stops and vents"
STATE_NAMES = {code: state.value for state, code in STATE_CODES.items()}
FAULT_NAMES = {f.value: f.name.lower() for f in Fault}


class StatusLine:
    """Calls ``describe()`` every ``interval_s`` [s] of wall time and shows the text on
    ``stream`` (see the module docstring)."""

    def __init__(self, describe: Callable[[], str], stream: TextIO | None = None, interval_s: float = 1.0) -> None:
        self._describe, self._stream, self._interval = describe, stream or sys.stderr, interval_s
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="pmactl-status", daemon=True)
        self._drawn = False

    def start(self, what: str) -> None:
        print(f"{what}; {STOP_HINT}", file=self._stream, flush=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self._interval):
            self._draw()

    def _draw(self) -> None:
        try:
            text = self._describe()
        except Exception as exc:  # noqa: BLE001 - a status line must never take the run down
            text = f"(status unavailable: {exc})"
        self._stream.write(f"\r\x1b[K{text}")
        self._stream.flush()
        self._drawn = True

    def stop(self) -> None:
        """Draw the last line, end it, and stop the thread."""
        if not self._thread.is_alive():
            return
        self._stop.set()
        self._thread.join()
        self._draw()
        self._stream.write("\n")
        self._stream.flush()


def wants_status(json_output: bool, stream: TextIO | None = None) -> bool:
    """A status line only for a person: stderr is a terminal and no ``--json``."""
    stream = stream or sys.stderr
    return not json_output and stream.isatty()


def describe_frame(frame: object, output_field: str, unit: str, errors: object | None) -> str:
    """``running  t 12.0 s  RMS 2.41 mm  max 7.70 mm  y 41.3 mm  p 2.31 bar  twin +0.4 mm  faults none``."""
    state = STATE_NAMES.get(int(getattr(frame, "state", 0)), "?")
    parts = [f"{state:<7}", f"t {getattr(frame, 't', math.nan):7.1f} s"]
    count = getattr(errors, "count", 0) if errors is not None else 0
    if count:
        rms = math.sqrt(errors.sum_sq / count)  # type: ignore[union-attr]
        parts.append(f"RMS {rms:.2f} {unit}  max {errors.max_abs:.2f} {unit}")  # type: ignore[union-attr]
    parts.append(f"y {getattr(frame, output_field, math.nan):.1f} {unit}")
    parts.append(f"u {getattr(frame, 'u_bar', math.nan):.2f} bar")
    pressure = getattr(frame, "pressure_bar", math.nan)
    if pressure == pressure:
        parts.append(f"p {pressure:.2f} bar")
    residual = getattr(frame, "twin_residual_mm", math.nan)  # measured - the forward twin's prediction
    if residual == residual:
        parts.append(f"twin {residual:+.1f} {unit}")
    fault = int(getattr(frame, "fault", 0))
    parts.append(f"faults {FAULT_NAMES.get(fault, fault) if fault else 'none'}")
    if state == State.SAFE.value:
        parts.append("(valve vented)")
    return "  ".join(parts)
