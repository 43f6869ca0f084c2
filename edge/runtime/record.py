"""``pmactl edge record``: open-loop excitation on the rig a config names, recorded as the CSV
the host tools read (:mod:`edge.runtime.recorder`).

The valve follows a protocol (:mod:`edge.control.protocols`) through an open-loop controller
(:mod:`edge.control.openloop`) inside the ordinary runtime, so the supervisor is fully active:
pressure and contraction (angle) limits, the e-stop, bus errors, stuck sensors and, in real
time, the watchdog. Any fault vents the valve in that tick and ends the recording; every row
before it is already in the CSV (flushed every ``[telemetry] flush_interval_s``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from edge.control.openloop import OpenLoop, OpenLoopJoint
from edge.control.protocols import build_protocol
from edge.control.reference import Reference
from edge.control.tick import Limits
from edge.errors import DataError
from edge.runtime.config import RigConfig
from edge.runtime.frame import frame_layout
from edge.runtime.recorder import CsvRecorder, meta_path
from edge.runtime.run import EdgeRuntime
from edge.runtime.summary import RunSummary

DEFAULT_RANGE_BAR = (0.0, 4.0)  # Ai2019's triangles reach 1, 2, 3, 4 bar
DEFAULT_RANGE_DEG = (-30.0, 30.0)  # a joint's commanded angle (hil joint_record: +-30 deg)
DEFAULT_SAMPLE_HZ = 100.0  # the rate of the recordings the host tools were developed on
MIN_ROWS = 10  # host.data.load_measurement's min_samples: a shorter recording is refused by every host tool


@dataclass
class RecordResult:
    """How a recording went: the runtime's summary and what the CSV holds."""

    summary: RunSummary
    csv: Path
    rows: int
    last_t: float
    command_range: tuple[float, float]
    unit: str
    sample_hz: float
    extra: dict[str, object] = field(default_factory=dict)

    def as_dict(self) -> dict[str, object]:
        s = self.summary.as_dict()
        return {
            "csv": str(self.csv),
            "meta": str(meta_path(self.csv)),
            "rows": self.rows,
            "last_t": None if math.isnan(self.last_t) else self.last_t,
            "sample_hz": self.sample_hz,
            "range": list(self.command_range),
            "unit": self.unit,
            "faults": s["faults"],
            "ticks": s["ticks"],
            "overruns": s["overruns"],
            "lateness": s["lateness"],
            "bus_errors": s["bus_errors"],
            "protocol": s["reference"],
            "telemetry": s["telemetry"],
            "realtime": s["realtime"],
        }


def parse_range(text: str | None, config: RigConfig) -> tuple[float, float]:
    """``LOW:HIGH`` (bar; commanded deg on a joint), or the default, checked against the config."""
    joint = config.rig.is_joint
    unit = "deg" if joint else "bar"
    if joint:
        allowed = (config.safety.angle_min_deg, config.safety.angle_max_deg)
        where = "[safety] angle_min_deg..angle_max_deg"
        default = DEFAULT_RANGE_DEG
    else:
        allowed = (config.control.pressure_min_bar, config.control.pressure_max_bar)
        where = "[control] pressure_min_bar..pressure_max_bar"
        default = DEFAULT_RANGE_BAR
    if text is None:
        return max(default[0], allowed[0]), min(default[1], allowed[1])
    low_text, sep, high_text = text.partition(":")
    try:
        low, high = float(low_text), float(high_text)
    except ValueError:
        sep = ""
    if not sep or not (math.isfinite(low) and math.isfinite(high)) or low >= high:
        raise DataError(f"--range {text!r}: write LOW:HIGH in {unit} with LOW < HIGH, e.g. --range 0:4")
    if low < allowed[0] or high > allowed[1]:
        raise DataError(
            f"--range {text}: leaves the config's {allowed[0]:g}..{allowed[1]:g} {unit} ({config.source} {where}); "
            "narrow --range or change the config"
        )
    return low, high


def sample_every(config: RigConfig, sample_hz: float | None) -> tuple[int, float]:
    """(ticks per CSV row, the CSV's rate [Hz]); the rate must divide the loop rate."""
    rate = config.loop.rate_hz
    if sample_hz is None:
        sample_hz = DEFAULT_SAMPLE_HZ if DEFAULT_SAMPLE_HZ <= rate and (rate / DEFAULT_SAMPLE_HZ).is_integer() else rate
    if not (math.isfinite(sample_hz) and 0 < sample_hz <= rate):
        raise DataError(f"--sample-hz {sample_hz:g} must be > 0 and at most the loop's {rate:g} Hz")
    every = rate / sample_hz
    if abs(every - round(every)) > 1e-9:
        raise DataError(f"--sample-hz {sample_hz:g} must divide the loop rate {rate:g} Hz (e.g. {rate / 10:g})")
    return int(round(every)), sample_hz


def record(
    config: RigConfig,
    protocol_spec: str,
    out: str | Path,
    *,
    range_text: str | None = None,
    duration_s: float | None = None,
    sample_hz: float | None = None,
    telemetry_path: str | Path | None = None,
) -> tuple[EdgeRuntime, CsvRecorder]:
    """Prepare a recording (everything checked, the rig opened); :func:`finish` runs it.

    Split in two so the caller can install signal handlers and hooks on the runtime first."""
    if duration_s is not None and not (math.isfinite(duration_s) and duration_s > 0):
        raise DataError(f"--duration {duration_s:g} must be a finite number of seconds > 0")
    low, high = parse_range(range_text, config)
    every, rate = sample_every(config, sample_hz)
    if duration_s is not None and duration_s * rate < MIN_ROWS:
        raise DataError(
            f"--duration {duration_s:g} s gives fewer than {MIN_ROWS} rows at {rate:g} Hz, fewer than the host tools "
            f"read; record at least {MIN_ROWS / rate:g} s"
        )
    spec = config.rig
    unit = "deg" if spec.is_joint else "bar"
    protocol = build_protocol(protocol_spec, low, high, config.period_s, duration_s, unit, nyquist_hz=rate / 2)
    c = config.control
    limits = Limits(c.pressure_min_bar, c.pressure_max_bar, c.slew_bar_per_s)
    controller = OpenLoopJoint(protocol, config.joint, limits) if spec.is_joint else OpenLoop(protocol, limits)
    meta: dict[str, object] = {
        "protocol": protocol_spec,
        "range": [low, high],
        "range_unit": unit,
        "config": config.source,
        "loop_rate_hz": config.loop.rate_hz,
        "sample_hz": rate,
        "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "fit_units": f"{unit},{spec.output_unit}",
    }
    recorder = CsvRecorder(
        out, spec, _layout_dtype(config), every, meta, config.telemetry.ring_ticks, config.telemetry.flush_interval_s
    )
    try:
        reference = Reference(f"protocol {protocol_spec} on {low:g}..{high:g} {unit}", protocol, protocol.duration_s)
        runtime = EdgeRuntime(
            config, None, reference, telemetry_path=telemetry_path, controller=controller, recorder=recorder
        )
    except BaseException:
        _abandon(recorder)
        raise
    return runtime, recorder


def _layout_dtype(config: RigConfig) -> np.dtype:
    return frame_layout(config.rig).dtype


def _abandon(recorder: CsvRecorder) -> None:
    """Close a recording that never started; an empty file this run created is removed."""
    recorder.close()
    if recorder.rows == 0:
        for path in (recorder.path, meta_path(recorder.path)):
            path.unlink(missing_ok=True)


def abandon(runtime: EdgeRuntime, recorder: CsvRecorder) -> None:
    """Give up a prepared recording before it ran: the rig released, the empty CSV removed."""
    runtime.rig.close()
    _abandon(recorder)


def finish(runtime: EdgeRuntime, recorder: CsvRecorder) -> RecordResult:
    """Run the prepared recording to its end (or a fault or a stop) and close the CSV."""
    try:
        summary = runtime.run(runtime.reference.duration_s)
    except BaseException as exc:
        if recorder.rows == 0:
            _abandon(recorder)
        else:
            recorder.finish({"faults": [str(exc)], "stopped": "error"})
        raise
    faults = list(summary.faults)
    recorder.finish(
        {"faults": faults, "stopped": "fault" if faults else "stop" if runtime.stop_requested.is_set() else "end"}
    )
    if recorder.failure is not None and recorder.failure not in faults:
        summary.faults.append(recorder.failure)
    low_high = recorder.meta["range"]
    assert isinstance(low_high, list)
    return RecordResult(
        summary,
        recorder.path,
        recorder.rows,
        recorder.last_t,
        (float(low_high[0]), float(low_high[1])),
        str(recorder.meta["range_unit"]),
        float(recorder.meta["sample_hz"]),  # type: ignore[arg-type]
    )
