"""The pmactl command line, run as a user runs it (real processes where it matters)."""

from __future__ import annotations

import argparse
import io
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from host.cli import main
from host.examples import example_path

TRAIN, TEST = str(example_path("train")), str(example_path("test"))


def run_pmactl(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "host.cli", *args], capture_output=True, text=True, timeout=300)


def test_help_lists_the_subcommands():
    result = run_pmactl("--help")
    assert result.returncode == 0
    assert "fit" in result.stdout and "demo" in result.stdout


def test_fit_json_has_the_documented_keys(capsys):
    assert main(["fit", "--model", "pi", "--train", TRAIN, "--test", TEST, "--test", TEST, "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert set(report) == {"model", "fit_seconds", "units", "warnings", "tests"}
    assert report["model"] == "pi" and report["fit_seconds"] > 0
    assert len(report["tests"]) == 2
    assert set(report["tests"][0]) == {"file", "rmse", "rmse_pct_pp", "max_error"}
    assert 0 < report["tests"][0]["rmse_pct_pp"] < 20


def test_fit_saves_a_bundle_the_edge_loads(tmp_path, capsys):
    from edge.runtime.bundle import load_bundle

    out = tmp_path / "bundle"
    assert main(["fit", "--model", "dpi", "--train", TRAIN, "--units", "bar,mm", "--save", str(out)]) == 0
    assert "bundle written" in capsys.readouterr().out
    bundle = load_bundle(out)
    assert bundle.manifest["model"]["kind"] == "dpi"
    assert bundle.manifest["fit"]["train"] == "pma_triangles.csv"


@pytest.mark.parametrize(
    "args, message",
    [
        (["fit", "--model", "pi", "--train", "missing.csv"], "missing.csv: cannot read file"),
        (["fit", "--model", "pi", "--train", TRAIN, "--units", "bar"], "--units"),
        (["fit", "--model", "dpi", "--train", TRAIN, "--parameterisation", "exponential"], "pi and mpi models only"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(args, message):
    result = run_pmactl(*args)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr


def test_constant_input_is_a_clear_error(tmp_path):
    path = tmp_path / "flat.csv"
    path.write_text("t,u,y\n" + "\n".join(f"{i / 100},1.0,{i}" for i in range(100)))
    result = run_pmactl("fit", "--model", "preisach", "--train", str(path))
    assert result.returncode == 2 and "constant" in result.stderr


def test_help_and_host_commands_on_an_edge_only_install():
    """With scipy and matplotlib absent, --help works and host commands name the extra."""
    blocker = (
        "import sys\n"
        "class Block:\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        "        if name.split('.')[0] in {'scipy', 'matplotlib'}:\n"
        "            raise ModuleNotFoundError(f'No module named {name!r}', name=name)\n"
        "sys.meta_path.insert(0, Block())\n"
        "from host.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    help_run = subprocess.run([sys.executable, "-c", blocker, "--help"], capture_output=True, text=True)
    assert help_run.returncode == 0 and "COMMAND" in help_run.stdout
    fit_run = subprocess.run(
        [sys.executable, "-c", blocker, "fit", "--model", "pi", "--train", TRAIN], capture_output=True, text=True
    )
    assert fit_run.returncode == 2
    assert "pip install 'pmactl[host]'" in fit_run.stderr and "Traceback" not in fit_run.stderr


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """One ``pmactl demo --json`` run (about 10 s) shared by the tests of what it reports."""
    out = tmp_path_factory.mktemp("demo") / "out"
    result = run_pmactl("demo", "--out", str(out), "--json")
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout, parse_constant=_not_json), result.stderr, out


def _not_json(name: str) -> None:
    raise AssertionError(f"pmactl demo --json wrote {name}, which is not JSON (non-finite numbers are null)")


def test_demo_lookup_tables_match_their_reference_models(demo):
    models = {row["model"]: row for row in demo[0]["models"]}
    assert set(models) == {"pi", "mpi", "dpi", "preisach"}
    assert all(row["table_vs_reference_mm"] < 1e-9 for row in models.values())


def test_demo_inverse_tables_undo_the_forward_tables(demo):
    """Every model's inverse table undoes its forward table to rounding. For DPI this holds
    because the fit bounds each digit's contraction/expansion slope ratio (max_asymmetry=10):
    unbounded, the shipped data gave ratios up to 630, the inverse amplified the forward's
    rounding by up to that factor per reversal and this test needed 1e-5 of the range
    (edge/hysteresis/dpi.py, host/identify/dpi.py). Now ~2e-12 bar, and at most 5e-11 bar for
    fits 1e-13 (relative) away, as another BLAS may produce.
    """
    for row in demo[0]["models"]:
        assert row["inverse_round_trip_bar"] < 1e-9, row


def test_demo_identifies_the_shipped_muscle_data(demo):
    models = {row["model"]: row for row in demo[0]["models"]}
    assert models["preisach"]["rmse_pct_pp"] < 3.0  # the shipped muscle data is well inside reach
    assert models["mpi"]["rmse_pct_pp"] < models["pi"]["rmse_pct_pp"]


def test_demo_feedforward_halves_the_tracking_error(demo):
    pid, with_ff, _ = demo[0]["closed_loop"]
    assert pid["faults"] == [] == with_ff["faults"] and with_ff["rms_error"] <= 0.5 * pid["rms_error"]


def test_demo_trained_correction_beats_feedforward_alone(demo):
    """The third row runs the bundle's trained correction (issue target: RMS <= 0.35x PID alone)."""
    pid, with_ff, with_nn = demo[0]["closed_loop"]
    assert with_nn["faults"] == [] and with_nn["rms_error"] <= 0.35 * pid["rms_error"]
    assert with_nn["rms_error"] < with_ff["rms_error"]


def test_demo_joint_feedforward_halves_the_angle_error(demo):
    """Schreiber's joint on the emulated rig: inverse-Preisach feedforward cuts RMS angle error >= 50 %."""
    pid, with_ff = demo[0]["joint"]
    assert pid["unit"] == "deg" and pid["faults"] == [] == with_ff["faults"]
    assert with_ff["rms_error"] <= 0.5 * pid["rms_error"]


def test_demo_writes_its_figures_and_bundles_into_out(demo):
    report, _, out = demo
    assert sorted(Path(f).name for f in report["figures"]) == ["joint.png", "loops.png", "tracking.png"]
    assert all(Path(f).stat().st_size > 10_000 and Path(f).parent == out for f in report["figures"])
    assert {p.name for p in out.iterdir()} >= {"pi", "mpi", "dpi", "preisach", "tracking-pid.pmt"}


def test_demo_warns_that_its_reference_leaves_the_bundles_reach(demo):
    report, stderr, _ = demo
    [warning] = report["warnings"]
    assert "reference asks 10.0..70.0 mm but the bundle reaches only" in warning
    assert warning in " ".join(stderr.split())


def test_demo_names_a_default_output_directory():
    from host.cli import build_parser

    args = build_parser().parse_args(["demo"])
    assert args.out == "pmactl-demo"


def test_version_is_printed():
    result = run_pmactl("--version")
    assert result.returncode == 0 and result.stdout.startswith("pmactl ")


def _options(parser: argparse.ArgumentParser, prefix: str = "pmactl"):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                yield from _options(child, f"{prefix} {name}")
        elif not isinstance(action, argparse._HelpAction):
            yield prefix, action


def test_every_option_has_help_text():
    from host.cli import build_parser

    missing = [f"{cmd} {'/'.join(a.option_strings) or a.dest}" for cmd, a in _options(build_parser()) if not a.help]
    assert missing == []


def test_operators_help_states_defaults_and_ranges():
    from host.cli import build_parser

    [operators] = [a for cmd, a in _options(build_parser()) if cmd == "pmactl fit" and a.dest == "operators"]
    assert "default 25" in operators.help and "range 1-100" in operators.help and "2-60" in operators.help


def one_line_error(result: subprocess.CompletedProcess[str], message: str) -> bool:
    lines = [line for line in result.stderr.strip().splitlines() if "warning:" not in line]
    return result.returncode == 2 and len(lines) == 1 and message in lines[0] and "Traceback" not in result.stderr


@pytest.mark.parametrize(
    "args, message",
    [
        (["fit", "--model", "pi", "--train", TRAIN, "--operators", "0"], "0 is outside 1-100"),
        (["fit", "--model", "pi", "--train", TRAIN, "--operators", "100000"], "100000 is outside 1-100"),
        (["fit", "--model", "preisach", "--train", TRAIN, "--operators", "80"], "80 is outside 2-60 for preisach"),
        (["fit", "--model", "foo", "--train", TRAIN], "invalid choice: 'foo'"),
        (["hil", "record", "--scenario", "sines", "--rate", "0", "--out", "x.csv"], "--rate: 0 Hz must be a positive"),
    ],
)
def test_bad_arguments_are_one_line(args, message):
    assert one_line_error(run_pmactl(*args), message)


def unwritable_dir(tmp_path: Path) -> Path:
    """A directory nobody can create files in: /sys for root (chmod does not stop root)."""
    if os.geteuid() == 0:
        return Path("/sys")
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    return locked


@pytest.mark.parametrize("kind", ["missing", "read-only", "a file"])
def test_fit_save_to_an_unwritable_place_is_one_line_before_fitting(tmp_path, kind):
    target = {
        "missing": tmp_path / "no" / "such" / "bundle",
        "read-only": unwritable_dir(tmp_path) / "bundle",
        "a file": Path(TRAIN),
    }[kind]
    expected = {"missing": "does not exist; create it", "read-only": "cannot write into", "a file": "is a file"}[kind]
    assert one_line_error(run_pmactl("fit", "--model", "pi", "--train", TRAIN, "--save", str(target)), expected)
    assert Path(TRAIN).stat().st_size > 100_000  # the user's file is untouched


def test_hil_record_out_in_a_missing_directory_is_one_line(tmp_path):
    result = run_pmactl("hil", "record", "--scenario", "sines", "--out", str(tmp_path / "no" / "r.csv"))
    assert one_line_error(result, "--out") and not (tmp_path / "no").exists()


def test_demo_out_in_a_read_only_place_is_one_line(tmp_path):
    assert one_line_error(run_pmactl("demo", "--out", str(unwritable_dir(tmp_path) / "demo")), "cannot write into")


def test_a_figure_format_matplotlib_cannot_write_is_named(tmp_path):
    from host.cli.outputs import OutputPathError, check_output

    with pytest.raises(OutputPathError, match=r"--plot .*x.xyz: cannot write the format '.xyz'; end the name in .png"):
        check_output(tmp_path / "x.xyz", "--plot", suffixes=(".png", ".pdf", ".svg"))


def test_an_unexpected_exception_is_one_line_naming_debug(monkeypatch, capsys):
    import host.cli.fit

    def broken(args):
        raise RuntimeError("the\nsky fell")

    monkeypatch.setattr(host.cli.fit, "run", broken)
    assert main(["fit", "--model", "pi", "--train", TRAIN]) == 2
    [line] = capsys.readouterr().err.strip().splitlines()
    assert "internal error RuntimeError: the sky fell" in line and "--debug" in line


def test_debug_shows_the_traceback(monkeypatch):
    import host.cli.fit

    def broken(args):
        raise RuntimeError("the sky fell")

    monkeypatch.setattr(host.cli.fit, "run", broken)
    with pytest.raises(RuntimeError, match="the sky fell"):
        main(["fit", "--model", "pi", "--train", TRAIN, "--debug"])


def test_an_os_error_names_the_file_and_the_fix(monkeypatch, capsys):
    import host.cli.fit

    def broken(args):
        raise PermissionError(13, "Permission denied", "/rig/out.csv")

    monkeypatch.setattr(host.cli.fit, "run", broken)
    assert main(["fit", "--model", "pi", "--train", TRAIN]) == 2
    assert "/rig/out.csv: Permission denied; check the permissions" in capsys.readouterr().err


def test_progress_is_off_for_json_and_when_stderr_is_not_a_terminal():
    from host.progress import wanted

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    assert wanted(False, Terminal()) and not wanted(True, Terminal()) and not wanted(False, io.StringIO())


def test_progress_names_each_step_on_stderr_and_stops_its_clock(capsys):
    from host.progress import Steps

    with Steps(2, True, "pmactl fit") as steps:
        steps.start("reading a.csv")
        steps.start("fitting on 10 samples")
    err = capsys.readouterr().err
    assert "reading a.csv" in err and "fitting on 10 samples" in err  # the leak guard checks the clock thread


@pytest.mark.parametrize(
    "option, target, message",
    [
        ("--plot", "x.xyz", "cannot write the format '.xyz'; end the name in .png"),
        ("--csv", "no/such/dir/run.csv", "does not exist; create it"),
    ],
)
def test_edge_telemetry_outputs_are_checked_before_reading(demo, tmp_path, option, target, message):
    telemetry = demo[2] / "tracking-pid.pmt"
    assert one_line_error(run_pmactl("edge", "telemetry", str(telemetry), option, str(tmp_path / target)), message)


def test_demo_refuses_a_folder_it_did_not_make(tmp_path):
    (tmp_path / "thesis.tex").write_text("mine")
    result = run_pmactl("demo", "--out", str(tmp_path), "--json")
    assert one_line_error(result, "holds files the demo did not write")
    assert [p.name for p in tmp_path.iterdir()] == ["thesis.tex"]


def test_demo_reuses_its_own_folder(demo):
    from host.cli.demo import DEMO_MARKER, demo_directory

    out = demo[2]
    assert (out / DEMO_MARKER).is_file() and demo_directory(str(out)) == out  # a second demo may write here


def test_edge_telemetry_export_never_overwrites_a_file(demo, tmp_path):
    """Not the recording itself (a reviewer replaced a run's telemetry with its CSV this way),
    not any other existing file."""
    telemetry = tmp_path / "run.pmt"
    telemetry.write_bytes((demo[2] / "tracking-pid.pmt").read_bytes())
    before = telemetry.read_bytes()
    notes = tmp_path / "notes.csv"
    notes.write_text("mine\n")
    for target in (telemetry, notes):
        result = run_pmactl("edge", "telemetry", str(telemetry), "--csv", str(target))
        assert one_line_error(result, "exists, and an export never overwrites a file")
    assert telemetry.read_bytes() == before and notes.read_text() == "mine\n"


def test_hil_record_shows_no_progress_in_a_pipe(tmp_path):
    result = run_pmactl("hil", "record", "--scenario", "sines", "--duration", "2", "--out", str(tmp_path / "r.csv"))
    assert result.returncode == 0 and result.stderr == "" and (tmp_path / "r.csv").exists()


def test_a_test_record_with_a_constant_output_is_warned_about(tmp_path):
    flat = tmp_path / "flat_y.csv"
    flat.write_text("t,u,y\n" + "\n".join(f"{i / 100},{2 + (i % 50) / 25},5.0" for i in range(400)))
    result = run_pmactl("fit", "--model", "pi", "--train", TRAIN, "--test", str(flat))
    assert result.returncode == 0 and "flat_y.csv: the output y is constant (5)" in result.stderr
