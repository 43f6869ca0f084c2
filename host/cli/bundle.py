"""``pmactl keygen`` and ``pmactl bundle sign|verify|inspect``."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from host.cli.outputs import strict_json


def register(sub: argparse._SubParsersAction) -> None:
    keygen = sub.add_parser("keygen", help="make an Ed25519 key pair for signing bundles")
    keygen.add_argument("--out", required=True, metavar="DIR", help="writes DIR/pmactl.key (mode 0600), DIR/pmactl.pub")
    keygen.set_defaults(run=run_keygen)

    bundle = sub.add_parser("bundle", help="sign, verify and inspect model bundles")
    bundle_sub = bundle.add_subparsers(dest="bundle_command", required=True, metavar="BUNDLE_COMMAND")
    sign = bundle_sub.add_parser("sign", help="sign a bundle's current release")
    sign.add_argument("directory", metavar="DIR", help="bundle directory (or one release)")
    sign.add_argument("--key", required=True, metavar="KEY", help="pmactl.key from pmactl keygen")
    sign.set_defaults(run=run_sign)
    verify = bundle_sub.add_parser("verify", help="check signature, checksums, roles and golden vectors")
    verify.add_argument("directory", metavar="DIR", help="bundle directory (or one release)")
    verify.add_argument(
        "--trusted",
        action="extend",
        nargs="+",
        default=[],
        metavar="PUB",
        help="trusted pmactl.pub files; when given, an unsigned bundle or another signer is refused",
    )
    verify.set_defaults(run=run_verify)
    inspect = bundle_sub.add_parser(
        "inspect", help="what a bundle holds: model, units, ranges, files, signer, provenance"
    )
    inspect.add_argument("directory", metavar="DIR", help="bundle directory (or one release)")
    inspect.add_argument("--json", action="store_true", help="print one JSON object")
    inspect.set_defaults(run=run_inspect)


def add_key_option(parser: argparse.ArgumentParser, what: str) -> None:
    """``--key KEY``: sign the new release the command writes (``what`` says which, in --help)."""
    parser.add_argument(
        "--key",
        metavar="KEY",
        help=f"pmactl.key from pmactl keygen: sign the new release {what} (without it, a signed "
        "bundle gets an unsigned release and the command says how to sign it)",
    )


def signing_state(directory: str | Path, key: str | None) -> str | None:
    """Before a command writes a release: refuse an unusable ``--key`` (nothing trained or written
    yet) and return the key id that signed the current release (``None``: unsigned)."""
    from models_export.signing import read_private_key, signer_of

    if key is not None:
        read_private_key(Path(key))
    return signer_of(directory)


def report_signing(directory: str | Path, key: str | None, signed_before: str | None, *, json_output: bool) -> None:
    """After a command wrote a release: sign it with ``key``, or print the one-line notice that it
    is unsigned (stderr); the confirmation goes to stdout unless the command prints JSON."""
    from models_export.signing import after_new_release

    line, warning = after_new_release(directory, key, signed_before)
    if line:
        print(
            f"pmactl: warning: {line}" if warning else line, file=sys.stderr if warning or json_output else sys.stdout
        )


def run_keygen(args: argparse.Namespace) -> int:
    from edge.runtime.bundle import read_public_key
    from models_export.signing import keygen

    private, public = keygen(args.out)
    print(f"wrote {private} (private, mode 600) and {public}; key id {read_public_key(public)[0]}")
    return 0


def run_sign(args: argparse.Namespace) -> int:
    from edge.runtime.bundle import load_bundle
    from models_export.signing import sign_release

    load_bundle(args.directory)  # only a bundle that verifies gets a signature
    release, key = sign_release(args.directory, args.key)
    print(f"signed release {release.name} ({release}) with key {key}")
    return 0


def _trusted(paths: list[str]) -> list[tuple[str, bytes]] | None:
    from edge.runtime.bundle import read_public_key

    return [read_public_key(Path(p)) for p in paths] or None


def run_verify(args: argparse.Namespace) -> int:
    from host.deploy.health import verify_release

    bundle, report = verify_release(args.directory, _trusted(args.trusted))
    trust = " (trusted)" if args.trusted else " (not checked against trusted keys: pass --trusted PUB)"
    signer = f"signed by {report.signer}{trust}" if report.signer else "unsigned"
    print(
        f"ok: release {bundle.release_id} ({bundle.path}), {signer}; checksums, roles and "
        f"{report.golden_samples} golden samples verified"
    )
    return 0


def describe(directory: str | Path) -> dict[str, object]:
    """The inspect record of a bundle (verified as it is loaded; the signer is checked against
    the key embedded in the signature)."""
    from host.deploy.health import verify_release

    bundle, report = verify_release(directory)
    manifest = bundle.manifest
    model = manifest.get("model") if isinstance(manifest.get("model"), dict) else {}
    files = manifest["files"]
    assert isinstance(files, dict) and isinstance(model, dict)
    return {
        "release": bundle.release_id,
        "path": str(bundle.path),
        "bundle_id": bundle.manifest_sha256,
        "created_utc": manifest.get("created_utc"),
        "kind": model.get("kind"),
        "units": {"input": bundle.units[0], "output": bundle.units[1]},
        "input_range": model.get("input_range"),
        "reachable_output_range": model.get("reachable_output_range"),
        "files": {
            name: {"role": e.get("role"), "sha256": e.get("sha256"), "bytes": (bundle.path / name).stat().st_size}
            for name, e in files.items()
        },
        "signer": report.signer,
        "correction": manifest.get("correction"),
        "quantisation": manifest.get("quantisation"),
        "provenance": manifest.get("provenance", {"pmactl_version": manifest.get("pmactl_version")}),
        "fit": manifest.get("fit"),
        "golden_samples": report.golden_samples,
        "roles": manifest.get("roles"),
        "nets": {
            which: {
                k: spec.get(k, "lstm-narmax" if k == "model" else None)
                for k in ("model", "file", "step_s", "preview_s", "maps")
            }
            for which, spec in (manifest.get("nets") or {}).items()  # type: ignore[attr-defined]
            if isinstance(spec, dict)
        },
    }


def _range(values: object, unit: str) -> str:
    if not isinstance(values, list):
        return "?"
    return (
        "["
        + ", ".join(
            "-inf" if v is None and i == 0 else "inf" if v is None else f"{v:.6g}" for i, v in enumerate(values)
        )
        + f"] {unit}"
    )


def _roles_line(roles: object) -> str:
    if not isinstance(roles, dict):
        return "not recorded (an older release: feedforward table, forward table)"
    return "; ".join(f"{kind} {', '.join(names)}" for kind, names in roles.items())


def _nets_line(nets: object) -> str:
    if not isinstance(nets, dict) or not nets:
        return "none"
    parts = []
    for which, spec in nets.items():
        preview = f", preview {spec['preview_s'] * 1e3:g} ms" if spec.get("preview_s") else ""
        parts.append(
            f"{which} {spec.get('model')} {spec.get('file')} ({spec.get('maps')}, step "
            f"{spec.get('step_s', 0) * 1e3:g} ms{preview})"
        )
    return "; ".join(parts)


def run_inspect(args: argparse.Namespace) -> int:
    record = describe(args.directory)
    if args.json:
        print(strict_json(record, indent=2))
        return 0
    units = record["units"]
    assert isinstance(units, dict)
    provenance = record["provenance"]
    assert isinstance(provenance, dict)
    lines = [
        f"release      {record['release']}  ({record['path']})",
        f"created      {record['created_utc']}",
        f"model        {record['kind']}: {units['input']} -> {units['output']}",
        f"input        {_range(record['input_range'], units['input'])}",
        f"reachable    {_range(record['reachable_output_range'], units['output'])}",
        f"signer       {record['signer'] or 'unsigned'}",
        f"correction   {json.dumps(record['correction']) if record['correction'] else 'none'}",
        f"quantisation {json.dumps(record['quantisation']) if record['quantisation'] else 'none recorded'}",
        f"roles        {_roles_line(record['roles'])}",
        f"nets         {_nets_line(record['nets'])}",
        f"provenance   pmactl {provenance.get('pmactl_version')}, python {provenance.get('python', '?')}, "
        f"host {provenance.get('host', '?')}",
    ]
    for item in provenance.get("training_data", []) or ["no training data recorded"]:
        lines.append(
            f"  trained on {item['file']} ({item['bytes']} bytes, sha256 {item['sha256']})"
            if isinstance(item, dict)
            else f"  {item}"
        )
    files = record["files"]
    assert isinstance(files, dict)
    lines.append(f"files        ({record['golden_samples']} golden samples verified)")
    for name, entry in files.items():
        lines.append(f"  {name:<16} {entry['role']:<10} {entry['bytes']:>8} B  sha256 {entry['sha256'][:16]}...")
    print("\n".join(lines))
    return 0
