"""The pmactl command line, run as a user runs it (real processes where it matters)."""

from __future__ import annotations

import json
import subprocess
import sys

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
    assert set(report) == {"model", "fit_seconds", "tests"}
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


def test_demo_runs_the_whole_path(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    models = {row["model"]: row for row in report["models"]}
    assert set(models) == {"pi", "mpi", "dpi", "preisach"}
    for row in models.values():
        assert row["table_vs_reference_mm"] < 1e-9
        assert row["inverse_round_trip_bar"] < 1e-6
    assert models["preisach"]["rmse_pct_pp"] < 3.0  # the shipped muscle data is well inside reach
    assert models["mpi"]["rmse_pct_pp"] < models["pi"]["rmse_pct_pp"]
    pid, with_ff = report["closed_loop"]
    assert pid["faults"] == [] == with_ff["faults"] and with_ff["rms_error"] <= 0.5 * pid["rms_error"]
