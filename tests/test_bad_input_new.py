"""Bad input to this session's new commands (edge record, edge probe): one line, exit 2, nothing
of the user's touched, and no huge allocation or endless wait before the refusal."""

from __future__ import annotations

from pathlib import Path

import pytest

from edge.control.protocols import build_protocol
from host.cli import main
from tests.edge_helpers import HIL_RIG


def one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(err) == 1, err
    assert "Traceback" not in err[0]
    return err[0]


@pytest.mark.parametrize(
    ("protocol", "extra", "message"),
    [
        ("triangles:frequency=1e-9", [], "one pass lasts 4e+09 s"),  # was a MemoryError "use fewer --operators"
        ("forc:curves=1e7", [], "one pass lasts"),
        ("steps", ["--duration", "1e12"], "--duration 1e+12: longer than"),
        ("sines:frequencies=400", [], "Nyquist rate 50 Hz"),  # was recorded, aliased, at 100 Hz
        ("chirp:f1=1e5", ["--duration", "1"], "Nyquist rate 50 Hz"),
        ("multisine:fmax=1e6,period=1000", [], "Nyquist rate"),  # was a hang
        ("multisine:fmax=20,period=1000", [], "fmax x period is too large"),
    ],
)
def test_oversized_or_aliased_protocol_is_refused_before_allocating(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], protocol: str, extra: list[str], message: str
) -> None:
    out = tmp_path / "run.csv"
    args = ["edge", "record", "--config", str(HIL_RIG), "--protocol", protocol, "--out", str(out), *extra]
    assert main(args) == 2
    assert message in one_line_error(capsys)
    assert not out.exists()


def test_protocol_csv_with_time_not_in_seconds_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    own = tmp_path / "own.csv"
    own.write_text("t,pressure\n0,0\n1e9,1\n")
    out = tmp_path / "run.csv"
    assert main(["edge", "record", "--config", str(HIL_RIG), "--protocol", str(own), "--out", str(out)]) == 2
    assert "is t in seconds?" in one_line_error(capsys)
    assert not out.exists()


def test_faster_sample_rate_allows_faster_sines() -> None:
    """The Nyquist check follows the recording's rate, not a constant."""
    with pytest.raises(ValueError, match="Nyquist"):
        build_protocol("sines:frequencies=10", 0.0, 4.0, 0.001, nyquist_hz=5.0)
    assert build_protocol("sines:frequencies=10", 0.0, 4.0, 0.001, nyquist_hz=50.0).values.max() > 3.9


def test_multisine_one_harmonic_at_a_time_matches_the_outer_product() -> None:
    import numpy as np

    values = build_protocol("multisine:period=2,fmax=5,periods=1", 0.0, 1.0, 0.01).values
    t = np.arange(200) * 0.01
    harmonics = np.arange(1, 11)
    phases = np.random.default_rng(0).uniform(0.0, 2 * np.pi, harmonics.size)
    signal = np.sin(2 * np.pi * np.outer(t, harmonics) / 2.0 + phases).sum(axis=1)
    expected = (signal - signal.min()) / (signal.max() - signal.min())
    assert values[-200:] == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("rate", ["1e-9", "0.5"])
def test_probe_rate_too_slow_to_stop_is_refused(capsys: pytest.CaptureFixture[str], rate: str) -> None:
    """--rate 1e-9 slept for 30 years and ignored SIGTERM."""
    assert main(["edge", "probe", "--config", str(HIL_RIG), "--rate", rate, "--duration", "0.1"]) == 2
    assert "must be at least 1 Hz" in one_line_error(capsys)


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (bytes(range(256)) * 10, "cannot read file"),  # was "internal error UnicodeDecodeError ... a pmactl bug"
        (b"t,u\n0,1\n1,2\n2,1\n3,2\n", "looks like sample numbers or milliseconds"),  # was simulated as seconds
        (b"t,u\n0,1\n0.01,1e308\n0.02,1\n", "beyond +-1e+100"),  # was accepted
        (b"t,u\n0,1\n0.02,2\n0.01,1\n", "not strictly increasing at file line 4"),
    ],
)
def test_simulate_bad_input_is_one_line_before_the_bundle_is_read(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: bytes, message: str
) -> None:
    data, out = tmp_path / "input.csv", tmp_path / "pred.csv"
    data.write_bytes(content)
    assert main(["simulate", str(tmp_path), str(data), "--out", str(out)]) == 2
    assert message in one_line_error(capsys)
    assert not out.exists()


@pytest.mark.parametrize(
    "content",
    [b"t;u\n0;1\n0.01;2\n0.02;1.5\n", b"t;u\n0;1\n0,01;2\n0,02;1,5\n", b"t\tu\n0\t1\n0.01\t2\n0.02\t1.5\n"],
)
def test_simulate_reads_a_designed_input_as_labs_write_it(tmp_path: Path, content: bytes) -> None:
    """A t,u input with ';', tab or a decimal comma (was: "columns 't' and 'u' needed; found ['t;u']")."""
    import argparse

    from host.cli.simulate import read_input

    data = tmp_path / "input.csv"
    data.write_bytes(content)
    t, u, y = read_input(data, argparse.Namespace(columns=None, time_unit=None))
    assert t == pytest.approx([0.0, 0.01, 0.02]) and u == pytest.approx([1.0, 2.0, 1.5]) and y is None


def test_simulate_keeps_a_designed_inputs_rows_as_spaced(tmp_path: Path) -> None:
    """Breakpoints of a designed input are its samples: no resampling, no 'two recordings' gap."""
    import argparse

    from host.cli.simulate import read_input

    data = tmp_path / "input.csv"
    data.write_text("t,u\n0,0\n0.1,0\n0.101,2\n0.2,2\n0.3,1\n")
    t, u, y = read_input(data, argparse.Namespace(columns=None, time_unit=None))
    assert t == pytest.approx([0.0, 0.1, 0.101, 0.2, 0.3]) and u == pytest.approx([0, 0, 2, 2, 1]) and y is None


def test_record_shorter_than_the_host_tools_read_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """--duration 0.0001 wrote a one-row CSV that pmactl fit then refused."""
    out = tmp_path / "run.csv"
    args = ["edge", "record", "--config", str(HIL_RIG), "--protocol", "steps", "--out", str(out)]
    assert main([*args, "--duration", "0.0001"]) == 2
    assert "fewer than 10 rows at 100 Hz" in one_line_error(capsys)
    assert not out.exists()
    assert main([*args, "--duration", "0.1", "--json"]) == 0  # exactly 10 rows is enough
    assert len(out.read_text().splitlines()) == 11
