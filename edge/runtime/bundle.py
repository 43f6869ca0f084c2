"""Load and verify a model bundle (see ``models_export.bundle`` for the layout), numpy only."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

from edge.errors import BundleError
from edge.hysteresis.lut import CompiledModel, read_table

FORMAT = "pmactl-bundle"
FORMAT_VERSION = 1
MANIFEST = "manifest.json"


@dataclass
class Bundle:
    """A verified bundle: the manifest and the evaluators of its tables."""

    path: Path
    manifest: dict[str, object]
    forward: CompiledModel
    inverse: CompiledModel
    correction_path: Path | None = None

    @property
    def units(self) -> tuple[str, str]:
        """(input unit, output unit) as the fit recorded them."""
        units = dict(dict(self.manifest.get("model", {})).get("units", {}))  # type: ignore[arg-type]
        return str(units.get("input", "?")), str(units.get("output", "?"))

    @property
    def correction_spec(self) -> dict[str, object] | None:
        spec = self.manifest.get("correction")
        return dict(spec) if isinstance(spec, dict) else None

    def require_units(self, input_unit: str, output_unit: str) -> None:
        """Refuse a bundle fitted in other units than the runtime's (a silent 10x error otherwise)."""
        if self.units != (input_unit, output_unit):
            raise BundleError(
                f"{self.path}: model maps {self.units[0]} -> {self.units[1]}, the edge needs {input_unit} -> "
                f"{output_unit}; re-fit with pmactl fit --units {input_unit},{output_unit} --save"
            )


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def load_bundle(directory: str | Path) -> Bundle:
    """Read ``directory``, check format and every file's checksum, and build the evaluators."""
    root = Path(directory)
    manifest_path = root / MANIFEST
    try:
        manifest = json.loads(manifest_path.read_text())
    except FileNotFoundError as exc:
        raise BundleError(f"{root}: no {MANIFEST}; point at a directory written by pmactl fit --save") from exc
    except (OSError, json.JSONDecodeError) as exc:
        raise BundleError(f"{manifest_path}: unreadable manifest ({exc}); re-export the bundle") from exc
    if manifest.get("format") != FORMAT or manifest.get("format_version") != FORMAT_VERSION:
        raise BundleError(
            f"{manifest_path}: format {manifest.get('format')!r} v{manifest.get('format_version')} "
            f"is not {FORMAT} v{FORMAT_VERSION}; re-export with this pmactl version"
        )
    tables = {}
    correction_path = None
    for name, entry in dict(manifest.get("files", {})).items():
        path = root / name
        if not path.is_file():
            raise BundleError(f"{root}: file {name} listed in the manifest is missing; re-copy the bundle")
        if _sha256(path) != entry.get("sha256"):
            raise BundleError(f"{path}: checksum mismatch (corrupt or edited); re-copy the bundle")
        if entry.get("role") == "correction":
            correction_path = path
        else:
            tables[entry.get("role")] = read_table(path)
    missing = {"forward", "inverse"} - set(tables)
    if missing:
        raise BundleError(f"{manifest_path}: no {' or '.join(sorted(missing))} table listed; re-export the bundle")
    if ("correction" in manifest) != (correction_path is not None):
        raise BundleError(f"{manifest_path}: correction entry and correction file do not go together; re-export")
    return Bundle(root, manifest, CompiledModel(tables["forward"]), CompiledModel(tables["inverse"]), correction_path)
