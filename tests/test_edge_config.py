"""Rig config: the examples load, each mistake gets its own clear error, the wires set the rate."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from edge.errors import ConfigError
from edge.runtime.config import config_from_dict, fastest_period_s, load_config

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"


def example(name: str = "hil-rig.toml") -> dict:
    return tomllib.loads((EXAMPLES / name).read_text())


@pytest.mark.parametrize("name", ["hil-rig.toml", "hil-serial.toml", "rpi-ads1115.toml"])
def test_every_shipped_example_config_is_valid(name):
    config = load_config(EXAMPLES / name)
    assert config.period_s >= fastest_period_s(config)


def refused(raw: dict) -> str:
    with pytest.raises(ConfigError) as info:
        config_from_dict(raw, "rig.toml")
    message = str(info.value)
    assert "\n" not in message and message.startswith("rig.toml: ")
    return message


def test_a_misspelled_key_is_named_with_a_suggestion():
    raw = example()
    raw["adc"]["data_rate"] = raw["adc"].pop("data_rate_sps")
    assert "[adc] unknown key 'data_rate'; did you mean 'data_rate_sps'?" in refused(raw)


def test_an_unknown_section_is_refused():
    raw = example()
    raw["pid"] = {"kp": 1.0}
    assert "unknown key 'pid'" in refused(raw)


def test_missing_calibration_is_named():
    raw = example()
    del raw["sensors"]["contraction"]
    assert "[sensors.contraction] missing" in refused(raw)
    raw = example()
    del raw["sensors"]["pressure"]["bar_per_volt"]
    assert "[sensors.pressure] missing required key 'bar_per_volt'" in refused(raw)


def test_inverted_limits_are_refused():
    raw = example()
    raw["control"]["pressure_min_bar"], raw["control"]["pressure_max_bar"] = 6.0, 1.0
    assert "pressure_min_bar 6.0 >= pressure_max_bar 1.0; limits inverted" in refused(raw)
    raw = example()
    raw["control"]["pressure_max_bar"] = 7.0
    assert "exceeds [safety] pressure_max_bar" in refused(raw)


def test_an_unknown_backend_url_is_refused():
    raw = example()
    raw["rig"]["io"] = "spi:///dev/spidev0.0"
    assert "is not a known backend; use i2c:///dev/i2c-N, serial:///dev/ttyXXX or sim://rig" in refused(raw)


def test_a_wrong_type_is_named():
    raw = example()
    raw["loop"]["rate_hz"] = "fast"
    assert "[loop] rate_hz = 'fast' is not a number" in refused(raw)


def test_a_chip_rate_the_converter_does_not_have_is_refused():
    raw = example()
    raw["adc"]["chip"], raw["adc"]["data_rate_sps"] = "ADS1115", 3300
    assert "ADS1115 has no 3300 SPS" in refused(raw)


def test_an_ads1115_cannot_read_two_channels_at_1_khz_and_the_message_says_how_fast_it_can():
    raw = example()
    raw["adc"]["chip"], raw["adc"]["data_rate_sps"] = "ADS1115", 860
    message = refused(raw)
    # 2 x 1.163 ms conversions + 2 x 132 + 29 I2C clocks at 1 MHz + 50 us compute
    assert "fastest this rig can meet is 2.669 ms (375 Hz)" in message and "860 SPS" in message


def test_a_slow_i2c_clock_limits_even_the_ads1015():
    raw = example()
    raw["rig"]["i2c_bus_hz"] = 400_000
    assert "1.389 ms (720 Hz)" in refused(raw)
    raw["loop"]["rate_hz"] = 700
    assert config_from_dict(raw).loop.rate_hz == 700


def test_a_slow_serial_link_limits_the_rate():
    raw = example("hil-serial.toml")
    raw["serial"]["baud"] = 115_200
    assert "28 bytes on the wire per tick take 2.431 ms at 115200 baud" in refused(raw)


def test_a_missing_file_and_bad_toml_are_one_line_errors(tmp_path):
    with pytest.raises(ConfigError, match="no such file; start from docs/examples/hil-rig.toml"):
        load_config(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[rig\nio = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(bad)
