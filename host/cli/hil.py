"""``pmactl hil record`` (a recording from the emulated rig with an optional hidden effect) and
``pmactl hil serve`` (the emulated rig's serial DAQ on a pseudo-terminal, in real time)."""

from __future__ import annotations

import argparse

from edge.errors import DataError
from host.cli.lazy import lazy
from host.cli.options import add_hil_options, positive_rate
from host.cli.outputs import check_output


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg,unused-ignore]
    """Add ``pmactl hil record`` and ``pmactl hil serve``."""
    from hil.effects import EFFECTS  # names only (no physics imported): pmactl edge never imports hil
    from hil.scenarios import SCENARIOS

    hil = sub.add_parser("hil", help="the emulated rig: recordings with hidden effects")
    hil_sub = hil.add_subparsers(dest="hil_command", required=True, metavar="HIL_COMMAND")
    rec = hil_sub.add_parser("record", help="run a test protocol on the emulated rig and write a measured-data CSV")
    rec.add_argument("--scenario", required=True, choices=list(SCENARIOS), help="test protocol the rig runs")
    rec.add_argument("--seed", type=int, default=0, help="random seed (protocol details and effect parameters)")
    rec.add_argument("--duration", type=float, default=120.0, metavar="S", help="seconds of recording (default 120)")
    rec.add_argument(
        "--effect",
        default="none",
        choices=list(EFFECTS),
        help="hidden effect, parameters drawn from physical ranges (default none)",
    )
    rec.add_argument(
        "--rate", type=positive_rate, default=100.0, metavar="HZ", help="sample rate, divides 1000 (default 100)"
    )
    rec.add_argument(
        "--decoy-columns", action="store_true", help="let load and temperature columns vary without any physical effect"
    )
    rec.add_argument(
        "--rig",
        choices=["muscle", "joint"],
        default="muscle",
        help="one muscle, or two on a pulley (writes t,u,y,u1,u2,p1,p2,theta)",
    )
    rec.add_argument(
        "--joint-command",
        choices=["differential", "angle"],
        default="differential",
        help="joint only: u is the differential pressure [bar], or a commanded angle [deg] through "
        "the edge's static inversion (what the joint controller's Preisach map is fitted on)",
    )
    rec.add_argument("--out", required=True, metavar="CSV", help="output CSV; the truth goes to <name>.truth.json")
    rec.set_defaults(run=lazy("host.cli.hil", "run_record"))
    srv = hil_sub.add_parser("serve", help="real-time mode: serve the emulated rig's serial DAQ on a pseudo-terminal")
    add_hil_options(srv, EFFECTS)
    srv.add_argument("--rate", type=positive_rate, default=1000.0, metavar="HZ", help="sample frames per second")
    srv.add_argument("--duration", type=float, metavar="S", help="stop after S seconds (default: until SIGTERM)")
    srv.add_argument("--config", metavar="RIG.toml", help="wire sensors and valve as this rig config says")
    srv.set_defaults(run=lazy("host.cli.hil", "run_serve"))


def run_serve(args: argparse.Namespace) -> int:
    from hil.serve import serve

    return serve(args.effect, args.seed, args.rate, args.duration, args.config)


def run_record(args: argparse.Namespace) -> int:
    from hil.record import record, truth_path, write_recording
    from host.progress import Steps, wanted

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
    from hil.record import truth_path

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
