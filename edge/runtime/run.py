"""The edge runtime: config + bundle + rig -> the fixed-rate loop, until the duration, a fault
or a stop request.

Per tick: wait for the deadline -> read the sensors -> supervisor (safety checks, then the pure
control tick) -> write the valve -> one telemetry row. I/O and time live here only. A fault
vents in the same tick and ends the run; every exit path vents the valve, closes the rig,
drains telemetry and gives the scheduling policy back. A runtime runs once.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from edge.control.pid import PIDGains
from edge.control.reference import Reference
from edge.control.tick import Controller, Limits, Readings
from edge.errors import BusError, ConfigError
from edge.runtime.backends import OpenedRig, open_rig
from edge.runtime.bundle import Bundle
from edge.runtime.config import RigConfig
from edge.runtime.safety import Fault, Health, State, Supervisor
from edge.runtime.scheduler import RealtimeSettings, TickScheduler, apply_realtime
from edge.runtime.telemetry import TelemetryWriter

SPIN_S = 300e-6  # poll the clock for the last 300 us before a deadline (wall clock only)
PHASES = ("read", "control", "write", "log")
STATE_CODES = {state: i for i, state in enumerate(State)}


@dataclass
class ErrorStats:
    """Running tracking-error sums [mm] over the scored ticks."""

    count: int = 0
    sum_sq: float = 0.0
    sum_abs: float = 0.0
    max_abs: float = 0.0

    def add(self, error: float) -> None:
        self.count += 1
        self.sum_sq += error * error
        self.sum_abs += abs(error)
        self.max_abs = max(self.max_abs, abs(error))

    def summary(self) -> dict[str, float | None]:
        if not self.count:
            return {"rms_error": None, "mean_abs_error": None, "max_error": None}
        return {
            "rms_error": math.sqrt(self.sum_sq / self.count),
            "mean_abs_error": self.sum_abs / self.count,
            "max_error": self.max_abs,
        }


@dataclass
class RunSummary:
    """What ``pmactl edge run --json`` prints (errors in mm)."""

    errors: ErrorStats
    lateness: dict[str, float]
    faults: list[str]
    notes: list[str] = field(default_factory=list)
    extra: dict[str, object] = field(default_factory=dict)

    def as_dict(self) -> dict[str, object]:
        return {
            **self.errors.summary(),
            "ticks": self.lateness["ticks"],
            "overruns": self.lateness["overruns"],
            "lateness_p99_us": self.lateness["lateness_p99_us"],
            "faults": self.faults,
            "unit": "mm",
            "scored_ticks": self.errors.count,
            "lateness": self.lateness,
            "realtime": self.notes,
            **self.extra,
        }


class Watchdog:
    """Vents the valve from its own thread if the loop stops ticking for ``timeout_s``.

    The loop may be stalled inside a bus transfer; ``vent`` drops the GPIO enable line first,
    which does not share that bus.
    """

    def __init__(self, rig: OpenedRig, timeout_s: float) -> None:
        self._rig, self.timeout_s = rig, timeout_s
        self.heartbeat = time.monotonic()
        self.fired_after_s: float | None = None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="pmactl-watchdog", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.timeout_s / 4):
            stalled = time.monotonic() - self.heartbeat
            if stalled > self.timeout_s and self.fired_after_s is None:
                self.fired_after_s = stalled
                self._rig.io.vent()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join()


class EdgeRuntime:
    """One configured run.

    Args:
        config: the validated rig config.
        bundle: the model bundle (its inverse table is the feedforward).
        reference: desired contraction [mm] over time.
        feedforward: False runs PID alone (the comparison of seed 000 Table 5).
        use_correction: False ignores the bundle's ONNX correction.
        telemetry_path: where to write telemetry (None: none).
        settle_s: ticks before this time [s] are not scored in the error summary.
        profile: record per-phase compute time of every tick (``phase_ns``).
        rig: an already opened rig (default: open the one the config names).
    """

    def __init__(
        self,
        config: RigConfig,
        bundle: Bundle | None,
        reference: Reference,
        *,
        feedforward: bool = True,
        use_correction: bool = True,
        telemetry_path: str | Path | None = None,
        settle_s: float = 0.0,
        profile: bool = False,
        rig: OpenedRig | None = None,
    ) -> None:
        self.config, self.bundle, self.reference = config, bundle, reference
        if bundle is not None:
            bundle.require_units("bar", "mm")
        correction = None
        if use_correction and bundle is not None and bundle.correction_path is not None:
            from edge.control.neural import NeuralCorrection

            correction = NeuralCorrection(bundle.correction_path, bundle.correction_spec or {})
        c = config.control
        inverse = bundle.inverse if feedforward and bundle is not None else None
        self.controller = Controller(
            reference,
            PIDGains(c.kp_bar_per_mm, c.ki_bar_per_mm_s, c.kd_bar_s_per_mm, c.derivative_filter_s),
            inverse,
            Limits(c.pressure_min_bar, c.pressure_max_bar, c.slew_bar_per_s),
            correction,
        )
        self.supervisor = Supervisor(self.controller, config.safety)
        self.rig = rig or open_rig(config)
        self.telemetry_path = telemetry_path
        self.settle_s = settle_s
        self.profile = profile
        self.phase_ns: np.ndarray | None = None
        self.stop_requested = threading.Event()
        self.on_tick: list[Callable[[float], None]] = []  # run before each tick's read (tests inject faults)

    def _header(self) -> dict[str, object]:
        return {
            "rate_hz": self.config.loop.rate_hz,
            "config": self.config.source,
            "bundle": str(self.bundle.path) if self.bundle else None,
            "reference": self.reference.spec,
            "feedforward": self.controller.inverse is not None,
            "correction": self.controller.correction is not None,
            "states": [s.value for s in State],
            "faults": {f.value: f.name.lower() for f in Fault},
            "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        }

    def run(self, duration_s: float | None = None) -> RunSummary:
        """Run until ``duration_s`` [s] (default: the reference's length, else until stopped)."""
        duration = duration_s if duration_s is not None else self.reference.duration_s
        config, rig = self.config, self.rig
        if duration is None and rig.lockstep:
            raise ConfigError(f"{config.source}: an endless reference on a lockstep rig never stops; give --duration")
        period = config.period_s
        telemetry = (
            TelemetryWriter(
                self.telemetry_path, self._header(), config.telemetry.ring_ticks, config.telemetry.flush_interval_s
            )
            if self.telemetry_path
            else None
        )
        realtime = RealtimeSettings(notes=["lockstep (simulated clock)"] if rig.lockstep else ["real-time disabled"])
        watchdog = None
        faults: list[str] = []
        errors = ErrorStats()
        scheduler = TickScheduler(rig.clock, period, spin_s=0.0 if rig.lockstep else SPIN_S)
        bus_errors = 0
        try:
            if config.loop.realtime and not rig.lockstep:
                realtime = apply_realtime(config.loop.priority, config.loop.cpu)
            try:
                first = rig.io.read()
            except BusError as exc:
                raise BusError(exc.errno, f"cannot arm, the first sensor read failed: {exc}") from exc
            self.supervisor.arm(Readings(first.contraction_mm, first.pressure_bar))
            if telemetry:
                telemetry.event(0.0, "arm", f"armed at {first.contraction_mm:.2f} mm; {'; '.join(realtime.notes)}")
            if not rig.lockstep:
                watchdog = Watchdog(rig, config.loop.watchdog_s)
            n_max = int(math.ceil(duration / period)) + 1 if duration is not None else 0
            if self.profile:
                self.phase_ns = np.zeros((max(n_max, 1), len(PHASES)), dtype=np.int64)
            scheduler.start()
            bus_errors = self._loop(scheduler, duration, telemetry, watchdog, errors, faults)
        finally:
            rig.io.close()  # vents first
            if watchdog:
                watchdog.stop()
            if telemetry:
                telemetry.close()
            realtime.restore()
        extra = {
            "bus_errors": bus_errors,
            "feedforward": self.controller.inverse is not None,
            "correction": self.controller.correction is not None,
            "reference": self.reference.spec,
            "rate_hz": config.loop.rate_hz,
            "telemetry": str(self.telemetry_path) if self.telemetry_path else None,
            "telemetry_dropped": telemetry.dropped if telemetry else 0,
        }
        return RunSummary(errors, scheduler.stats.summary(), faults, realtime.notes, extra)

    def _loop(
        self,
        scheduler: TickScheduler,
        duration: float | None,
        telemetry: TelemetryWriter | None,
        watchdog: Watchdog | None,
        errors: ErrorStats,
        faults: list[str],
    ) -> int:
        io, supervisor, period = self.rig.io, self.supervisor, self.config.period_s
        phase, profile = self.phase_ns, self.profile
        clock_ns = time.perf_counter_ns
        bus_errors = 0
        tick = 0
        while not self.stop_requested.is_set():
            if duration is not None and scheduler.index * period >= duration - 1e-9:
                break
            t, lateness = scheduler.wait()
            for hook in self.on_tick:
                hook(t)
            t0 = clock_ns()
            bus_error = False
            try:
                reading = io.read()
                readings = Readings(reading.contraction_mm, reading.pressure_bar)
                estop = reading.estop
            except BusError as exc:
                bus_error, readings, estop = True, None, False
                bus_errors += 1
                if telemetry:
                    telemetry.event(t, "bus_error", str(exc))
            t1 = clock_ns()
            if watchdog is not None and watchdog.fired_after_s is not None:
                outcome = supervisor.trip(Fault.WATCHDOG, f"loop stalled for {watchdog.fired_after_s * 1e3:.0f} ms")
            else:
                outcome = supervisor.tick(t, period, readings, Health(bus_error, lateness > period, estop))
            t2 = clock_ns()
            try:
                io.write(outcome.pressure_bar, outcome.valve_enabled)
            except BusError as exc:
                bus_errors += 1
                if telemetry:
                    telemetry.event(t, "bus_error", str(exc))
            t3 = clock_ns()
            command = outcome.command
            if command is not None and readings is not None and t >= self.settle_s:
                errors.add(command.reference_mm - readings.contraction_mm)
            if telemetry:
                y = readings.contraction_mm if readings else math.nan
                p = readings.pressure_bar if readings else math.nan
                if command is not None:
                    ref, ff, nn, fb = (
                        command.reference_mm,
                        command.feedforward_bar,
                        command.correction_bar,
                        command.feedback_bar,
                    )
                else:
                    ref = ff = nn = fb = math.nan
                telemetry.record(
                    (
                        t,
                        ref,
                        y,
                        p,
                        ff,
                        nn,
                        fb,
                        outcome.pressure_bar if outcome.valve_enabled else 0.0,
                        STATE_CODES[outcome.state],
                        outcome.fault_kind.value if outcome.fault_kind else 0,
                        lateness * 1e6,
                    )
                )
            if profile and phase is not None and tick < len(phase):
                phase[tick] = (t1 - t0, t2 - t1, t3 - t2, clock_ns() - t3)
            tick += 1
            if watchdog is not None:
                watchdog.heartbeat = time.monotonic()
            if outcome.state is State.SAFE:
                faults.append(outcome.fault or "safe state")
                if telemetry:
                    telemetry.event(t, "fault", outcome.fault or "safe state")
                break
        if self.stop_requested.is_set() and telemetry:
            telemetry.event(scheduler.index * period, "stop", "stop requested (signal); valve vented")
        return bus_errors
