"""Capture the golden 25 s lockstep run from the pre-redesign runtime (commit 4df3193)."""

import hashlib
import json
from pathlib import Path

import numpy as np

from edge.runtime.telemetry import read_telemetry
from tests.edge_helpers import runtime

root = Path("tests/data/edge_golden")
out = {}
for name, ff in (("feedforward", True), ("pid", False)):
    path = Path(f"/tmp/golden_{name}.pmt")
    path.unlink(missing_ok=True)
    s = runtime(root / "bundle", feedforward=ff, telemetry_path=path, settle_s=5.0).run(25.0).as_dict()
    rec = read_telemetry(path)
    cols = list(rec.header["columns"])
    rows = rec.rows
    dec = rows[::100]
    out[name] = {
        "summary": {k: s[k] for k in ("rms_error", "mean_abs_error", "max_error", "ticks", "scored_ticks", "faults")},
        "columns": cols,
        "decimation": 100,
        "rows_sha256": hashlib.sha256(np.ascontiguousarray(rows).tobytes()).hexdigest(),
        "stats": {
            c: {
                "mean": float(rows[:, i].mean()),
                "std": float(rows[:, i].std()),
                "min": float(rows[:, i].min()),
                "max": float(rows[:, i].max()),
            }
            for i, c in enumerate(cols)
        },
        "decimated": {c: [float(v) for v in dec[:, i]] for i, c in enumerate(cols)},
    }
    print(name, out[name]["summary"])
out["captured_from"] = (
    "commit 4df3193 (before the edge runtime v2 redesign): pmactl edge run --config docs/examples/hil-rig.toml "
    "--bundle tests/data/edge_golden/bundle --duration 25 --settle 5 (feedforward on / --no-feedforward)"
)
(root / "golden_25s.json").write_text(json.dumps(out, separators=(",", ":")))
