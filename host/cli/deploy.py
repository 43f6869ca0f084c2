"""``pmactl deploy``, ``pmactl rollback`` and ``pmactl releases``."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from host.cli.outputs import strict_json

if TYPE_CHECKING:
    from host.deploy.deploy import Outcome

TARGET_HELP = "a directory, or ssh://[user@]host[:port]/path (uses ~/.ssh/config, ssh-agent, known_hosts)"


def register(sub: argparse._SubParsersAction) -> None:
    deploy = sub.add_parser("deploy", help="ship a bundle to a rig, check it there, switch to it atomically")
    deploy.add_argument("directory", metavar="DIR", help="bundle directory (its current release) or a release")
    deploy.add_argument("target", metavar="TARGET", help=TARGET_HELP)
    _common(deploy)
    deploy.add_argument(
        "--keep", type=int, default=5, metavar="N", help="releases kept on the target (default 5, >= 2)"
    )
    deploy.add_argument(
        "--post-flip",
        metavar="CMD",
        help="shell command run on the target after the switch (e.g. "
        "'systemctl restart pmactl-edge'); a non-zero exit rolls back",
    )
    deploy.add_argument("--json", action="store_true", help="print the outcome as one JSON object")
    deploy.set_defaults(run=run_deploy)

    rollback = sub.add_parser("rollback", help="switch a rig back to its previous release (checked first)")
    rollback.add_argument("target", metavar="TARGET", help=TARGET_HELP)
    _common(rollback)
    rollback.add_argument("--json", action="store_true", help="print the outcome as one JSON object")
    rollback.set_defaults(run=run_rollback)

    releases = sub.add_parser("releases", help="list the releases on a rig and which one is current")
    releases.add_argument("target", metavar="TARGET", help=TARGET_HELP)
    releases.add_argument("--remote-python", default="python3", metavar="PATH", help="Python with pmactl on the target")
    releases.add_argument("--json", action="store_true", help="print the releases as one JSON object")
    releases.set_defaults(run=run_releases)


def _common(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--trusted", action="append", default=[], metavar="PUB", help="trusted pmactl.pub (repeatable)")
    parser.add_argument(
        "--tick-limit-us",
        type=float,
        default=200.0,
        metavar="US",
        help="health check: median model evaluation per tick must stay below this (default 200 us)",
    )
    parser.add_argument(
        "--remote-python",
        default="python3",
        metavar="PATH",
        help="Python with pmactl[edge] on an ssh target (default python3; e.g. /opt/pmactl/venv/bin/python)",
    )


def _report(outcome: Outcome, as_json: bool, verb: str) -> int:
    from host.deploy import DeployError

    if as_json:
        print(strict_json(outcome.as_dict(), default=str))
    else:
        for step in outcome.steps:
            mark = "ok    " if step.get("ok") else "FAILED"
            seconds = f"{step['seconds']:.3f} s" if isinstance(step.get("seconds"), float) else ""
            print(f"  {mark} {step['step']:<17} {seconds}")
    if not outcome.ok:
        rolled = "; rolled back to the release that ran before" if outcome.rolled_back else ""
        state = f"; current is {outcome.current or 'none'}" if outcome.reached else "; the target was not contacted"
        raise DeployError(
            f"{verb} to {outcome.target} failed at step '{outcome.failed_step}': {outcome.error}{rolled}{state}"
        )
    return 0


def run_deploy(args: argparse.Namespace) -> int:
    import asyncio
    from pathlib import Path

    from host.deploy.deploy import deploy

    outcome = asyncio.run(
        deploy(
            args.directory,
            args.target,
            trusted=[Path(p) for p in args.trusted],
            keep=args.keep,
            tick_limit_us=args.tick_limit_us,
            post_flip=args.post_flip,
            remote_python=args.remote_python,
        )
    )
    _report(outcome, args.json, "deploy")
    if not args.json:
        print(
            f"deployed release {outcome.release} to {outcome.target} in {outcome.seconds:.2f} s "
            f"({outcome.bytes_sent} bytes); current {outcome.current}, previous {outcome.previous or 'none'}"
        )
        if outcome.pinned_keys:
            print(
                f"the target now trusts only key(s) {', '.join(outcome.pinned_keys)} "
                f"(written to its trusted_keys/; later deploys must be signed by one of them)"
            )
    return 0


def run_rollback(args: argparse.Namespace) -> int:
    import asyncio
    from pathlib import Path

    from host.deploy.deploy import rollback

    outcome = asyncio.run(
        rollback(
            args.target,
            trusted=[Path(p) for p in args.trusted],
            tick_limit_us=args.tick_limit_us,
            remote_python=args.remote_python,
        )
    )
    _report(outcome, args.json, "rollback")
    if not args.json:
        print(f"rolled back {outcome.target}: current {outcome.current}, previous {outcome.previous}")
    return 0


def run_releases(args: argparse.Namespace) -> int:
    import asyncio

    from host.deploy.deploy import list_releases

    outcome = asyncio.run(list_releases(args.target, remote_python=args.remote_python))
    if args.json:
        print(
            strict_json(
                {
                    "target": outcome.target,
                    "current": outcome.current,
                    "previous": outcome.previous,
                    "releases": outcome.releases,
                }
            )
        )
    _report(outcome, False, "listing releases") if not outcome.ok else None
    if not args.json:
        if not outcome.releases:
            print(f"{outcome.target}: no releases")
        for release in outcome.releases:
            mark = "current " if release["current"] else "previous" if release["previous"] else ""
            print(
                f"{mark:<8} {release['id']}  {release['created_utc']}  {release['kind']:<9} "
                f"signer {release['signer'] or 'unsigned'}"
            )
    return 0
