"""``pmactl hil record``: a recording from the emulated rig with an optional hidden effect."""

from __future__ import annotations

import argparse

from edge.errors import DataError
from hil.record import record, truth_path, write_recording
from host.cli.outputs import check_output
from host.progress import Steps, wanted


def run_record(args: argparse.Namespace) -> int:
    if not 1.0 <= args.duration <= 24 * 3600:
        raise DataError(f"--duration {args.duration} s is outside 1 s .. 24 h")
    check_output(args.out, "--out")
    if getattr(args, "rig", "muscle") == "joint":
        return _record_joint(args)
    with Steps(2, wanted(False), "pmactl hil record") as steps:
        steps.start(f"running {args.duration:g} s of {args.scenario} (about {args.duration / 110:.0f} s)")
        try:
            recording = record(
                args.scenario, args.seed, args.duration, args.effect, args.rate, decoy_columns=args.decoy_columns
            )
        except ValueError as exc:
            raise DataError(str(exc)) from exc
        steps.start(f"writing {args.out}")
        path = write_recording(recording, args.out)
    print(
        f"wrote {path} ({recording.t.size} samples at {args.rate:g} Hz, scenario {args.scenario}, "
        f"effect {args.effect}) and {truth_path(path).name}"
    )
    return 0


def _record_joint(args: argparse.Namespace) -> int:
    from hil.joint_record import record_joint, write_joint_recording

    try:
        recording = record_joint(
            args.scenario, args.seed, args.duration, args.effect, args.rate, command=args.joint_command
        )
    except ValueError as exc:
        raise DataError(str(exc)) from exc
    path = write_joint_recording(recording, args.out)
    print(
        f"wrote {path} (joint: {recording.t.size} samples at {args.rate:g} Hz, scenario {args.scenario}, "
        f"u = {recording.truth['command']} [{recording.truth['u_unit']}]) "
        f"and {truth_path(path).name}"
    )
    return 0
