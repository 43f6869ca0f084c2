"""Every failure the v2 review found on the emulated rig, through the real runtime and CLI:
device failures reach the supervisor, nothing is taken as "fine" when it could not be read,
and bad input is one line with exit status 2."""

from __future__ import annotations

import errno
import json
import math

import pytest

from edge.errors import BusError, PmactlError
from edge.hal.gpio import GpiodLines
from edge.runtime.safety import Fault
from edge.runtime.telemetry import read_telemetry
from host.cli import main
from tests.edge_helpers import HIL_RIG, fit_bundle

CONST = "const:value=40"


@pytest.fixture(scope="module")
def bundle(tmp_path_factory):
    return fit_bundle(tmp_path_factory.mktemp("bundle") / "preisach")


def rig_with(tmp_path, faults: str, name: str = "rig.toml"):
    """The shipped HIL config with ``faults`` scheduled in its sim:// URL."""
    path = tmp_path / name
    path.write_text(
        HIL_RIG.read_text().replace("sim://rig?clock=lockstep", f"sim://rig?clock=lockstep&faults={faults}")
    )
    return path


def run_cli(tmp_path, capsys, bundle, faults, reference=CONST, duration="4"):
    telemetry = tmp_path / "t.pmt"
    args = ["edge", "run", "--config", str(rig_with(tmp_path, faults)), "--bundle", str(bundle)]
    code = main([*args, "--reference", reference, "--duration", duration, "--telemetry", str(telemetry), "--json"])
    captured = capsys.readouterr()
    return code, json.loads(captured.out), read_telemetry(telemetry), captured.err


def first_fault(record):
    t, fault = record.column("t"), record.column("fault")
    return t[fault > 0][0], set(fault[fault > 0])


def test_a_failing_valve_dac_write_reaches_the_supervisor(tmp_path, capsys, bundle):
    """Constant set-point: before v2, 5000 failed writes in 5 s gave faults: []."""
    code, summary, record, err = run_cli(tmp_path, capsys, bundle, "dac_nack@2.0")
    assert code == 1 and len(summary["faults"]) == 1
    assert "dac write failed (EREMOTEIO)" in summary["faults"][0] and "no acknowledge" in summary["faults"][0]
    at, kinds = first_fault(record)
    assert 2.0 - 0.001 <= at < 2.0 + 0.003 and kinds == {Fault.BUS.value}
    assert (record.rows["wr_dac"] == errno.EREMOTEIO).sum() >= 2  # every failed write is in the telemetry
    assert "FAULT: 3 consecutive ticks with a device error; dac write failed" in err


def test_an_adc_that_raises_does_not_hide_a_pressed_e_stop(tmp_path, capsys, bundle):
    """Before v2 a failed ADC read set estop = False for that tick."""
    code, summary, record, _ = run_cli(tmp_path, capsys, bundle, "adc_nack@2.0,estop@2.0")
    at, kinds = first_fault(record)
    assert code == 1 and summary["faults"] == ["e-stop pressed"] and kinds == {Fault.ESTOP.value}
    assert at < 2.0 + 0.002  # the tick the e-stop went down, not after a bus-error streak
    row = record.rows[-1]
    assert row["rd_adc"] == errno.EREMOTEIO and row["estop"] == 1.0 and math.isnan(row["contraction_mm"])


def test_a_gpio_chip_that_fails_with_oserror_is_a_device_fault_not_a_traceback(tmp_path, capsys, bundle):
    code, summary, record, err = run_cli(tmp_path, capsys, bundle, "gpio_error@1.0")
    assert code == 1 and "lines read failed (ENODEV)" in summary["faults"][0] and "Traceback" not in err
    at, kinds = first_fault(record)
    assert 1.0 - 0.001 <= at < 1.0 + 0.003 and kinds == {Fault.BUS.value}
    assert record.rows["u_bar"][-1] == 0.0 and [e["kind"] for e in record.events][-2:] == ["fault", "end"]


class _VanishedChip:
    """libgpiod v2's request object after the chip went away: every call raises OSError."""

    def get_value(self, offset):
        raise OSError(errno.ENODEV, "No such device")

    def set_value(self, offset, value):
        raise OSError(errno.ENODEV, "No such device")

    def release(self):
        raise OSError(errno.ENODEV, "No such device")


def test_libgpiod_oserror_becomes_a_bus_error():
    pytest.importorskip("gpiod")
    from gpiod.line import Value

    lines = object.__new__(GpiodLines)
    lines._request, lines._offsets, lines._value = _VanishedChip(), {"estop": 27, "valve_enable": 17}, Value
    with pytest.raises(BusError, match="GPIO line 'estop': read failed") as info:
        lines.get("estop")
    assert isinstance(info.value, PmactlError) and info.value.errno == errno.ENODEV
    with pytest.raises(BusError, match="GPIO line 'valve_enable': write failed"):
        lines.set("valve_enable", False)
    lines.close()  # releasing a vanished chip is not an error


def one_line_refusal(capsys, argv, expected):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert expected in err and err.count("\n") == 0 and "Traceback" not in err, err


@pytest.mark.parametrize(
    ("flags", "expected"),
    [
        (["--duration", "nan"], "--duration nan must be a finite number of seconds > 0"),
        (["--duration", "inf"], "--duration inf must be a finite number of seconds > 0"),
        (["--duration", "5", "--settle", "5"], "--settle 5 s is not shorter than the run (5 s)"),
        (["--duration", "5", "--settle", "nan"], "--settle nan must be a finite number"),
    ],
)
def test_a_duration_or_settle_that_measures_nothing_is_refused(capsys, bundle, flags, expected):
    one_line_refusal(capsys, ["edge", "run", "--config", str(HIL_RIG), "--bundle", str(bundle), *flags], expected)


@pytest.mark.parametrize(
    ("content", "expected"),
    [
        ("t,y_ref\n0,40\n", "one row is not a trajectory"),
        ("t,y_ref\n0,40\n1\n2,41\n", "line 3 has t='1', y_ref=None; both must be numbers"),
        (b"\x00\x01\xffPK\x03\x04binary", "not a text CSV"),
        (None, "is a directory"),
    ],
)
def test_a_bad_reference_file_is_refused(tmp_path, capsys, bundle, content, expected):
    path = tmp_path / "ref.csv"
    if content is None:
        path.mkdir()
    elif isinstance(content, bytes):
        path.write_bytes(content)
    else:
        path.write_text(content)
    args = ["edge", "run", "--config", str(HIL_RIG), "--bundle", str(bundle), "--reference", f"csv:{path}"]
    one_line_refusal(capsys, args, expected)


@pytest.mark.parametrize(
    ("find", "replace", "expected"),
    [
        (
            "tracking_error_max_mm = 25.0",
            "tracking_error_max_mm = nan",
            "tracking_error_max_mm = nan is not a finite number",
        ),
        ("pressure_max_bar = 6.5", "pressure_max_bar = nan", "[safety] pressure_max_bar = nan is not a finite number"),
        ("rate_hz = 1000", "rate_hz = nan", "[loop] rate_hz = nan is not a finite number"),
        ("ring_ticks = 65536", "ring_ticks = 1e10", "[telemetry] ring_ticks = 10000000000.0 is not an integer"),
        ("ring_ticks = 65536", "ring_ticks = 10000000000", "[telemetry] ring_ticks = 10000000000 must be in 1024.."),
    ],
)
def test_a_config_that_would_switch_a_trip_off_or_exhaust_memory_is_refused(
    tmp_path, capsys, bundle, find, replace, expected
):
    config = tmp_path / "rig.toml"
    text = HIL_RIG.read_text()
    assert find in text
    config.write_text(text.replace(find, replace, 1))
    one_line_refusal(
        capsys, ["edge", "run", "--config", str(config), "--bundle", str(bundle), "--duration", "1"], expected
    )


def test_a_second_run_to_the_same_telemetry_path_is_refused_and_the_first_kept(tmp_path, capsys, bundle):
    telemetry = tmp_path / "run.pmt"
    args = ["edge", "run", "--config", str(HIL_RIG), "--bundle", str(bundle), "--duration", "0.2", "--telemetry"]
    assert main([*args, str(telemetry)]) == 0
    first = telemetry.read_bytes()
    capsys.readouterr()
    one_line_refusal(capsys, [*args, str(telemetry)], "exists, and a run never overwrites another")
    assert telemetry.read_bytes() == first
    assert main([*args, str(tmp_path / "run-{time}.pmt")]) == 0  # the service's pattern: a new file per run
    assert len(list(tmp_path.glob("run-2*.pmt"))) == 1


def test_a_full_disk_mid_run_is_a_logged_fault_with_the_valve_vented_and_the_summary_kept(tmp_path, bundle):
    """/dev/full answers every write with ENOSPC, as a full disk does."""
    from tests.edge_helpers import runtime

    edge = runtime(bundle, CONST, telemetry_path=tmp_path / "t.pmt")
    rig = edge.rig.device.rig

    replaced = []

    def disk_fills(t: float) -> None:
        if abs(t - 1.0) < 5e-4:
            # swap, never close here: the writer thread may be inside a write to the old handle
            writer = edge.telemetry
            replaced.append(writer._file)
            writer._file = open("/dev/full", "wb")  # noqa: SIM115

    edge.on_tick.append(disk_fills)
    try:
        summary = edge.run(10.0).as_dict()
    finally:
        for handle in replaced:
            handle.close()
    assert len(summary["faults"]) == 1 and "No space left on device" in summary["faults"][0]
    assert summary["ticks"] < 10_000 and summary["rms_error"] is not None  # ended early, summary intact
    assert rig.dac.output_volts == 0.0 and not rig.gpio.get("valve_enable")
