"""The edge runtime: config + bundle + rig -> the fixed-rate loop, until the duration, a fault
or a stop request.

Per tick, on one preallocated frame (:mod:`edge.runtime.frame`): wait for the deadline ->
``rig.read(frame)`` (every device; failures as errno fields) -> ``supervisor.step(frame)``
(one rule over every device status, the channel checks, then the pure control law fills the
command) -> ``rig.write(frame)`` -> ``rig.prepare(frame)`` (start the next conversions) ->
telemetry copies the frame. No per-tick objects; ``gc.freeze()`` after warm-up. A fault vents
in the same tick and ends the run; every exit path vents the valve, closes the rig, logs an
``end`` event with the summary, drains telemetry and gives the scheduling policy back.
"""

from __future__ import annotations

import dataclasses
import gc
import math
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from edge.control.adapt import OutputMapEstimator
from edge.control.joint import JointController
from edge.control.pid import PIDGains
from edge.control.reference import Reference, beyond_reach
from edge.control.tick import Controller, Limits, Readings
from edge.control.twin import ForwardModel
from edge.errors import BusError, DataError
from edge.runtime.bundle import Bundle
from edge.runtime.config import RigConfig
from edge.runtime.coverage import outside_coverage, read_coverage
from edge.runtime.frame import frame_layout
from edge.runtime.live import LiveView
from edge.runtime.recorder import CsvRecorder
from edge.runtime.rig import Rig, open_rig
from edge.runtime.rigspec import ANALOG_IN
from edge.runtime.safety import SAFE_CODE, STATE_CODES, Fault, State, Supervisor
from edge.runtime.scheduler import RealtimeSettings, TickScheduler, apply_realtime
from edge.runtime.summary import ErrorStats, RunSummary
from edge.runtime.telemetry import TelemetryWriter
from edge.runtime.watchdog import Watchdog

if TYPE_CHECKING:
    from edge.control.net_narmax import NetInverse
    from edge.hysteresis.lut import CompiledModel

SPIN_S = 300e-6  # poll the clock for the last 300 us before a deadline (wall clock only)
PHASES = ("read", "control", "write", "log", "cpu")  # wall ns per phase; "cpu": thread CPU ns of control + log
RUNNING_CODE = STATE_CODES[State.RUNNING]
REACH_CHECK_S = 60.0  # an endless reference is checked over its first minute
PUBLISH_S = 0.2  # how often the loop copies its running error sums to ``EdgeRuntime.errors``


def bundle_record(bundle: Bundle | None) -> dict[str, object] | None:
    """Which model ran: the bundle's identity (sha256 of the manifest as ``id``, kind, units,
    creation time, signer), its release path and whether it carries a correction."""
    if bundle is None:
        return None
    identity = bundle.identity
    return {
        "path": str(bundle.path),
        "id": identity["bundle_id"],
        **identity,
        "correction": bundle.correction_path is not None,
    }


def output_span(bundle: Bundle) -> float:
    """The bundle's output span (the inverse takes the forward table's reachable output range)."""
    lo, hi = bundle.inverse.input_range
    if math.isfinite(lo) and math.isfinite(hi) and hi > lo:
        return float(hi - lo)
    from edge.runtime.bundle import reachable_output_range

    lo, hi = reachable_output_range(bundle.forward, bundle.inverse)
    return float(hi - lo)


def check_duration(duration_s: float | None, settle_s: float, reference: Reference) -> None:
    """Refuse a run that would measure nothing: a non-finite or non-positive duration, or a
    settle time that covers all of it."""
    if duration_s is not None and not (math.isfinite(duration_s) and duration_s > 0):
        raise DataError(f"--duration {duration_s:g} must be a finite number of seconds > 0")
    if not (math.isfinite(settle_s) and settle_s >= 0):
        raise DataError(f"--settle {settle_s:g} must be a finite number of seconds >= 0")
    length = duration_s if duration_s is not None else reference.duration_s
    if length is not None and settle_s >= length:
        raise DataError(
            f"--settle {settle_s:g} s is not shorter than the run ({length:g} s); nothing would be scored. "
            "Lower --settle or run longer"
        )


class EdgeRuntime:
    """One configured run.

    Args:
        config: the validated rig config.
        bundle: the model bundle (its inverse table is the feedforward).
        reference: desired contraction [mm] over time.
        feedforward: False runs PID alone (the comparison of Ai2019 Table 5).
        use_correction: False ignores the bundle's ONNX correction.
        twin: False runs without the forward twin (and so without ``[adapt]``): the table-only
            tick, for comparison.
        telemetry_path: where to write telemetry (None: none); ``{time}`` in it becomes the
            start time (UTC), so a service writes a new file per run.
        settle_s: ticks before this time [s] are not scored in the error summary.
        profile: record per-phase wall time of every tick (``phase_ns``); ``"cpu"`` also the
            thread CPU time of the compute phases (its clock calls inflate the wall phases).
        rig: an already opened rig (default: open the one the config names).
        controller: the control law (default: the bundle's feedforward + PID); ``pmactl edge
            record`` passes an open-loop one (:mod:`edge.control.openloop`).
        recorder: a further per-tick sink (the recording CSV, :mod:`edge.runtime.recorder`);
            like telemetry, a write failure is a fault.
        live: the live view (:mod:`edge.runtime.live`), fed ticks and events; never a fault.
    """

    def __init__(
        self,
        config: RigConfig,
        bundle: Bundle | None,
        reference: Reference,
        *,
        feedforward: bool = True,
        use_correction: bool = True,
        twin: bool = True,
        telemetry_path: str | Path | None = None,
        settle_s: float = 0.0,
        profile: bool | str = False,
        rig: Rig | None = None,
        controller: Controller | JointController | None = None,
        recorder: CsvRecorder | None = None,
        live: LiveView | None = None,
    ) -> None:
        self.config, self.bundle, self.reference = config, bundle, reference
        spec = config.rig
        self.unit = spec.output_unit
        if bundle is not None:  # a joint's model maps desired to commanded angle (edge.control.joint)
            bundle.require_units("deg" if spec.is_joint else "bar", self.unit)
        correction = None
        self.feedforward_role = ""
        self.twin_model = ""  # "net" or "table" when the forward twin runs
        if bundle is not None and not spec.is_joint:
            from edge.control.net_roles import choose_role

            self.feedforward_role = choose_role(bundle.feedforward_roles, config.feedforward.role, config.source)
        if use_correction and self.feedforward_role.endswith("+correction") and bundle is not None:
            from edge.control.neural import NeuralCorrection

            correction = NeuralCorrection(bundle.correction_path or "", bundle.correction_spec or {})
        c = config.control
        inverse: CompiledModel | NetInverse | None = bundle.inverse if feedforward and bundle is not None else None
        if feedforward and bundle is not None and self.feedforward_role.startswith("net"):
            inverse = bundle.feedforward(self.feedforward_role, config.period_s)
        limits = Limits(c.pressure_min_bar, c.pressure_max_bar, c.slew_bar_per_s)
        self.controller: Controller | JointController
        if controller is not None:
            self.controller = controller
        elif spec.is_joint:
            j = config.joint
            gains = PIDGains(j.kp, j.ki_per_s, j.kd_s, j.derivative_filter_s)
            table = bundle.inverse if feedforward and bundle is not None else None  # a joint runs the table
            self.controller = JointController(reference, gains, j, table, limits, j.feedback == "through_model")
        else:
            gains = PIDGains(c.kp_bar_per_mm, c.ki_bar_per_mm_s, c.kd_bar_s_per_mm, c.derivative_filter_s)
            forward = self._forward_twin(bundle) if twin and bundle is not None else None  # watches the muscle
            adapt = (
                OutputMapEstimator(config.adapt, config.period_s, output_span(bundle))
                if config.adapt.enabled and forward is not None and bundle is not None and inverse is not None
                else None
            )
            self.controller = Controller(reference, gains, inverse, limits, correction, forward, adapt)
        self.layout = frame_layout(config.rig)
        self.frame = self.layout.new()
        channel_limits = tuple(
            (ch.field, ch.minimum, ch.maximum)
            for ch in config.rig.channels
            if ch.kind == ANALOG_IN and (math.isfinite(ch.minimum) or math.isfinite(ch.maximum))
        )
        self.rig = rig or open_rig(config, self.layout)
        # the frame is the rig's ctypes row; the law (muscle or joint) fixes which fields it fills
        self.supervisor: Supervisor[Any] = Supervisor(
            self.controller, config.safety, self.layout.status_fields, channel_limits, config.period_s,
            device_errors=self.rig.errors, output_field=spec.output_field,
            vent_fields=tuple(ch.field for ch in spec.channels if ch.name == "valve_b"),
            pressure_fields=tuple(ch.field for ch in spec.channels if ch.name == "pressure_b"),
            twin_span_mm=output_span(bundle) if bundle is not None and not spec.is_joint else 0.0,
        )  # fmt: skip
        self.supervisor.bind(self.layout.status_view(self.frame))
        self.telemetry_path = (
            Path(str(telemetry_path).replace("{time}", time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())))
            if telemetry_path
            else None
        )
        self.settle_s = settle_s
        self.profile = profile
        self.phase_ns: np.ndarray | None = None
        self.stop_requested = threading.Event()
        self._device_error_ticks = 0  # ticks on which some device reported an error
        self.telemetry: TelemetryWriter | None = None  # the open writer while running
        self.recorder = recorder
        self.live = live
        self.on_tick: list[Callable[[float], None]] = []  # run before each tick's read (tests inject faults)
        self.errors = ErrorStats()  # the running tracking-error sums (a status line reads them)
        self.on_warning: list[Callable[[str], None]] = []  # each warning once, as it happens (the CLI prints)
        self.warnings: list[str] = []  # before arming: a reference beyond the bundle's reach or its correction's data
        inverse_model = self.controller.inverse
        if inverse_model is not None:
            length = reference.duration_s or REACH_CHECK_S
            reach = beyond_reach(reference, length, tuple(inverse_model.input_range), self.unit)  # type: ignore[arg-type]
            if reach:
                self.warnings.append(reach)
        coverage = read_coverage(bundle.correction_spec, str(bundle.path)) if bundle is not None else None
        if coverage is not None and self.controller.correction is not None:
            outside = outside_coverage(reference, reference.duration_s or REACH_CHECK_S, coverage, self.unit)
            if outside:
                self.warnings.append(outside)

    def _header(self) -> dict[str, object]:
        spec = self.config.rig
        return {
            "rate_hz": self.config.loop.rate_hz,
            "config": self.config.source,
            "bundle": bundle_record(self.bundle),
            "reference": self.reference.spec,
            "feedforward": self.controller.inverse is not None,
            "feedforward_role": self.feedforward_role if self.controller.inverse is not None else "",
            "correction": self.controller.correction is not None,
            "twin": self.controller.twin is not None,
            "adapt": dataclasses.asdict(self.config.adapt) if getattr(self.controller, "adapt", None) else None,
            "states": [s.value for s in State],
            "faults": {f.value: f.name.lower() for f in Fault},
            "channels": {
                c.field: {"device": c.device, "unit": c.unit, "scale": c.scale, "zero": c.zero} for c in spec.channels
            },
            "devices": {d.name: {"driver": d.driver, "bus": spec.bus(d.bus).url} for d in spec.devices},
            "started_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        }

    def run(self, duration_s: float | None = None) -> RunSummary:
        """Run until ``duration_s`` [s] (default: the reference's length, else until stopped)."""
        config, rig = self.config, self.rig
        try:
            check_duration(duration_s, self.settle_s, self.reference)
        except BaseException:
            rig.close()  # a refused run still leaves the rig vented and released
            raise
        duration = duration_s if duration_s is not None else self.reference.duration_s
        if duration is None and rig.lockstep:
            rig.close()
            raise DataError(f"{config.source}: an endless reference on a lockstep rig never stops; give --duration")
        period = config.period_s
        try:
            telemetry = (
                TelemetryWriter(
                    self.telemetry_path,
                    self._header(),
                    self.layout.dtype,
                    config.telemetry.ring_ticks,
                    config.telemetry.flush_interval_s,
                )
                if self.telemetry_path
                else None
            )
        except BaseException:
            rig.close()
            raise
        self.telemetry = telemetry
        if telemetry is not None:
            telemetry.bind(self.layout.bytes_view(self.frame))
        if self.recorder is not None:
            self.recorder.bind_frame(self.frame, config.period_s)
        if self.live is not None:
            self.live.bind_frame(self.frame, config.period_s)
        realtime = RealtimeSettings(notes=["lockstep (simulated clock)"] if rig.lockstep else ["real-time disabled"])
        watchdog = None
        faults: list[str] = []
        errors = self.errors = ErrorStats()  # published every PUBLISH_S while running (status line)
        scheduler = TickScheduler(rig.clock, period, spin_s=0.0 if rig.lockstep else SPIN_S)
        frozen = False
        try:
            if config.loop.realtime and not rig.lockstep:
                realtime = apply_realtime(config.loop.priority, config.loop.cpu)
            gc.collect()
            gc.freeze()  # everything allocated so far is permanent: the loop allocates ~nothing
            frozen = True
            frame = self.frame
            rig.read(frame)
            failed = [dev for dev, rd, _ in self.layout.status_fields if getattr(frame, rd)]
            if failed:
                detail = "; ".join(f"{d}: {rig.errors.get(d, '')}" for d in failed)
                raise BusError(5, f"cannot arm, the first read failed ({detail})")
            y0 = getattr(frame, config.rig.output_field)
            self.supervisor.arm(Readings(y0, frame.pressure_bar))
            self._event(0.0, "arm", f"armed at {y0:.2f} {self.unit}; {'; '.join(realtime.notes)}")
            for warning in self.warnings:
                self._event(0.0, "warning", warning)
            n_max = int(math.ceil(duration / period)) + 1 if duration is not None else 0
            if self.profile:
                self.phase_ns = np.zeros((max(n_max, 1), len(PHASES)), dtype=np.int64)
            if not rig.lockstep:
                watchdog = Watchdog(rig, config.loop.watchdog_s)
            rig.prepare(frame)
            scheduler.start()
            self._loop(scheduler, duration, telemetry, watchdog, errors, faults)
        finally:
            try:
                rig.close()  # vents first; never raises out of vent, but a driver's close might
            except Exception as exc:  # noqa: BLE001 - the run's own error and summary come first
                faults.append(f"rig close failed: {exc}")
            if frozen:
                gc.unfreeze()
            if watchdog:
                watchdog.stop()
            realtime.restore()
            extra = self._extra(telemetry)
            if self.live is not None:
                self.live.event(scheduler.index * period, "end", "end of run")
                self.live.close()
            if telemetry:
                if telemetry.failure is not None and telemetry.failure not in faults:
                    faults.append(telemetry.failure)
                summary = RunSummary(errors, scheduler.stats.summary(), faults, realtime.notes, extra, self.unit)
                telemetry.event(scheduler.index * period, "end", "end of run", summary=summary.as_dict())
                telemetry.close()
                if telemetry.failure is not None and telemetry.failure not in faults:
                    faults.append(telemetry.failure)  # the last drain failed
        extra = self._extra(telemetry)
        return RunSummary(errors, scheduler.stats.summary(), faults, realtime.notes, extra, self.unit)

    def _extra(self, telemetry: TelemetryWriter | None) -> dict[str, object]:
        return {
            "bus_errors": self._device_error_ticks,
            "feedforward": self.controller.inverse is not None,
            "feedforward_role": self.feedforward_role if self.controller.inverse is not None else "",
            "correction": self.controller.correction is not None,
            "reference": self.reference.spec,
            "rate_hz": self.config.loop.rate_hz,
            "telemetry": str(self.telemetry_path) if self.telemetry_path else None,
            "telemetry_dropped": telemetry.dropped if telemetry else 0,
            "bundle": bundle_record(self.bundle),
            "warnings": list(self.warnings),
            **self._twin_record(),
        }

    def _forward_twin(self, bundle: Bundle) -> ForwardModel:
        """The twin: the forward table, or with ``[feedforward] twin = "net"`` the bundle's forward net
        (it models the rate dependence the net inverse compensates; a net role is needed)."""
        wanted, source = self.config.feedforward.twin, self.config.source
        if wanted not in ("table", "net"):
            raise DataError(f'{source}: [feedforward] twin = "{wanted}" is unknown; use "table" or "net"')
        if wanted == "net":
            if not (self.feedforward_role.startswith("net") and "forward" in bundle.net_paths):
                raise DataError(
                    f'{source}: [feedforward] twin = "net" needs a net feedforward role and a bundle with a forward '
                    f'net (role here: {self.feedforward_role or "none"}); use twin = "table"'
                )
            self.twin_model = "net"
            return bundle.forward_net(self.config.period_s)
        self.twin_model = "table"
        return bundle.forward

    def _twin_record(self) -> dict[str, object]:
        """The twin's worst window RMS [mm] and the adaptation's final map, when they ran."""
        watch, adapt = self.supervisor.twin_watch, getattr(self.controller, "adapt", None)
        record: dict[str, object] = {}
        if watch is not None:
            record["twin_model"] = self.twin_model
            record["twin_rms_max_mm"] = watch.worst_rms_mm
            record["twin_warning_t"] = watch.warned_at_s
        if adapt is not None:
            record["adapt"] = {"offset_mm": adapt.offset_, "gain": adapt.gain_, "updates": adapt.updates_}
        return record

    def _event(self, t: float, kind: str, text: str, **extra: object) -> None:
        """An event to the telemetry log and the live view (whichever are open)."""
        if self.telemetry is not None:
            self.telemetry.event(t, kind, text, **extra)
        if self.live is not None:
            self.live.event(t, kind, text)

    def _report(self, warnings: list[str], t: float, telemetry: TelemetryWriter | None) -> None:
        for warning in warnings:
            self.warnings.append(warning)
            self._event(t, "warning", warning)
            for callback in self.on_warning:
                callback(warning)

    def _loop(
        self,
        scheduler: TickScheduler,
        duration: float | None,
        telemetry: TelemetryWriter | None,
        watchdog: Watchdog | None,
        errors: ErrorStats,
        faults: list[str],
    ) -> None:
        rig, supervisor, period, frame = self.rig, self.supervisor, self.config.period_s, self.frame
        read, step, write, prepare = rig.read, supervisor.step, rig.write, rig.prepare
        record = telemetry.record_bound if telemetry is not None else None
        record_live = self.live.record_bound if self.live is not None else None
        recorder = self.recorder
        record_csv = recorder.record_bound if recorder is not None else None
        phase, profile, settle = self.phase_ns, self.profile, self.settle_s
        clock_ns, cpu_ns = time.perf_counter_ns, time.thread_time_ns
        timed_cpu = profile == "cpu"  # the CPU clock calls inflate the wall phases: a separate run
        hooks = self.on_tick
        reference_field, output_field = f"reference_{self.unit}", self.config.rig.output_field
        tick = 0
        streak = 0
        reported = 0
        publish_every = max(1, int(round(PUBLISH_S / period)))
        next_publish = publish_every
        count, sum_sq, sum_abs, max_abs = errors.count, errors.sum_sq, errors.sum_abs, errors.max_abs
        stop = self.stop_requested
        try:
            while not stop.is_set():
                if duration is not None and scheduler.index * period >= duration - 1e-9:
                    break
                t, lateness = scheduler.wait()
                for hook in hooks:
                    hook(t)
                t0 = clock_ns()
                frame.t, frame.lateness_us = t, lateness * 1e6
                read(frame)
                t1 = clock_ns()
                c1 = cpu_ns() if timed_cpu else 0
                if watchdog is not None and watchdog.fired_after_s is not None:
                    supervisor.trip(frame, Fault.WATCHDOG, f"loop stalled for {watchdog.fired_after_s * 1e3:.0f} ms")
                elif telemetry is not None and telemetry.failure is not None:
                    supervisor.trip(frame, Fault.TELEMETRY, telemetry.failure)
                elif recorder is not None and recorder.failure is not None:
                    supervisor.trip(frame, Fault.TELEMETRY, recorder.failure)
                else:
                    step(frame, period)
                t2 = clock_ns()
                c2 = cpu_ns() if timed_cpu else 0
                write(frame)
                if frame.state != SAFE_CODE:
                    prepare(frame)
                t3 = clock_ns()
                c3 = cpu_ns() if timed_cpu else 0
                if frame.state == RUNNING_CODE and t >= settle:
                    error = getattr(frame, reference_field) - getattr(frame, output_field)
                    if error == error:  # a held tick has no reading
                        count += 1
                        sum_sq += error * error
                        error = error if error >= 0.0 else -error
                        sum_abs += error
                        if error > max_abs:
                            max_abs = error
                if record is not None:
                    record()
                if record_csv is not None:
                    record_csv()
                if record_live is not None:
                    record_live()
                if supervisor.bus_error_streak != streak:
                    streak = supervisor.bus_error_streak
                    if streak:
                        self._device_error_ticks += 1
                        self._event(t, "device_error", supervisor.device_fault(frame) or "device error")
                if profile and phase is not None and tick < len(phase):
                    t4 = clock_ns()
                    phase[tick] = (t1 - t0, t2 - t1, t3 - t2, t4 - t3, (c2 - c1) + (cpu_ns() - c3) if timed_cpu else 0)
                tick += 1
                if tick >= next_publish:  # for a status line in another thread, and new warnings
                    errors.count, errors.sum_sq, errors.sum_abs, errors.max_abs = count, sum_sq, sum_abs, max_abs
                    next_publish = tick + publish_every
                    if len(supervisor.warnings) > reported:
                        self._report(supervisor.warnings[reported:], t, telemetry)
                        reported = len(supervisor.warnings)
                if watchdog is not None:
                    watchdog.heartbeat = time.monotonic()
                if frame.state == SAFE_CODE:
                    reason = supervisor.fault or "safe state"
                    faults.append(reason)
                    self._event(t, "fault", reason, code=supervisor.fault_kind.value if supervisor.fault_kind else 0)
                    break
        finally:
            errors.count, errors.sum_sq, errors.sum_abs, errors.max_abs = count, sum_sq, sum_abs, max_abs
        if len(supervisor.warnings) > reported:
            self._report(supervisor.warnings[reported:], scheduler.index * period, telemetry)
        if self.stop_requested.is_set():
            self._event(scheduler.index * period, "stop", "stop requested (signal); valve vented")
