"""``pmactl edge run``, ``record`` and ``telemetry``: the runtime from the command line.

Nothing here imports ``host``, ``hil``, scipy, matplotlib or torch (``--plot`` imports
matplotlib when asked), so the SBC runs the loop with only ``pmactl[edge]``: as
``pmactl edge ...`` or ``python -m edge ...``. SIGTERM and SIGINT end the loop cleanly: the
valve is vented, telemetry drained, the summary printed. Errors are one line, exit status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, TypeVar

from edge.errors import DataError, PmactlError

if TYPE_CHECKING:
    from edge.runtime.run import EdgeRuntime

T = TypeVar("T")
DEFAULT_REFERENCE = "sine:amplitude=30,frequency=0.2,offset=40"


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``edge run`` and ``edge telemetry`` to the ``pmactl`` command line."""
    edge = sub.add_parser("edge", help="the control loop that runs on the rig's computer")
    edge_sub = edge.add_subparsers(dest="edge_command", required=True, metavar="EDGE_COMMAND")
    erun = edge_sub.add_parser("run", help="run the fixed-rate control loop on the rig a config names")
    erun.add_argument("--config", required=True, metavar="RIG.toml", help="rig config (docs/examples/*.toml)")
    erun.add_argument("--bundle", required=True, metavar="DIR", help="model bundle written by pmactl fit --save")
    erun.add_argument("--duration", type=float, metavar="S", help="seconds to run (default: the reference's length)")
    erun.add_argument(
        "--reference",
        default=DEFAULT_REFERENCE,
        metavar="SPEC",
        help="desired contraction: sine:amplitude=,frequency=,offset= | ramp-sine:peak=,frequency=,offset=,rise=,hold= "
        "| const:value= | a CSV with t,y_ref (default: Ai2019's 30 sin(2 pi 0.2 t) + 40 mm)",
    )
    erun.add_argument("--no-feedforward", action="store_true", help="PID alone (no inverse-hysteresis feedforward)")
    erun.add_argument("--no-correction", action="store_true", help="ignore the bundle's ONNX correction")
    erun.add_argument("--settle", type=float, default=0.0, metavar="S", help="leave the first S seconds unscored")
    erun.add_argument(
        "--telemetry",
        metavar="FILE",
        help="write per-tick telemetry to this new file (+ FILE.events.jsonl); an existing file is refused, "
        "{time} in the name becomes the start time",
    )
    erun.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    erun.add_argument(
        "--live",
        metavar="[HOST:]PORT",
        help="serve the run live to Foxglove (WebSocket; same topics as the MCAP export); HOST defaults to 127.0.0.1",
    )
    erun.set_defaults(run=run)
    erec = edge_sub.add_parser(
        "record",
        help="open-loop excitation on the rig, recorded as the CSV pmactl fit / train / diagnose / identify read",
    )
    erec.add_argument("--config", required=True, metavar="RIG.toml", help="rig config (docs/examples/*.toml)")
    erec.add_argument(
        "--protocol",
        required=True,
        metavar="NAME",
        help="triangles (Ai2019) | forc (Schreiber, for a Preisach fit) | sines | steps | multisine | chirp, "
        "optionally NAME:key=value,... (lists with /), or FILE.csv with columns t,<command>",
    )
    erec.add_argument("--out", required=True, metavar="RUN.csv", help="the recording to create (+ RUN.meta.json)")
    erec.add_argument(
        "--range",
        metavar="LOW:HIGH",
        help="command range: bar (default 0:4, Ai2019), or commanded deg on a joint (default -30:30); "
        "within the config's limits",
    )
    erec.add_argument(
        "--duration", type=float, metavar="S", help="seconds to record, repeating the protocol (default: one pass)"
    )
    erec.add_argument(
        "--sample-hz", type=float, metavar="HZ", help="CSV rows per second; divides the loop rate (default 100)"
    )
    erec.add_argument("--telemetry", metavar="FILE", help="also write per-tick telemetry (as edge run --telemetry)")
    erec.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    erec.add_argument(
        "--live",
        metavar="[HOST:]PORT",
        help="serve the run live to Foxglove (WebSocket; same topics as the MCAP export); HOST defaults to 127.0.0.1",
    )
    erec.set_defaults(run=record)
    eprobe = edge_sub.add_parser(
        "probe", help="read every input with the valve disabled (wiring check); --calibrate a channel"
    )
    eprobe.add_argument("--config", required=True, metavar="RIG.toml", help="rig config (docs/examples/*.toml)")
    eprobe.add_argument("--rate", type=float, metavar="HZ", help="reads per second (default: the config's loop rate)")
    eprobe.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: at Ctrl-C)")
    eprobe.add_argument(
        "--calibrate",
        metavar="CHANNEL",
        help="two-point calibration: type two known values; prints the scale and zero lines for the config",
    )
    eprobe.add_argument(
        "--average", type=float, default=0.5, metavar="S", help="seconds of readings per calibration point"
    )
    eprobe.add_argument("--json", action="store_true", help="print what was read as one JSON object at the end")
    eprobe.set_defaults(run=probe)
    etel = edge_sub.add_parser("telemetry", help="summarise a telemetry file; export CSV, MCAP or a plot")
    etel.add_argument("file", metavar="FILE", help="telemetry written by pmactl edge run --telemetry")
    etel.add_argument("--csv", metavar="OUT.csv", help="write every telemetry row as CSV here")
    etel.add_argument("--mcap", metavar="OUT.mcap", help="for Foxglove / PlotJuggler (one JSON message per tick)")
    etel.add_argument("--plot", metavar="OUT.png", help="needs matplotlib (the host extra)")
    etel.set_defaults(run=telemetry)


def run(args: argparse.Namespace) -> int:
    from edge.control.reference import parse_reference
    from edge.runtime.bundle import load_bundle
    from edge.runtime.config import load_config
    from edge.runtime.run import EdgeRuntime, check_duration

    config = load_config(args.config)
    reference = parse_reference(args.reference)
    check_duration(args.duration, args.settle, reference)
    if args.telemetry and "{time}" not in args.telemetry and Path(args.telemetry).exists():
        raise DataError(
            f"{args.telemetry}: exists, and a run never overwrites another; choose a new path "
            "(a {time} in the name is replaced by the start time)"
        )
    bundle = load_bundle(args.bundle, trusted_keys=config.bundle_trusted_keys or None)
    runtime = EdgeRuntime(
        config,
        bundle,
        reference,
        feedforward=not args.no_feedforward,
        use_correction=not args.no_correction,
        telemetry_path=args.telemetry,
        settle_s=args.settle,
    )

    _attach_live(runtime, args.live)
    for warning in runtime.warnings:  # before arming
        print(f"pmactl edge: warning: {warning}", file=sys.stderr, flush=True)
    from edge.runtime.status import wants_status

    prefix = "\n" if wants_status(args.json) else ""  # off the status line
    runtime.on_warning.append(lambda text: print(f"{prefix}pmactl edge: warning: {text}", file=sys.stderr, flush=True))
    summary = _run_stoppable(runtime, lambda: runtime.run(args.duration), f"running {args.reference}", args.json)
    result = summary.as_dict()
    if args.json:
        print(json.dumps(result), flush=True)
    else:
        _print_summary(result)
    for fault in summary.faults:
        print(f"pmactl edge: FAULT: {fault} (valve vented)", file=sys.stderr)
    return 1 if summary.faults else 0


def _run_stoppable(runtime: EdgeRuntime, body: Callable[[], T], what: str, json_output: bool) -> T:
    """``body()`` with SIGTERM and SIGINT asking ``runtime`` to stop (it vents and ends cleanly)
    and, for a person at a terminal, how to stop and a status line a second."""
    from edge.runtime.status import StatusLine, describe_frame, wants_status

    def request_stop(*_: object) -> None:
        runtime.stop_requested.set()

    status = None
    live = runtime.live
    if live is not None:
        print(f"live view: {live.url} (Foxglove: Open connection -> Foxglove WebSocket)", file=sys.stderr, flush=True)
    if wants_status(json_output):
        spec = runtime.config.rig
        status = StatusLine(lambda: describe_frame(runtime.frame, spec.output_field, spec.output_unit, runtime.errors))
    previous = {sig: signal.signal(sig, request_stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        if status is not None:
            status.start(what)
        return body()
    finally:
        if status is not None:
            status.stop()
        if live is not None:
            live.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def _attach_live(runtime: EdgeRuntime, address: str | None) -> None:
    """``--live``: a Foxglove WebSocket server fed by the runtime; the rig is released if it fails."""
    if address is None:
        return
    from edge.runtime.live import LiveView

    try:
        runtime.live = LiveView(address, runtime.layout.dtype, runtime.config.loop.rate_hz)
    except BaseException:
        runtime.rig.close()
        raise


def record(args: argparse.Namespace) -> int:
    from edge.runtime import record as recording
    from edge.runtime.config import load_config

    config = load_config(args.config)
    if args.telemetry and "{time}" not in args.telemetry and Path(args.telemetry).exists():
        raise DataError(f"{args.telemetry}: exists, and a run never overwrites another; choose a new path")
    runtime, recorder = recording.record(
        config,
        args.protocol,
        args.out,
        range_text=args.range,
        duration_s=args.duration,
        sample_hz=args.sample_hz,
        telemetry_path=args.telemetry,
    )
    try:
        _attach_live(runtime, args.live)
    except BaseException:
        recording.abandon(runtime, recorder)
        raise
    result = _run_stoppable(
        runtime, lambda: recording.finish(runtime, recorder), f"recording {args.protocol} to {args.out}", args.json
    )
    data = result.as_dict()
    if args.json:
        print(json.dumps(data), flush=True)
    else:
        unit, y_unit = result.unit, config.rig.output_unit
        last = f"t 0..{result.last_t:.2f} s" if result.rows else "nothing"
        print(
            f"{result.rows} rows ({last}) at {result.sample_hz:g} Hz to {result.csv} (+ {data['meta']}); "
            f"protocol {args.protocol} on {result.command_range[0]:g}..{result.command_range[1]:g} {unit}"
        )
        print(
            f"columns: {', '.join(c.name for c in recorder.columns)}; u = "
            f"{recorder.columns[1].meaning} [{unit}], y = {recorder.columns[2].meaning} [{y_unit}]"
        )
        lateness = result.summary.lateness
        print(
            f"{lateness['ticks']:.0f} ticks, overruns {lateness['overruns']:.0f}, lateness p99 "
            f"{lateness['lateness_p99_us']:.0f} us; ticks with a device error {data['bus_errors']}"
        )
        if result.rows and not result.summary.faults:
            print(f"next: pmactl fit --model preisach --train {result.csv} --units {unit},{y_unit} --save BUNDLE_DIR")
    if runtime.stop_requested.is_set() and not result.summary.faults:
        print(
            f"pmactl edge: stopped (valve vented); {result.rows} rows up to t={result.last_t:.3f} s "
            f"kept in {result.csv}",
            file=sys.stderr,
        )
    for fault in result.summary.faults:
        print(
            f"pmactl edge: FAULT: {fault} (valve vented); {result.rows} rows up to "
            f"t={result.last_t:.3f} s kept in {result.csv}",
            file=sys.stderr,
        )
    return 1 if result.summary.faults else 0


def probe(args: argparse.Namespace) -> int:
    import threading

    from edge.runtime.config import load_config
    from edge.runtime.probe import Probe
    from edge.runtime.probe_view import as_dict, calibrate, watch

    config = load_config(args.config)
    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise DataError(f"--duration {args.duration:g} must be a finite number of seconds > 0")
    if not (math.isfinite(args.average) and 0.01 <= args.average <= 60):
        raise DataError(f"--average {args.average:g} must be between 0.01 and 60 s")
    stopped = threading.Event()
    reader = Probe(config, args.rate)  # opened and vented
    previous = {sig: signal.signal(sig, lambda *_: stopped.set()) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        if args.calibrate:
            reader.channel(args.calibrate)  # an unknown channel is refused before anything is shown
            live = sys.stdout.isatty() and sys.stdin.isatty()
            result = calibrate(
                reader, args.calibrate, args.average, sys.stdin.fileno(), sys.stdout, live, stopped.is_set
            )
            if result is None:
                print("pmactl edge probe: stopped before both points; nothing calibrated", file=sys.stderr)
                return 1
        else:
            watch(reader, args.duration, sys.stdout, sys.stdout.isatty() and not args.json, stopped.is_set, args.json)
    finally:
        reader.close()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    if args.json:
        print(json.dumps(as_dict(reader)), flush=True)
    return 0


def _print_summary(result: dict[str, object]) -> None:
    def mm(key: str) -> str:  # mm on a muscle, deg on a joint
        value = result[key]
        return f"{value:.3f} {result.get('unit', 'mm')}" if isinstance(value, float) else "n/a"

    lateness = result["lateness"]
    assert isinstance(lateness, dict)
    print(
        f"{result['ticks']} ticks at {result['rate_hz']:g} Hz, reference {result['reference']}, "
        f"feedforward {'on' if result['feedforward'] else 'off'}, correction {'on' if result['correction'] else 'off'}"
    )
    print(f"tracking error: RMS {mm('rms_error')}, mean |e| {mm('mean_abs_error')}, max {mm('max_error')}")
    if result.get("twin_model"):
        print(f"forward twin: {result['twin_model']}, worst window RMS {mm('twin_rms_max_mm')} (residual)")
    print(
        f"lateness: median {lateness['lateness_median_us']:.0f} us, p99 {lateness['lateness_p99_us']:.0f} us, "
        f"max {lateness['lateness_max_us']:.0f} us; overruns {result['overruns']}; "
        f"ticks with a device error {result['bus_errors']}"
    )
    print(f"real-time: {'; '.join(result['realtime'])}")  # type: ignore[arg-type]
    if result["telemetry"]:
        print(f"telemetry: {result['telemetry']} ({result['telemetry_dropped']} rows dropped)", flush=True)


def telemetry(args: argparse.Namespace) -> int:
    from edge.runtime.telemetry_read import read_telemetry

    for option, path, suffixes in (
        ("--csv", args.csv, (".csv",)),
        ("--mcap", args.mcap, (".mcap",)),
        ("--plot", args.plot, (".png", ".pdf", ".svg")),
    ):
        if path:
            _check_output(Path(path), option, suffixes)  # before reading: no work lost to a bad path
    outputs = [Path(p) for p in (args.csv, args.mcap, args.plot) if p]
    if len(set(map(str, outputs))) < len(outputs):
        raise DataError("--csv, --mcap and --plot name the same file; give each its own")
    record = read_telemetry(args.file)
    if args.csv:
        _write_csv(record, Path(args.csv))
    if args.mcap:
        from edge.runtime.mcap_export import export_mcap

        export_mcap(record, Path(args.mcap))
    if args.plot:
        from edge.runtime.telemetry_plot import plot

        plot(record, Path(args.plot))
    bundle = record.header.get("bundle")
    model = f", model {bundle.get('kind')} {str(bundle.get('id'))[:12]}" if isinstance(bundle, dict) else ""
    print(
        f"{args.file}: {len(record.rows)} ticks at {record.header.get('rate_hz')} Hz, "
        f"{len(record.events)} events{model}"
    )
    for event in record.events:
        print(f"  t={float(event['t']):.3f} s {event['kind']}: {event['text']}")  # type: ignore[arg-type]
    if record.problems:
        print(f"pmactl edge telemetry: skipped: {'; '.join(record.problems)}", file=sys.stderr)
    if not (args.csv or args.plot or args.mcap):
        print("(add --csv OUT.csv, --mcap OUT.mcap and/or --plot OUT.png to export)", file=sys.stderr)
    return 0


def _check_output(path: Path, option: str, suffixes: tuple[str, ...] | None) -> None:
    """One line if ``path`` cannot be written as ``option``'s output file."""
    if (path.exists() and not path.is_dir()) or path.is_symlink():
        raise DataError(f"{option} {path}: exists, and an export never overwrites a file; choose a new name")
    if suffixes and path.suffix.lower() not in suffixes:
        raise DataError(
            f"{option} {path}: cannot write the format '{path.suffix}'; end the name in {' or '.join(suffixes)}"
        )
    if path.is_dir():
        raise DataError(f"{option} {path}: is a directory; name a file")
    parent = path.parent if str(path.parent) else Path(".")
    if not parent.is_dir():
        raise DataError(f"{option} {path}: directory {parent} does not exist; create it first")


def _write_csv(record: object, path: Path) -> None:
    import numpy as np

    rows = record.rows  # type: ignore[attr-defined]
    columns = list(rows.dtype.names)
    table = np.column_stack([rows[c].astype(np.float64) for c in columns]) if len(rows) else np.empty((0, len(columns)))
    try:
        np.savetxt(path, table, delimiter=",", header=",".join(columns), comments="", fmt="%.9g")
    except OSError as exc:
        raise DataError(f"{path}: cannot write the CSV ({exc.strerror})") from exc


def build_parser(prog: str = "python -m edge") -> argparse.ArgumentParser:
    """The ``edge`` subcommands alone (``python -m edge``; ``pmactl edge`` on the SBC path)."""
    parser = argparse.ArgumentParser(prog=prog, description="pmactl edge runtime")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of ``python -m edge`` (``pmactl edge`` goes through ``host.cli``)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    args = build_parser().parse_args(argv if argv[:1] == ["edge"] else ["edge", *argv])
    try:
        return int(args.run(args))
    except PmactlError as exc:
        print(f"pmactl edge: error: {exc}", file=sys.stderr)
    except KeyboardInterrupt:
        print("pmactl edge: interrupted", file=sys.stderr)
        return 130
    return 2
