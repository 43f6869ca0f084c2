"""The forward twin and online adaptation on the emulated rig (issue 30): two tables.

Usage: nice -n 10 python bench/adapt_bench.py [--quick]

1. **Twin watch**: the example bundle (``pmactl fit --model preisach`` on the shipped
   ``pma_triangles.csv``) runs a 10-50 mm sine at 0.2 Hz with the default ``[safety]`` twin
   settings (warning when the residual's RMS over 2 s passes 6 % of the bundle's span). The
   matching muscle runs long, on two references, then on a hold, a 1 Hz ramp-sine, a
   rate-dependent muscle and the session-shifted one of table 2, to count false warnings; a bundle fitted to
   another plant (the same muscle with 7.5 kg instead of 3.5 kg), a leak and a position sensor
   that slips off the muscle (``hil.faults``, from t = 20 s) must be warned about: the table
   gives the seconds from the onset to the warning.
2. **Adaptation**: the HIL muscle of another session (``effect=session_shift``, sized on the
   real 18-03 vs 31-03 campaigns, :mod:`hil.effects`) tracked with and without ``[adapt]``
   (default settings), for feedforward alone, a soft PID and the default PID; the unshifted
   muscle as a control. Tracking RMS after a 10 s settle, and the ratio with/without.

Every run is in lockstep (simulated clock); wall and CPU seconds of each row are printed.
"""

from __future__ import annotations

import sys
import tempfile
import time
import tomllib
from dataclasses import replace
from pathlib import Path

from edge.control.reference import parse_reference
from edge.runtime.bundle import load_bundle
from edge.runtime.config import RigConfig, config_from_dict
from edge.runtime.run import EdgeRuntime
from hil.plant import PlantParams, Schedule
from hil.record import record, write_recording
from host.data import load_measurement
from host.examples import example_path
from host.workflow import make_estimator, save_bundle

SINE = "sine:amplitude=20,frequency=0.2,offset=30"
FAST_SINE = "sine:amplitude=20,frequency=0.5,offset=30"
RAMP_SINE = "ramp-sine:peak=20,frequency=1,offset=30,rise=20,hold=10"
ONSET_S = 20.0
GAINS = {
    "feedforward alone": {"kp_bar_per_mm": 0.0, "ki_bar_per_mm_s": 0.0},
    "soft PID (0.01, 0.05)": {"kp_bar_per_mm": 0.01, "ki_bar_per_mm_s": 0.05},
    "default PID (0.05, 0.5)": {},
}


def fit_on(train_csv: Path, directory: Path) -> Path:
    train = load_measurement(train_csv)
    estimator = make_estimator("preisach").fit(train.u, train.y)
    return save_bundle(estimator, train, directory, ("bar", "mm"), {"model": "preisach"})


HIL_RIG = Path(__file__).resolve().parents[1] / "docs" / "examples" / "hil-rig.toml"


def config(url_options: str = "", **sections: dict) -> RigConfig:
    """The example HIL rig with ``url_options`` on its sim:// URL and ``sections`` merged in."""
    raw = tomllib.loads(HIL_RIG.read_text())
    raw["buses"]["i2c"]["url"] = "sim://rig?clock=lockstep" + url_options
    for name, values in sections.items():
        raw.setdefault(name, {}).update(values)
    return config_from_dict(raw, str(HIL_RIG))


def run(
    bundle: Path, cfg: RigConfig, reference: str, duration_s: float, settle_s: float = 10.0
) -> tuple[dict, float, float]:
    wall, cpu = time.perf_counter(), time.process_time()
    edge = EdgeRuntime(cfg, load_bundle(bundle), parse_reference(reference), settle_s=settle_s)
    summary = edge.run(duration_s).as_dict()
    return summary, time.perf_counter() - wall, time.process_time() - cpu


def twin_warnings(summary: dict) -> list[str]:
    return [w for w in summary["warnings"] if "forward twin" in w]


def twin_table(example: Path, other: Path, long_s: float) -> None:
    print("\n## 1. Twin watch (warning: residual RMS over 2 s > 6 % of the bundle's span)\n")
    print("| case | run [s] | twin warnings | worst 2 s RMS [mm] | onset -> warning [s] | wall [s] | CPU [s] |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    cases = [
        ("matching bundle, 0.2 Hz sine", example, config(), SINE, long_s, None),
        ("matching bundle, 0.5 Hz sine", example, config(), FAST_SINE, long_s, None),
        ("matching bundle, hold at 30 mm", example, config(), "const:value=30", 60.0, None),
        ("matching bundle, 1 Hz ramp-sine", example, config(), RAMP_SINE, 50.0, None),
        ("matching bundle, rate-dependent muscle", example, config("&effect=rate_dependence"), SINE, 60.0, None),
        ("matching bundle, session-shifted muscle", example, config("&effect=session_shift"), SINE, 60.0, None),
        ("bundle of another plant (7.5 kg)", other, config(), SINE, 40.0, 0.0),
        ("leak (muscle keeps 80 %)", example, config(f"&faults=leak@{ONSET_S:g}"), SINE, 40.0, ONSET_S),
        (
            "leak, with [adapt] on",
            example,
            config(f"&faults=leak@{ONSET_S:g}", adapt={"enabled": True}),
            SINE,
            40.0,
            ONSET_S,
        ),
        ("position sensor detached", example, config(f"&faults=sensor_detached@{ONSET_S:g}"), SINE, 40.0, ONSET_S),
    ]
    for name, bundle, cfg, reference, duration, onset in cases:
        summary, wall, cpu = run(bundle, cfg, reference, duration, settle_s=0.0)
        warned = twin_warnings(summary)
        first = summary.get("twin_warning_t")
        delay = (
            f"{first - onset:.2f}" if (onset is not None and first is not None) else ("-" if onset is None else "none")
        )
        print(
            f"| {name} | {duration:g} | {len(warned)} | {summary.get('twin_rms_max_mm', float('nan')):.2f} | {delay} "
            f"| {wall:.1f} | {cpu:.1f} |"
        )


def adapt_table(example: Path, duration_s: float) -> None:
    print("\n## 2. Adaptation on the muscle of another session (tracking RMS after 10 s, mm)\n")
    print(
        "| control | plant | reference | without [adapt] | with [adapt] | ratio | a [mm], b at the end "
        "| wall [s] | CPU [s] |"
    )
    print("|---|---|---|---:|---:|---:|---|---:|---:|")
    for label, gains in GAINS.items():
        for effect, reference in (("session_shift", SINE), ("session_shift", FAST_SINE), ("none", SINE)):
            rms, wall, cpu, end = {}, 0.0, 0.0, ""
            for enabled in (False, True):
                cfg = config(f"&effect={effect}", control=gains, adapt={"enabled": enabled})
                summary, w, c = run(example, cfg, reference, duration_s)
                rms[enabled], wall, cpu = summary["rms_error"], wall + w, cpu + c
                if enabled:
                    end = f"{summary['adapt']['offset_mm']:+.2f}, {summary['adapt']['gain']:.3f}"
            hz = reference.split("frequency=")[1].split(",")[0]
            print(
                f"| {label} | {effect} | {hz} Hz | {rms[False]:.3f} | {rms[True]:.3f} | {rms[True] / rms[False]:.2f} "
                f"| {end} | {wall:.1f} | {cpu:.1f} |"
            )


def main() -> None:
    quick = "--quick" in sys.argv
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        example = fit_on(example_path("train"), work / "example")
        heavy = replace(PlantParams(), load=Schedule((0.0,), (7.5,)))
        other_csv = write_recording(record("triangles", 1, 80.0, params=heavy), work / "heavy.csv")
        other = fit_on(other_csv, work / "other")
        twin_table(example, other, 60.0 if quick else 300.0)
        adapt_table(example, 30.0 if quick else 60.0)


if __name__ == "__main__":
    main()
