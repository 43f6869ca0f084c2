"""``pmactl edge run`` and ``pmactl edge telemetry``: the runtime from the command line.

Only ``edge`` modules are imported for ``run``, so it works on an SBC with the edge extra.
SIGTERM and SIGINT end the loop cleanly: the valve is vented, telemetry drained, the summary
printed.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path

from edge.control.reference import parse_reference
from edge.errors import DataError
from edge.runtime.bundle import load_bundle
from edge.runtime.config import load_config
from edge.runtime.run import EdgeRuntime


def run(args: argparse.Namespace) -> int:
    if args.duration is not None and args.duration <= 0:
        raise DataError(f"--duration {args.duration:g} must be positive (seconds)")
    config = load_config(args.config)
    reference = parse_reference(args.reference)
    bundle = load_bundle(args.bundle)
    runtime = EdgeRuntime(
        config,
        bundle,
        reference,
        feedforward=not args.no_feedforward,
        use_correction=not args.no_correction,
        telemetry_path=args.telemetry,
        settle_s=args.settle,
    )

    def request_stop(*_: object) -> None:
        runtime.stop_requested.set()

    previous = {sig: signal.signal(sig, request_stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    try:
        summary = runtime.run(args.duration)
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    result = summary.as_dict()
    if args.json:
        print(json.dumps(result))
    else:
        _print_summary(result)
    return 1 if summary.faults else 0


def _print_summary(result: dict[str, object]) -> None:
    def mm(key: str) -> str:
        value = result[key]
        return f"{value:.3f} mm" if isinstance(value, float) else "n/a"

    lateness = result["lateness"]
    assert isinstance(lateness, dict)
    print(
        f"{result['ticks']} ticks at {result['rate_hz']:g} Hz, reference {result['reference']}, "
        f"feedforward {'on' if result['feedforward'] else 'off'}, correction {'on' if result['correction'] else 'off'}"
    )
    print(f"tracking error: RMS {mm('rms_error')}, mean |e| {mm('mean_abs_error')}, max {mm('max_error')}")
    print(
        f"lateness: median {lateness['lateness_median_us']:.0f} us, p99 {lateness['lateness_p99_us']:.0f} us, "
        f"max {lateness['lateness_max_us']:.0f} us; overruns {result['overruns']}; bus errors {result['bus_errors']}"
    )
    print(f"real-time: {'; '.join(result['realtime'])}")  # type: ignore[arg-type]
    for fault in result["faults"]:  # type: ignore[union-attr]
        print(f"FAULT: {fault} (valve vented)")
    if result["telemetry"]:
        print(f"telemetry: {result['telemetry']} ({result['telemetry_dropped']} rows dropped)")


def telemetry(args: argparse.Namespace) -> int:
    from edge.runtime.telemetry import read_telemetry
    from host.cli.outputs import FIGURE_SUFFIXES, check_output

    if args.csv:
        check_output(args.csv, "--csv")
    if args.plot:
        check_output(args.plot, "--plot", suffixes=FIGURE_SUFFIXES)
    record = read_telemetry(args.file)
    columns = list(record.header["columns"])  # type: ignore[call-overload]
    if args.csv:
        import numpy as np

        np.savetxt(args.csv, record.rows, delimiter=",", header=",".join(columns), comments="", fmt="%.9g")
    if args.plot:
        _plot(record, Path(args.plot))
    print(
        f"{args.file}: {len(record.rows)} ticks at {record.header.get('rate_hz')} Hz, {len(record.events)} events"
        + (f", {record.truncated_bytes} bytes of a partial last row ignored" if record.truncated_bytes else "")
    )
    for event in record.events:
        print(f"  t={event['t']:.3f} s {event['kind']}: {event['text']}")
    if not (args.csv or args.plot):
        print("(add --csv OUT.csv and/or --plot OUT.png to export)", file=sys.stderr)
    return 0


def _plot(record, path: Path) -> None:  # noqa: ANN001
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = record.column("t")
    fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True)
    axes[0].plot(t, record.column("reference_mm"), label="reference")
    axes[0].plot(t, record.column("contraction_mm"), label="measured")
    axes[0].set_ylabel("contraction [mm]")
    axes[0].legend(loc="upper right")
    for name in ("u_ff_bar", "u_nn_bar", "u_fb_bar", "u_bar"):
        axes[1].plot(t, record.column(name), label=name.removesuffix("_bar"))
    axes[1].set_ylabel("pressure command [bar]")
    axes[1].legend(loc="upper right", ncol=4)
    axes[2].plot(t, record.column("lateness_us"), lw=0.5)
    axes[2].set_ylabel("lateness [us]")
    axes[2].set_xlabel("t [s]")
    fig.suptitle(f"{record.header.get('reference')} ({record.header.get('rate_hz')} Hz)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
