"""Try bad inputs as a new user would and count how pmactl answers them.

Usage: python bench/bad_inputs.py [--show]

Every case runs ``pmactl`` as a separate process (``python -m host.cli``) in a scratch
directory. A case that should be refused passes when it exits with status 2 and exactly one
line on stderr (warnings apart)
and no traceback; a case that should be accepted (a UTF-8 BOM, quoted numbers, semicolons: the
delimiter is sniffed) passes when it exits 0. The table prints each case's outcome, then the counts:
one-line errors, tracebacks, other refusals (exit 2 but several lines), silent accepts of bad
input, internal errors (one line that reports a pmactl bug), hangs (over the time limit).
``--show`` also prints each case's stderr.
"""

from __future__ import annotations

import os
import socket
import stat
import subprocess
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

TIME_LIMIT_S = 60.0


@dataclass
class Case:
    name: str
    args: list[str]
    expect: str = "error"  # "error" (one line, exit 2) or "ok" (exit 0)


def write_csv(path: Path, header: str, rows: list[str], prefix: bytes = b"") -> str:
    path.write_bytes(prefix + (header + "\n" + "\n".join(rows) + "\n").encode())
    return str(path)


def triangle_rows(n: int = 400, dt: float = 0.01, fmt: str = "{t:.4f},{u:.5f},{y:.5f}") -> list[str]:
    t = np.arange(n) * dt
    u = 2.0 + 2.0 * np.abs(((t / 2.0) % 2.0) - 1.0) * np.sign(np.sin(0.3 * t) + 2)
    y = 10 * np.tanh(u / 2) + 0.3 * np.sin(np.arange(n) / 7)
    return [fmt.format(t=a, u=b, y=c) for a, b, c in zip(t, u, y)]


def build_cases(root: Path) -> list[Case]:
    good = triangle_rows()
    csv = {
        "good": write_csv(root / "good.csv", "t,u,y", good),
        "bom": write_csv(root / "bom.csv", "t,u,y", good, prefix=b"\xef\xbb\xbf"),
        "quoted": write_csv(root / "quoted.csv", '"t","u","y"', ['"' + r.replace(",", '","') + '"' for r in good]),
        "short_row": write_csv(root / "short.csv", "t,u,y", good[:50] + ["0.5,1.0"] + good[51:]),
        "long_row": write_csv(root / "long.csv", "t,u,y", good[:50] + [good[50] + ",7"] + good[51:]),
        "duplicate_column": write_csv(root / "dup.csv", "t,u,y,y", [r + ",0" for r in good]),
        "huge_values": write_csv(
            root / "huge.csv",
            "t,u,y",
            [r.rsplit(",", 1)[0] + ",1e300" for r in good[:1]]
            + [f"{r.rsplit(',', 1)[0]},{1e300 * (1 + i % 3)}" for i, r in enumerate(good[1:])],
        ),
        "gap_1000s": write_csv(
            root / "gap.csv",
            "t,u,y",
            [f"{i * 1e-4:.4f},{np.sin(i / 30):.4f},{np.sin(i / 30 - 0.2):.4f}" for i in range(2000)]
            + [f"{1000 + i * 1e-4:.4f},{np.sin(i / 30):.4f},{np.sin(i / 30 - 0.2):.4f}" for i in range(2000)],
        ),
        "constant_output": write_csv(root / "const.csv", "t,u,y", [r.rsplit(",", 1)[0] + ",5.0" for r in good]),
        "text_cells": write_csv(root / "text.csv", "t,u,y", good[:10] + ["0.1,abc,1"] + good[11:]),
        "semicolons": write_csv(root / "semi.csv", "t;u;y", [r.replace(",", ";") for r in good]),
        "empty": write_csv(root / "empty.csv", "", []),
    }
    (root / "binary.csv").write_bytes(bytes(range(256)) * 20)
    # a directory nobody may write into, root included (chmod does not stop root)
    readonly = Path("/sys") if os.geteuid() == 0 else root / "readonly"
    if readonly != Path("/sys"):
        readonly.mkdir()
        os.chmod(readonly, stat.S_IRUSR | stat.S_IXUSR)
    fit = ["fit", "--model", "pi", "--train"]
    cases = [
        Case(f"csv {name}", [*fit, path], "ok" if name in {"good", "bom", "quoted", "semicolons"} else "error")
        for name, path in csv.items()
    ]
    cases += [
        Case("csv missing file", [*fit, str(root / "absent.csv")]),
        Case("csv is a directory", [*fit, str(root)]),
        Case("csv binary", [*fit, str(root / "binary.csv")]),
        Case("test csv broken", [*fit, csv["good"], "--test", csv["short_row"]]),
        Case("--operators 0", [*fit, csv["good"], "--operators", "0"]),
        Case("--operators -3", [*fit, csv["good"], "--operators", "-3"]),
        Case("--operators 100000", [*fit, csv["good"], "--operators", "100000"]),
        Case(
            "preisach --operators 100000",
            ["fit", "--model", "preisach", "--train", csv["good"], "--operators", "100000"],
        ),
        Case("--operators abc", [*fit, csv["good"], "--operators", "abc"]),
        Case("--calibration 5", [*fit, csv["good"], "--test", csv["good"], "--calibration", "5"]),
        Case("--units bar", [*fit, csv["good"], "--units", "bar"]),
        Case("--model foo", ["fit", "--model", "foo", "--train", csv["good"]]),
        Case("fit without --train", ["fit", "--model", "pi"]),
        Case("--save in missing dir", [*fit, csv["good"], "--save", str(root / "no" / "such" / "bundle")]),
        Case("--save in read-only dir", [*fit, csv["good"], "--save", str(readonly / "bundle")]),
        Case("--save onto a file", [*fit, csv["good"], "--save", csv["good"]]),
        Case(
            "hil record --rate 0",
            ["hil", "record", "--scenario", "sines", "--duration", "2", "--rate", "0", "--out", str(root / "r.csv")],
        ),
        Case(
            "hil record --rate -100",
            ["hil", "record", "--scenario", "sines", "--duration", "2", "--rate", "-100", "--out", str(root / "r.csv")],
        ),
        Case(
            "hil record --rate 333",
            ["hil", "record", "--scenario", "sines", "--duration", "2", "--rate", "333", "--out", str(root / "r.csv")],
        ),
        Case(
            "hil record --out missing dir",
            ["hil", "record", "--scenario", "sines", "--duration", "2", "--out", str(root / "no" / "r.csv")],
        ),
        Case(
            "hil record --out read-only",
            ["hil", "record", "--scenario", "sines", "--duration", "2", "--out", str(readonly / "r.csv")],
        ),
        Case("demo --out in missing dir", ["demo", "--out", str(root / "no" / "such" / "demo")]),
        Case("demo --out read-only", ["demo", "--out", str(readonly / "demo")]),
        Case("demo --out onto a file", ["demo", "--out", csv["good"]]),
        Case("unknown command", ["fitt"]),
        Case("no command", []),
    ]
    return cases + new_command_cases(root, csv, readonly)


RIG = str(Path(__file__).resolve().parents[1] / "docs" / "examples" / "hil-rig.toml")


def new_command_cases(root: Path, csv: dict[str, str], readonly: Path) -> list[Case]:
    """edge record / probe, simulate, diagnose and the data options (--columns, --time-unit, globs)."""
    own = {
        "negative": write_csv(root / "p_neg.csv", "t,pressure", ["0,0", "5,-2", "10,0"]),
        "huge": write_csv(root / "p_huge.csv", "t,pressure", ["0,0", "5,1e9", "10,0"]),
        "one_row": write_csv(root / "p_one.csv", "t,pressure", ["0,0"]),
        "nan": write_csv(root / "p_nan.csv", "t,pressure", ["0,0", "5,nan", "10,0"]),
        "unsorted": write_csv(root / "p_unsorted.csv", "t,pressure", ["0,0", "5,1", "3,0"]),
        "t_in_ms": write_csv(root / "p_longt.csv", "t,pressure", ["0,0", "1000000000,1"]),
        "no_header": write_csv(root / "p_nohead.csv", "0,0", ["1,1", "2,0"]),
    }
    (root / "p_dir.csv").mkdir()
    existing = write_csv(root / "existing.csv", "t,u,y", ["precious"])
    ms = write_csv(root / "ms.csv", "t,u,y", triangle_rows(fmt="{t:.0f},{u:.5f},{y:.5f}", dt=10.0))
    comma = write_csv(root / "comma.csv", "t;u;y", [r.replace(",", ";").replace(".", ",") for r in triangle_rows()])
    design_semi = write_csv(root / "design_semi.csv", "t;u", ["0;1", "0,01;2", "0,02;1"])
    huge_u = write_csv(root / "design_huge.csv", "t,u", ["0,1", "0.01,1e308", "0.02,1"])
    record = ["edge", "record", "--config", RIG, "--protocol"]

    def rec(name: str, protocol: str, *extra: str, expect: str = "error") -> Case:
        out = str(root / f"rec_{len(name)}_{abs(hash(name)) % 10**6}.csv")
        return Case(f"record {name}", [*record, protocol, "--out", out, *extra], expect)

    probe = ["edge", "probe", "--config", RIG]
    simulate = ["simulate", make_bundle(root, csv["good"])]  # a real bundle: a bad input cannot hide behind it
    cases = [
        rec("steps 1 s", "steps", "--duration", "1", expect="ok"),
        rec("protocol unknown", "foo"),
        rec("protocol csv negative", own["negative"]),
        rec("protocol csv huge", own["huge"]),
        rec("protocol csv one row", own["one_row"]),
        rec("protocol csv NaN", own["nan"]),
        rec("protocol csv unsorted t", own["unsorted"]),
        rec("protocol csv t 1e9 s", own["t_in_ms"]),
        rec("protocol csv no header", own["no_header"]),
        rec("protocol csv missing", str(root / "absent.csv")),
        rec("protocol csv is a dir", str(root / "p_dir.csv")),
        rec("protocol csv binary", str(root / "binary.csv")),
        rec("triangles:frequency=1e-9", "triangles:frequency=1e-9"),
        rec("forc:curves=1e7", "forc:curves=1e7"),
        rec("multisine:fmax=1e6", "multisine:fmax=1e6,period=1000"),
        rec("sines:frequencies=400 (alias)", "sines:frequencies=400"),
        rec("steps:levels=2.5", "steps:levels=2.5"),
        rec("steps:hold", "steps:hold"),
        rec("--duration 1e12", "steps", "--duration", "1e12"),
        rec("--duration -1", "steps", "--duration", "-1"),
        rec("--duration 0.0001 (one row)", "steps", "--duration", "0.0001"),
        rec("--duration nan", "steps", "--duration", "nan"),
        rec("--range 0:100", "steps", "--range", "0:100"),
        rec("--range 4:1", "steps", "--range", "4:1"),
        rec("--range nan:4", "steps", "--range", "nan:4"),
        rec("--range abc", "steps", "--range", "abc"),
        rec("--sample-hz 7", "steps", "--sample-hz", "7"),
        rec("--sample-hz 0", "steps", "--sample-hz", "0"),
        rec("--live 99999", "steps", "--live", "99999"),
        rec("--live abc", "steps", "--live", "abc"),
        rec("--live port taken", "steps", "--live", str(TAKEN_PORT)),
        Case("record --out missing dir", [*record, "steps", "--out", str(root / "no" / "r.csv")]),
        Case("record --out exists", [*record, "steps", "--out", existing]),
        Case("record --out is a dir", [*record, "steps", "--out", str(root)]),
        Case("record --out read-only", [*record, "steps", "--out", str(readonly / "r.csv")]),
        Case(
            "record --config missing",
            ["edge", "record", "--config", str(root / "no.toml"), "--protocol", "steps", "--out", str(root / "r1.csv")],
        ),
        Case(
            "record --config is a CSV",
            ["edge", "record", "--config", csv["good"], "--protocol", "steps", "--out", str(root / "r2.csv")],
        ),
        Case(
            "record --config is a dir",
            ["edge", "record", "--config", str(root), "--protocol", "steps", "--out", str(root / "r3.csv")],
        ),
        Case("probe 0.1 s", [*probe, "--duration", "0.1"], "ok"),
        Case("probe --rate 0", [*probe, "--rate", "0", "--duration", "0.1"]),
        Case("probe --rate 1e-9", [*probe, "--rate", "1e-9", "--duration", "0.1"]),
        Case("probe --rate 1e9", [*probe, "--rate", "1e9", "--duration", "0.1"]),
        Case("probe --duration -1", [*probe, "--duration", "-1"]),
        Case("probe --average 0", [*probe, "--calibrate", "pressure", "--average", "0"]),
        Case("probe --calibrate nope", [*probe, "--calibrate", "nope"]),
        Case("probe --calibrate valve", [*probe, "--calibrate", "valve"]),
        Case("simulate bundle not a bundle", ["simulate", str(root), csv["good"], "--out", str(root / "s1.csv")]),
        Case("simulate bundle missing", ["simulate", str(root / "nob"), csv["good"], "--out", str(root / "s2.csv")]),
        Case("simulate input binary", [*simulate, str(root / "binary.csv"), "--out", str(root / "s3.csv")]),
        Case("simulate input empty", [*simulate, csv["empty"], "--out", str(root / "s4.csv")]),
        Case("simulate input missing", [*simulate, str(root / "absent.csv"), "--out", str(root / "s5.csv")]),
        Case("simulate input ms time", [*simulate, ms, "--out", str(root / "s6.csv")]),
        Case("simulate input u 1e308", [*simulate, huge_u, "--out", str(root / "s7.csv")]),
        Case("simulate input text cell", [*simulate, csv["text_cells"], "--out", str(root / "s8.csv")]),
        Case("simulate --out exists", [*simulate, csv["good"], "--out", existing]),
        Case("simulate --out missing dir", [*simulate, csv["good"], "--out", str(root / "no" / "s.csv")]),
        Case("simulate --out is a dir", [*simulate, csv["good"], "--out", str(root)]),
        Case(
            "simulate --columns garbage",
            [*simulate, csv["good"], "--out", str(root / "s9.csv"), "--columns", "garbage"],
        ),
        Case("simulate ';' decimal-comma input", [*simulate, design_semi, "--out", str(root / "s10.csv")], "ok"),
        Case("fit --columns no such", [*FIT, csv["good"], "--columns", "t=t,u=u,y=nope"]),
        Case("fit --columns twice", [*FIT, csv["good"], "--columns", "t=t,u=u,y=y,y=u"]),
        Case("fit --time-unit h", [*FIT, csv["good"], "--time-unit", "h"]),
        Case("fit ms time column", [*FIT, ms]),
        Case("fit ms time --time-unit ms", [*FIT, ms, "--time-unit", "ms"], "ok"),
        Case("fit ';' decimal comma", [*FIT, comma], "ok"),
        Case("fit glob matches nothing", [*FIT, str(root / "nomatch*.csv")]),
        Case("diagnose glob matches nothing", ["diagnose", str(root / "nomatch*.csv")]),
        Case("diagnose binary", ["diagnose", str(root / "binary.csv")]),
        Case("diagnose missing", ["diagnose", str(root / "absent.csv")]),
        Case("diagnose directory", ["diagnose", str(root / "p_dir.csv")]),
        Case("diagnose --rules unknown field", ["diagnose", csv["good"], csv["good"], "--rules", "alpah=0.1"]),
        Case("diagnose --rules flag not a flag", ["diagnose", csv["good"], csv["good"], "--rules", "column_first=2"]),
        Case("diagnose --rules on v2", ["diagnose", csv["good"], "--rules", "alpha=0.01"]),
    ]
    return cases


FIT = ["fit", "--model", "pi", "--train"]


def make_bundle(root: Path, train: str) -> str:
    """A PI bundle fitted on ``train`` for the simulate cases."""
    bundle = root / "bundle"
    command = [sys.executable, "-m", "host.cli", *FIT, train, "--save", str(bundle)]
    subprocess.run(command, capture_output=True, check=True, timeout=TIME_LIMIT_S, cwd=root)
    return str(bundle)


TAKEN_PORT = 0  # set in main(): a port this script listens on while the cases run


def run_case(case: Case, cwd: Path) -> tuple[str, str]:
    try:
        result = subprocess.run(
            [sys.executable, "-m", "host.cli", *case.args],
            capture_output=True,
            text=True,
            timeout=TIME_LIMIT_S,
            cwd=cwd,
        )
    except subprocess.TimeoutExpired:
        return "hang", f"over {TIME_LIMIT_S:g} s"
    lines = [line for line in result.stderr.splitlines() if line.strip() and "warning:" not in line]
    if "Traceback" in result.stderr:
        return "traceback", result.stderr
    if "This is a pmactl bug" in result.stderr:  # one line, but an unforeseen exception, not the fix
        return "internal error", result.stderr
    if case.expect == "ok":
        return ("pass" if result.returncode == 0 else "refused good input"), result.stderr
    if result.returncode == 0:
        return "silently accepted", result.stderr
    if result.returncode == 2 and len(lines) == 1:
        return "one-line error", result.stderr
    return "unclear error", result.stderr


def main(argv: list[str]) -> int:
    show = "--show" in argv
    counts: dict[str, int] = {}
    global TAKEN_PORT
    taken = socket.socket()
    taken.bind(("127.0.0.1", 0))
    taken.listen()
    TAKEN_PORT = taken.getsockname()[1]
    with taken, tempfile.TemporaryDirectory(prefix="pmactl-bad-inputs-") as tmp:
        root = Path(tmp)
        cases = build_cases(root)
        print(f"{'case':<38} outcome")
        for case in cases:
            outcome, stderr = run_case(case, root)
            counts[outcome] = counts.get(outcome, 0) + 1
            print(f"{case.name:<38} {outcome}")
            if show and stderr.strip():
                print("    " + "\n    ".join(stderr.strip().splitlines()[-3:]))
        if (root / "readonly").exists():
            os.chmod(root / "readonly", stat.S_IRWXU)
    print()
    print(f"{len(cases)} cases: " + ", ".join(f"{n} {k}" for k, n in sorted(counts.items(), key=lambda kv: -kv[1])))
    good = counts.get("one-line error", 0) + counts.get("pass", 0)
    return 0 if good == len(cases) else 1


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
