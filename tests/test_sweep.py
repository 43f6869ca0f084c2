"""pmactl sweep on the local pool: real pmactl subprocesses, small matrices (a few CPU-seconds each).

Helpers here are shared with tests/test_sweep_ray.py.
"""

from __future__ import annotations

import csv
import json
import os
import socket
import subprocess
import sys
import time
import tomllib
from pathlib import Path

import pytest

from host.cli import main
from host.sweep.backends import LocalBackend
from host.sweep.engine import SweepResult, run_sweep
from host.sweep.matrix import load_matrix
from host.sweep.presets import Resources
from host.sweep.report import comparable

# record 5 s on the emulated rig, then fit on it and score on it: ~0.7 s of CPU per cell
RECORD_AND_FIT = """
kind = "fit"
timeout_s = 120
retries = 1
{extra_top}

[axes]
model = {models}
seed = "{seeds}"

{extra_steps}

[[steps]]
name = "record"
args = ["hil", "record", "--scenario", "triangles", "--seed", "{{seed}}", "--duration", "5", "--out", "rec.csv"]
json = "none"

[[steps]]
name = "fit"
args = ["fit", "--model", "{{model}}", "--train", "rec.csv", "--test", "rec.csv", "--json"]

[thresholds]
"fit.tests.0.rmse_pct_pp" = {{ max = {limit} }}
"""


def record_and_fit(
    path: Path,
    models: str = '["pi"]',
    seeds: str = "1..2",
    limit: float = 5.0,
    extra_top: str = "",
    extra_steps: str = "",
) -> Path:
    path.write_text(
        RECORD_AND_FIT.format(models=models, seeds=seeds, limit=limit, extra_top=extra_top, extra_steps=extra_steps)
    )
    return path


def local_sweep(matrix: Path, out: Path, workers: int) -> SweepResult:
    """The sweep in this process on the local pool (closed afterwards: no threads left)."""
    backend = LocalBackend(workers, Resources())
    try:
        return run_sweep(load_matrix(matrix), out, backend)
    finally:
        backend.close()


def read_rows(out: Path) -> list[dict[str, str]]:
    with open(out / "results.csv", newline="") as f:
        return list(csv.DictReader(f))


def comparable_rows(matrix_path: Path, out: Path) -> list[dict[str, str]]:
    """The table without timing and placement columns, in cell order."""
    timing = load_matrix(matrix_path).timing_columns
    return [comparable(row, timing) for row in sorted(read_rows(out), key=lambda r: int(r["index"]))]


def sweep_process(*args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "host.cli", "sweep", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def processes_working_in(folder: Path) -> list[int]:
    """PIDs whose working directory is inside ``folder`` (cells still running there)."""
    found = []
    root = str(folder.resolve())
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            cwd = os.readlink(f"/proc/{entry}/cwd")
        except OSError:
            continue
        if cwd.startswith(root):
            found.append(int(entry))
    return found


def wait_until(predicate, timeout_s: float, what: str) -> None:  # noqa: ANN001
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout_s} s waiting for {what}")


# ---------------------------------------------------------------------------------------------
# the matrix: bad input is one line, exit 2


def write(path: Path, text: str) -> Path:
    path.write_text(text)
    return path


@pytest.mark.parametrize(
    "text, message",
    [
        ('kind = "fit"\n[axes]\nmodel = ["pi"]\n[valuez]\n', "unknown key 'valuez'; did you mean 'values'?"),
        ('kind = "fitt"\n[axes]\nmodel = ["pi"]\n', "kind = 'fitt'; use one of"),
        ('kind = "fit"\n[axes]\n', "[axes] is empty"),
        ('kind = "fit"\n[axes]\nseed = "5..1"\n', "is empty; write the smaller number first"),
        (
            'kind = "fit"\n[axes]\nmodel = ["pi"]\n[[steps]]\nargs = ["fit", "--model", "{modle}"]\n',
            "{modle} has no value",
        ),
        ('kind = "hil-run"\n[axes]\ncontroller = ["pid", "lqr"]\n[values]\nbundle = "b"\n', "'lqr' is not one of"),
        ('kind = "train"\n[axes]\nseed = "1..2"\n', "has no default command"),
        (
            'kind = "fit"\n[axes]\nmodel = ["pi"]\n[thresholds]\n"fit.x" = { max = 1, where = { effect = "a" } }\n',
            "where must name axes",
        ),
        ('kind = "fit"\n[axes]\nstatus = [1]\n', "are result columns"),
        ('kind = "fit"\naxes = [', "not valid TOML"),
    ],
)
def test_a_bad_matrix_is_one_line_and_exit_2(tmp_path, capsys, text, message):
    matrix = write(tmp_path / "m.sweep.toml", text)
    assert main(["sweep", str(matrix), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0] and str(matrix) in err[0]
    assert not (tmp_path / "out").exists()  # nothing written for a matrix that cannot run


def test_missing_ray_names_the_extra(tmp_path):
    """With ray unimportable, --ray is one line naming pmactl[cluster] (the SBC never needs ray)."""
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..1")
    blocker = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] == 'ray':\n"
        "            raise ModuleNotFoundError(f'No module named {name!r}', name=name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "from host.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", blocker, "sweep", str(matrix), "--ray", "local"], capture_output=True, text=True
    )
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "pmactl sweep: error: --ray needs the cluster extra (ray is not installed); "
        "install it with: pip install 'pmactl[cluster]'"
    ]


def test_an_axis_fills_a_toml_key_and_keeps_the_rest_of_the_file():
    from host.sweep.matrix import builtin_values
    from host.sweep.template import set_toml_key

    source = Path(str(builtin_values(Path("."))["hil_config"])).read_text()
    url = "sim://rig?adc=ADS1015&clock=lockstep&effect=creep&seed=7"
    edited = set_toml_key(source, "buses.i2c.url", url, "test")
    assert tomllib.loads(edited)["buses"]["i2c"]["url"] == url
    before, after = tomllib.loads(source), tomllib.loads(edited)
    before["buses"]["i2c"].pop("url"), after["buses"]["i2c"].pop("url")
    assert before == after
    assert len(source.splitlines()) == len(edited.splitlines())
    changed = [b for a, b in zip(source.splitlines(), edited.splitlines()) if a != b]
    assert len(changed) == 1 and "sim://rig" in changed[0]  # comments and layout untouched
    added = set_toml_key(source, "faults.nack_burst_at_s", 3.5, "test")  # a section that does not exist yet
    assert tomllib.loads(added)["faults"] == {"nack_burst_at_s": 3.5}


def test_list_prints_every_cell_with_its_own_seed_and_commands(tmp_path, capsys):
    matrix = write(
        tmp_path / "m.sweep.toml",
        'kind = "hil-run"\n[axes]\neffect = ["none", "creep"]\ncontroller = ["pid", "pid+ff"]\n[paths]\nbundle = "b"\n',
    )
    assert main(["sweep", str(matrix), "--list"]) == 0
    out = capsys.readouterr().out
    assert "4 cells of kind hil-run" in out
    assert out.count("--no-feedforward --no-correction") == 2 and out.count("pmactl edge run") == 4
    cells = load_matrix(matrix).cells
    assert len({c.seed for c in cells}) == 4  # no seed axis: each cell its own seed, from its labels
    assert [c.seed for c in cells] == [c.seed for c in load_matrix(matrix).cells]  # ... reproducibly
    assert all(f"--bundle {tmp_path / 'b'}" in out for _ in cells)  # [paths] relative to the matrix file


# ---------------------------------------------------------------------------------------------
# running cells on the local pool


def test_a_small_matrix_gives_one_row_per_cell_with_pass_fail(tmp_path):
    matrix = record_and_fit(tmp_path / "m.sweep.toml", models='["pi", "preisach"]', seeds="1..1", limit=0.5)
    out = tmp_path / "out"
    done = sweep_process(str(matrix), "--out", str(out), "--json")
    stdout, stderr = done.communicate(timeout=120)
    assert done.returncode == 1, stderr  # pi misses the 0.5 % limit: the sweep reports failure
    summary = json.loads(stdout)
    assert (summary["cells"], summary["pass"], summary["fail"], summary["error"]) == (2, 1, 1, 0)
    assert stderr == ""  # --json: no progress bar
    rows = read_rows(out)
    assert [r["model"] for r in rows] == ["pi", "preisach"]
    pi, preisach = rows
    assert pi["status"] == "fail" and "fit.tests.0.rmse_pct_pp=" in pi["reasons"] and "> 0.5" in pi["reasons"]
    assert preisach["status"] == "pass"
    assert float(preisach["fit.tests.0.rmse_pct_pp"]) < float(pi["fit.tests.0.rmse_pct_pp"])
    summary_md = (out / "summary.md").read_text()
    assert "**1 pass, 1 fail, 0 error**" in summary_md and "| model | pi | 1 | 0 | 1 | 0 |" in summary_md


# a cell that prints one metric from Python: a cell in well under a CPU-second
ECHO = """
kind = "fit"
timeout_s = {timeout}
retries = 1
{extra_top}

[axes]
n = {ns}

{before}
[[steps]]
name = "echo"
program = true
args = ["{{python}}", "-c", "import json; print(json.dumps(dict(n={{n}})))"]
"""


def echo_matrix(path: Path, ns: str = "[1, 2]", timeout: float = 120, extra_top: str = "", before: str = "") -> Path:
    path.write_text(ECHO.format(ns=ns, timeout=timeout, extra_top=extra_top, before=before))
    return path


def test_a_cell_killed_by_a_signal_is_retried(tmp_path):
    """Attempt 1 of every cell dies from SIGKILL (as under the OOM killer); attempt 2 finishes.

    The timeout is far above what a cell needs on any machine: only the signal can end attempt 1.
    """
    crash_once = (
        '[[before]]\nname = "crash"\nprogram = true\njson = "none"\n'
        'args = ["{python}", "-c", "import os, sys; '
        'os.kill(os.getpid(), 9) if sys.argv[1] == \'1\' else None", "{attempt}"]\n'
    )
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..1", extra_steps=crash_once)
    result = local_sweep(matrix, tmp_path / "out", 1)
    [row] = result.rows
    assert (row["status"], row["attempts"], result.retried) == ("pass", 2, 1)
    journal = [json.loads(line) for line in (tmp_path / "out" / "cells.jsonl").read_text().splitlines()]
    [first_try] = [r for r in journal if not r["final"]]
    assert first_try["error_kind"] == "signal" and "SIGKILL" in first_try["error"]


def test_a_hung_cell_times_out_and_its_processes_are_killed(tmp_path):
    """A cell that never ends: each attempt is stopped at the timeout, the cell is an error, nothing is left."""
    hang = (
        '[[before]]\nname = "hang"\nprogram = true\njson = "none"\n'
        'args = ["{python}", "-c", "import subprocess, sys, time; '
        "subprocess.Popen([sys.executable, '-c', 'import time; time.sleep(600)']); time.sleep(600)\"]\n"
    )
    matrix = echo_matrix(tmp_path / "m.sweep.toml", ns="[1]", timeout=1, before=hang)
    result = local_sweep(matrix, tmp_path / "out", 1)
    [row] = result.rows
    assert row["status"] == "error" and "timeout" in row["reasons"] and row["attempts"] == 2
    assert row["elapsed_s"] >= 1.0  # stopped no earlier than the limit (how much later depends on the load)
    journal = [json.loads(line) for line in (tmp_path / "out" / "cells.jsonl").read_text().splitlines()]
    assert [r["error_kind"] for r in journal] == ["timeout", "timeout"]
    assert processes_working_in(tmp_path / "out") == []  # the step and its child: the process group was killed


def test_changed_thresholds_rescore_without_running_again(tmp_path):
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..1", limit=5.0)
    out = tmp_path / "out"
    first = local_sweep(matrix, out, 1)
    assert (first.ran, first.rows[0]["status"]) == (1, "pass")
    matrix.write_text(matrix.read_text().replace("max = 5.0", "max = 0.01"))
    second = local_sweep(matrix, out, 1)
    assert (second.ran, second.resumed, second.rows[0]["status"]) == (0, 1, "fail")


def test_a_second_sweep_on_the_same_folder_is_refused(tmp_path, capsys):
    from host.sweep.journal import Journal

    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..1")
    with Journal(tmp_path / "out"):
        assert main(["sweep", str(matrix), "--out", str(tmp_path / "out")]) == 2
    assert "another pmactl sweep is writing here" in capsys.readouterr().err


def test_a_folder_that_holds_no_sweep_is_refused_and_left_as_it_was(tmp_path, capsys):
    matrix = echo_matrix(tmp_path / "m.sweep.toml")
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.md").write_text("my notes\n")
    assert main(["sweep", str(matrix), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "holds no sweep" in err and "choose a new or empty --out" in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in out.iterdir()) == ["summary.md"]
    assert (out / "summary.md").read_text() == "my notes\n"


@pytest.mark.parametrize(
    "edit",
    [
        lambda t: t.replace("n = [1, 2]", "n = [1, 3]"),  # other axes
        lambda t: t.replace('name = "echo"', 'name = "echo2"'),  # other steps
        lambda t: t.replace('kind = "fit"', 'kind = "diagnose"'),  # another kind
    ],
    ids=["axes", "steps", "kind"],
)
def test_another_matrix_in_a_sweep_folder_is_refused_and_the_results_kept(tmp_path, capsys, edit):
    first = echo_matrix(tmp_path / "a.sweep.toml")
    out = tmp_path / "out"
    assert local_sweep(first, out, 1).counts()["pass"] == 2
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    second = tmp_path / "b.sweep.toml"
    second.write_text(edit(first.read_text()))
    assert main(["sweep", str(second), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "holds the results of another matrix" in err and "use another --out" in err
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


def test_the_same_matrix_with_other_thresholds_may_use_the_folder_again(tmp_path):
    first = echo_matrix(tmp_path / "a.sweep.toml")
    out = tmp_path / "out"
    assert local_sweep(first, out, 1).counts()["pass"] == 2
    second = tmp_path / "b.sweep.toml"
    second.write_text(first.read_text() + '\n[thresholds]\n"echo.n" = { max = 1 }\n')
    again = local_sweep(second, out, 1)
    assert (again.ran, again.resumed, again.counts()["fail"]) == (0, 2, 1)


def test_a_killed_sweep_resumes_without_rerunning_finished_cells(tmp_path):
    """SIGKILL mid-run (a crash or a reboot), then the same command: finished cells are kept."""
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..4")
    out = tmp_path / "out"
    first = sweep_process(str(matrix), "--out", str(out), "--workers", "1", "--json")
    journal = out / "cells.jsonl"
    wait_until(lambda: journal.exists() and journal.read_text().count("\n") >= 2, 120, "two finished cells")
    first.kill()
    first.communicate()
    wait_until(lambda: not processes_working_in(out), 60, "the orphaned cell to end")
    done_before = [json.loads(line)["key"] for line in journal.read_text().splitlines()]
    assert 2 <= len(done_before) < 4

    second = sweep_process(str(matrix), "--out", str(out), "--workers", "1", "--json")
    stdout, stderr = second.communicate(timeout=120)
    assert second.returncode == 0, stderr
    summary = json.loads(stdout)
    assert (summary["pass"], summary["resumed"], summary["ran"]) == (4, len(done_before), 4 - len(done_before))
    keys = [json.loads(line)["key"] for line in journal.read_text().splitlines()]
    assert sorted(keys) == sorted(set(keys)) and len(keys) == 4  # each cell ran to completion once
    for key in done_before:
        assert [p.name for p in (out / "cells" / key).iterdir()] == ["attempt-1"]


def test_sigterm_stops_the_running_cells_and_the_next_run_finishes(tmp_path):
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..4")
    out = tmp_path / "out"
    first = sweep_process(str(matrix), "--out", str(out), "--workers", "1")
    journal = out / "cells.jsonl"
    wait_until(lambda: journal.exists() and journal.read_text().count("\n") >= 1, 120, "a finished cell")
    first.terminate()
    _, stderr = first.communicate(timeout=60)
    assert first.returncode == 130
    assert "interrupted" in stderr and "run the same command to resume" in stderr and "Traceback" not in stderr
    assert processes_working_in(out) == []  # the running cell was stopped, not left behind
    assert len(read_rows(out)) == journal.read_text().count("\n") < 4  # the table holds what finished
    second = local_sweep(matrix, out, 1)
    assert len(second.rows) == 4 and second.ran + second.resumed == 4 and second.resumed >= 1


def test_hil_run_cells_fill_the_rig_config_from_their_axes(tmp_path):
    """The preset's sim:// template: each cell's rig runs its own hidden effect and seed."""
    matrix = write(
        tmp_path / "m.sweep.toml",
        'kind = "hil-run"\n[axes]\neffect = ["none", "transport_delay"]\n'
        '[values]\nduration = 8\nsettle = 2\nbundle = "bundle"\n'
        '[[before]]\nname = "fit"\n'
        'args = ["fit", "--model", "preisach", "--train", "{example_train}", "--units", "bar,mm", "--save", "bundle"]\n'
        'json = "none"\n',
    )
    result = local_sweep(matrix, tmp_path / "out", 2)
    rows = {r["effect"]: r for r in result.rows}
    for effect, row in rows.items():
        config = tomllib.loads((tmp_path / "out" / "cells" / row["cell"] / "attempt-1" / "rig.toml").read_text())
        assert f"effect={effect}&seed={row['seed']}" in config["buses"]["i2c"]["url"]
        assert row["run.ticks"] > 0 and row["run.feedforward"] is True
    # a dead time in the loop costs tracking (or trips the tracking-error fault)
    delayed = rows["transport_delay"]
    assert delayed["run.faults.n"] > 0 or delayed["run.rms_error"] > rows["none"]["run.rms_error"]


def test_an_unreachable_ray_address_is_one_line_not_a_hang(tmp_path):
    """ray.init retries a dead head node for minutes; the sweep asks first and names the fix."""
    pytest.importorskip("ray", reason="ray not installed (pip install 'pmactl[cluster]')")
    matrix = record_and_fit(tmp_path / "m.sweep.toml", seeds="1..1")
    with socket.socket() as closed:  # a port nothing listens on
        closed.bind(("127.0.0.1", 0))
        port = closed.getsockname()[1]
    done = subprocess.run(
        [sys.executable, "-m", "host.cli", "sweep", str(matrix), "--ray", f"127.0.0.1:{port}"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2
    (line,) = done.stderr.strip().splitlines()
    assert "nothing answers there" in line and "--ray local" in line


def test_a_spliced_list_fills_its_own_placeholders(tmp_path, capsys):
    """extra = ["--operators", "{operators}"]: the preset's "{extra}" argument takes the axis value."""
    matrix = write(
        tmp_path / "m.sweep.toml",
        'kind = "fit"\n[axes]\noperators = [8, 25]\n[values]\nextra = ["--operators", "{operators}"]\n',
    )
    assert main(["sweep", str(matrix), "--list"]) == 0
    out = capsys.readouterr().out
    assert "--operators 8 --json" in out and "--operators 25 --json" in out
