"""The work of ``pmactl demo`` (its command line is :mod:`host.cli.demo`): the whole path on the
shipped example data.

For every model: identify on the training recording, score on the held-out one (initial state
and offset estimated, see :mod:`host.evaluate`), write the bundle, load it back the way the
edge does (numpy only, checksums verified) and check that the lookup tables reproduce the
reference model and that the inverse table undoes the forward table. Then run the edge loop
(``pmactl edge run``) on the emulated rig in lockstep with the Preisach bundle: Ai2019's
tracking test, PID alone, PID + inverse-hysteresis feedforward, and PID + feedforward + the
neural correction ``pmactl train --model correction`` adds to the bundle (trained here on the
emulated rig's working range, see :mod:`host.train.correction`). Last, Schreiber's antagonistic
joint: PID alone against PID + inverse-Preisach feedforward (:func:`joint_loop`).

Everything goes to ``--out`` (default ``./pmactl-demo``; new, empty, or an earlier demo's
folder, see :func:`host.cli.demo.demo_directory`): a bundle per model, the three tracking runs' telemetry and
the figures ``loops.png`` (measured vs model loops), ``tracking.png`` (the closed loop, all
three controllers) and ``joint.png`` (the joint, both controllers). Each result is printed as it finishes.
"""

from __future__ import annotations

import argparse
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from edge.control.reference import beyond_reach, parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.config import load_config
from edge.runtime.run import EdgeRuntime
from edge.runtime.telemetry import read_telemetry
from hil.configs import HIL_JOINT_CONFIG, HIL_RIG_CONFIG
from hil.joint_record import record_joint, write_joint_recording
from host.cli.outputs import strict_json
from host.data import Measurement, load_measurement
from host.demo_figures import plot_loops, plot_tracking
from host.examples import example_path
from host.train.correction import correction_bundle
from host.workflow import make_estimator, rest_state, save_bundle, score_on

MODELS = ("pi", "mpi", "dpi", "preisach")
TRACKING = "sine:amplitude=30,frequency=0.2,offset=40"  # Ai2019 Table 4: 3 sin(2 pi 0.2 t) + 4 cm
TRACKING_S, SETTLE_S = 25.0, 5.0
# key: (label, inverse feedforward on, trained correction on)
CONTROLLERS = {
    "pid": ("PID", False, False),
    "feedforward": ("PID + inverse feedforward", True, False),
    "correction": ("PID + feedforward + trained NN", True, True),
}


def identify(name: str, train: Measurement, test: Measurement, out: Path) -> tuple[dict[str, object], np.ndarray, int]:
    """Fit, score, bundle, load back and check one model; the row, the test prediction, its first scored sample."""
    estimator = make_estimator(name).fit(train.u, train.y)
    [result] = score_on(estimator.model_, [test])
    bundle_dir = save_bundle(estimator, train, out / name, ("bar", "mm"), {"model": name})
    bundle = load_bundle(bundle_dir)
    # parity: reference model vs its lookup table, both from the rest state, on the test input
    forward, _ = rest_state(estimator.model_, float(train.u.min()))
    reference = forward.simulate(test.u)
    table = bundle.forward.simulate(test.u)
    round_trip = bundle.inverse.simulate(table)
    score = result.prediction.score
    row = {
        "model": name,
        "fit_seconds": estimator.fit_seconds_,
        "rmse_mm": score.rmse,
        "rmse_pct_pp": score.rmse_pct_pp,
        "max_error_mm": score.max_error,
        "table_vs_reference_mm": float(np.abs(reference - table).max()),
        "inverse_round_trip_bar": float(np.abs(round_trip - np.clip(test.u, *bundle.forward.input_range)).max()),
        "input_range_bar": list(bundle.forward.input_range),
        "bundle": str(bundle_dir),
    }
    return row, result.prediction.y, result.prediction.window_end


def tracked_run(
    config: Path,
    bundle_dir: Path,
    reference: str,
    duration_s: float,
    telemetry: Path,
    label: str,
    say: Callable[[str], None],
    *,
    feedforward: bool,
    use_correction: bool = False,
) -> dict[str, object]:
    """One ``pmactl edge run`` on the emulated rig in lockstep; its summary row, also printed."""
    # the demo's own output from its previous run (the edge never overwrites telemetry by itself)
    for previous in (telemetry, telemetry.with_name(telemetry.name + ".events.jsonl")):
        previous.unlink(missing_ok=True)
    runtime = EdgeRuntime(
        load_config(config),
        load_bundle(bundle_dir),
        parse_reference(reference),
        settle_s=SETTLE_S,
        telemetry_path=telemetry,
        feedforward=feedforward,
        use_correction=use_correction,
    )
    row: dict[str, object] = {"controller": label, **runtime.run(duration_s).as_dict()}
    faults = row["faults"]
    assert isinstance(faults, list)
    say(
        f"{label:<31} {row['max_error']:>9.2f} {row['mean_abs_error']:>14.2f} {row['rms_error']:>9.2f} {len(faults):>7}"
    )
    return row


def closed_loop(bundle_dir: Path, out: Path, say: Callable[[str], None]) -> list[dict[str, object]]:
    """Ai2019 Table 5 on the emulated rig, one row per controller (errors in mm)."""
    return [
        tracked_run(
            HIL_RIG_CONFIG,
            bundle_dir,
            TRACKING,
            TRACKING_S,
            out / f"tracking-{key}.pmt",
            label,
            say,
            feedforward=feedforward,
            use_correction=correction,
        )  # fmt: skip
        for key, (label, feedforward, correction) in CONTROLLERS.items()
    ]


JOINT_TRACKING = "sine:amplitude=15,frequency=0.2,offset=0"  # deg
JOINT_FORC_S, JOINT_S = 120.0, 20.0


def joint_loop(out: Path, say: Callable[[str], None]) -> list[dict[str, object]]:
    """Schreiber's antagonistic joint on the emulated rig: record first-order descending curves
    through the edge's static inversion, fit the Everett map (deg -> deg), then track a sine with
    PID alone and with PID + inverse-Preisach feedforward (errors in deg)."""
    csv = write_joint_recording(record_joint("forc", 0, JOINT_FORC_S, command="angle"), out / "joint-forc.csv")
    train = load_measurement(csv)
    estimator = make_estimator("preisach", preisach_method="forc").fit(train.u, train.y)
    bundle_dir = save_bundle(estimator, train, out / "joint", ("deg", "deg"), {"model": "preisach"})
    say(f"  Everett map from {len(train)} samples of first-order descending curves: {bundle_dir}")
    say(f"{'controller':<31} {'max [deg]':>9} {'mean |e| [deg]':>14} {'RMS [deg]':>9} {'faults':>7}")
    return [
        tracked_run(
            HIL_JOINT_CONFIG,
            bundle_dir,
            JOINT_TRACKING,
            JOINT_S,
            out / f"joint-{key}.pmt",
            label,
            say,
            feedforward=feedforward,
        )  # fmt: skip
        for key, label, feedforward in (("pid", "PID", False), ("feedforward", "PID + inverse Preisach", True))
    ]


def tracking_figure(
    out: Path,
    prefix: str,
    keys: list[str],
    loop: list[dict[str, object]],
    reachable: tuple[float, float],
    quantity: str = "contraction",
    unit: str = "mm",
) -> Path:
    """``{prefix}.png`` from the telemetry ``{prefix}-{key}.pmt`` of each run in ``loop``."""
    output = {"mm": ("reference_mm", "contraction_mm"), "deg": ("reference_deg", "angle_deg")}[unit]
    runs, rms = {}, {}
    for key, row in zip(keys, loop):
        record = read_telemetry(out / f"{prefix}-{key}.pmt")
        runs[str(row["controller"])] = {
            "t": record.column("t"),
            "reference": record.column(output[0]),
            "output": record.column(output[1]),
            "command_bar": record.column("u_bar"),
            "pressure_bar": record.column("pressure_bar"),
        }
        if "valve_b_bar" in record.columns:
            runs[str(row["controller"])]["command_b_bar"] = record.column("valve_b_bar")
        rms[str(row["controller"])] = float(row["rms_error"])  # type: ignore[arg-type]
    return plot_tracking(out / f"{prefix}.png", runs, SETTLE_S, reachable, rms, quantity=quantity, unit=unit)


def run_demo(args: argparse.Namespace) -> int:
    """Everything ``pmactl demo`` prints, in order; ``args``: ``out``, ``json``."""
    from host.cli.demo import demo_directory

    out = demo_directory(args.out)
    say: Callable[[str], None] = (lambda line: None) if args.json else (lambda line: print(line, flush=True))
    train = load_measurement(example_path("train"))
    test = load_measurement(example_path("test"))
    say("pmactl demo: muscle pressure [bar] -> contraction [mm], example data shipped with pmactl")
    say(f"  train: {Path(train.source).name} ({len(train)} samples: triangles 0->1,2,3,4 bar at 0.05 Hz)")
    say(f"  test:  {Path(test.source).name} ({len(test)} samples: slow sine + faster sine, minor loops)")
    say("")
    say(
        f"{'model':<9} {'fit [s]':>8} {'RMSE [mm]':>10} {'% p-p':>7} {'max [mm]':>9} "
        f"{'table-ref [mm]':>15} {'inv(fwd) [bar]':>15}"
    )
    rows, predictions = [], {}
    for name in MODELS:
        row, y_hat, start = identify(name, train, test, out)
        rows.append(row)
        predictions[name] = (y_hat, start, float(row["rmse_pct_pp"]))  # type: ignore[arg-type]
        say(
            f"{name:<9} {row['fit_seconds']:>8.3f} {row['rmse_mm']:>10.4f} {row['rmse_pct_pp']:>7.2f} "
            f"{row['max_error_mm']:>9.3f} {row['table_vs_reference_mm']:>15.2e} {row['inverse_round_trip_bar']:>15.2e}"
        )
    loops = plot_loops(out / "loops.png", test.u, test.y, predictions)
    say("")
    say("RMSE etc.: held-out test, after estimating its initial state and offset on its first 10 %.")
    say("table-ref: lookup table (as the edge loads it) vs reference model; inv(fwd): inverse table")
    say(f"applied to the forward table's output, against the input. Measured vs model loops: {loops}")
    say("")
    say("Training the inverse correction on the emulated rig's working range (pmactl train --model correction) ...")
    trained = correction_bundle(out / "preisach")
    say(
        f"  {trained.samples} samples, {trained.fit_seconds:.1f} s; held-out inverse error "
        f"{trained.tail_rmse_ff_bar:.3f} bar (table alone) -> {trained.tail_rmse_bar:.3f} bar (table + NN)"
    )
    say("")
    reachable = load_bundle(out / "preisach").inverse.input_range
    reach = beyond_reach(parse_reference(TRACKING), TRACKING_S, reachable)
    if reach:
        warnings.warn(f"demo tracking test: {reach}", stacklevel=1)
    say(f"Closed loop on the emulated rig ({HIL_RIG_CONFIG.name}: ADS1015 + MCP4725 over I2C, 1 kHz, lockstep),")
    say(f"tracking 30 sin(2 pi 0.2 t) + 40 mm for {TRACKING_S:g} s, scored after {SETTLE_S:g} s (pmactl edge run):")
    say(f"{'controller':<31} {'max [mm]':>9} {'mean |e| [mm]':>14} {'RMS [mm]':>9} {'faults':>7}")
    loop = closed_loop(out / "preisach", out, say)
    tracking = tracking_figure(out, "tracking", list(CONTROLLERS), loop, reachable)
    pid_rms, ff_rms, nn_rms = (float(row["rms_error"]) for row in loop)  # type: ignore[arg-type]
    say(f"Feedforward cuts the RMS error by {1 - ff_rms / pid_rms:.0%} (Ai2019 reports 48 %); with the trained")
    say(f"correction the RMS error is {nn_rms / pid_rms:.2f}x PID alone. Tracking: {tracking}")
    say("")
    say(
        f"The antagonistic joint of Schreiber et al. ({HIL_JOINT_CONFIG.name}: two muscles on a pulley, 500 Hz, "
        "lockstep),"
    )
    say(f"tracking 15 sin(2 pi 0.2 t) deg for {JOINT_S:g} s, scored after {SETTLE_S:g} s:")
    joint = joint_loop(out, say)
    joint_cut = 1 - float(joint[1]["rms_error"]) / float(joint[0]["rms_error"])  # type: ignore[arg-type]
    joint_reach = load_bundle(out / "joint").inverse.input_range
    joint_figure = tracking_figure(out, "joint", ["pid", "feedforward"], joint, joint_reach, "joint angle", "deg")
    say(f"Inverse-Preisach feedforward cuts the joint's RMS angle error by {joint_cut:.0%}. Joint: {joint_figure}")
    say(f"Everything is in {out}/ (bundles, telemetry, figures); delete it when done.")
    if args.json:
        report = {
            "train": train.source,
            "test": test.source,
            "models": rows,
            "correction": trained.as_dict(),
            "closed_loop": loop,
            "joint": joint,
            "figures": [str(loops), str(tracking), str(joint_figure)],
            "warnings": [reach] if reach else [],
        }
        print(strict_json(report, indent=2))
    return 0
