"""Rig config: the examples load, each mistake gets its own clear error, every limit is finite
and in range, the wires (a sum over the devices' own wire times) set the rate."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from edge.errors import ConfigError
from edge.runtime.config import config_from_dict, fastest_period_s, load_config
from tests.edge_helpers import HIL_RIG

EXAMPLES = Path(__file__).resolve().parents[1] / "docs" / "examples"

LEGACY_HIL_RIG = """
[rig]
io = "sim://rig?adc=ADS1015&clock=lockstep"
gpio = "sim://rig"
i2c_bus_hz = 1_000_000
[loop]
rate_hz = 1000
realtime = false
[adc]
chip = "ADS1015"
data_rate_sps = 3300
[sensors.contraction]
channel = 1
mm_per_volt = 48.484848
volts_at_zero_mm = 0.20625
[sensors.pressure]
channel = 0
bar_per_volt = 2.5
volts_at_zero_bar = 0.5
[valve]
bar_per_volt = 2.0
"""


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


def test_a_config_in_the_first_format_still_loads_as_the_same_rig():
    config = config_from_dict(tomllib.loads(LEGACY_HIL_RIG), "old.toml")
    assert [d.driver for d in config.rig.devices] == ["ads1015", "mcp4725", "gpio"]
    channel = config.rig.channel("contraction")
    assert (channel.device, channel.input, channel.scale, channel.zero) == ("adc", 1, 48.484848, 0.20625)
    assert config.rig.channel("estop").active_low and config.rig.bus("i2c").options["hz"] == 1_000_000


def test_a_misspelled_key_is_named_with_a_suggestion():
    raw = example()
    raw["loop"]["rate"] = raw["loop"].pop("rate_hz")
    assert "[loop] unknown key 'rate'; did you mean 'rate_hz'?" in refused(raw)
    raw = example()
    raw["devices"]["adc"]["data_rate"] = raw["devices"]["adc"].pop("data_rate_sps")
    assert "[devices.adc] unknown key(s) ['data_rate'] for ads1015" in refused(raw)


def test_an_unknown_section_is_refused():
    raw = example()
    raw["pid"] = {"kp": 1.0}
    assert "unknown section(s) ['pid']" in refused(raw)


def test_a_missing_channel_or_device_is_named():
    raw = example()
    del raw["channels"]["contraction"]
    assert "[channels] contraction missing" in refused(raw)
    raw = example()
    raw["channels"]["contraction"]["device"] = "adc2"
    assert "[channels.contraction] device = 'adc2' is not a declared device" in refused(raw)
    raw = example()
    raw["devices"]["adc"]["driver"] = "ads9999"
    assert "driver = 'ads9999' is not installed" in refused(raw)


def test_inverted_limits_are_refused():
    raw = example()
    raw["control"]["pressure_min_bar"], raw["control"]["pressure_max_bar"] = 6.0, 1.0
    assert "pressure_min_bar 6.0 >= pressure_max_bar 1.0; limits inverted" in refused(raw)
    raw = example()
    raw["control"]["pressure_max_bar"] = 7.0
    assert "exceeds [safety] pressure_max_bar" in refused(raw)


@pytest.mark.parametrize(
    ("section", "key", "value"),
    [
        ("safety", "tracking_error_max_mm", math.nan),
        ("safety", "pressure_max_bar", math.nan),
        ("safety", "contraction_max_mm", math.inf),
        ("loop", "rate_hz", math.nan),
        ("loop", "rate_hz", math.inf),
        ("control", "kp_bar_per_mm", math.nan),
        ("telemetry", "flush_interval_s", math.nan),
    ],
)
def test_a_non_finite_limit_is_refused_in_one_line(section, key, value):
    """NaN compares false with everything: accepted, it would switch the trip off."""
    raw = example()
    raw[section][key] = value
    assert f"[{section}] {key} = {value!r} is not a finite number" in refused(raw)


@pytest.mark.parametrize(
    ("section", "key", "value", "expected"),
    [
        ("control", "kp_bar_per_mm", -0.05, "must be in 0..1000; a negative gain"),
        ("safety", "tracking_error_max_mm", 0.0, "must be in 0.01..10000"),
        ("safety", "bus_error_streak", 0, "must be in 1..1000"),
        ("loop", "rate_hz", 0.0, "must be in 1..100000"),
        ("telemetry", "ring_ticks", 10_000_000_000, "must be in 1024.."),
        ("telemetry", "ring_ticks", 1e10, "is not an integer"),
    ],
)
def test_an_out_of_range_value_is_refused_in_one_line(section, key, value, expected):
    raw = example()
    raw.setdefault(section, {})[key] = value
    assert expected in refused(raw)


def test_an_unknown_bus_url_is_refused():
    raw = example()
    raw["buses"]["i2c"]["url"] = "spi:///dev/spidev0.0"
    assert "is not a known bus; use i2c:///dev/i2c-N" in refused(raw)
    raw = example()
    raw["devices"]["adc"]["bus"] = "gpio"
    raw["buses"]["gpio"]["url"] = "gpiochip:///dev/gpiochip0"
    assert "ads1015 cannot sit on 'gpiochip:///dev/gpiochip0'" in refused(raw)


def test_a_wrong_type_is_named():
    raw = example()
    raw["loop"]["rate_hz"] = "fast"
    assert "[loop] rate_hz = 'fast' is not a finite number" in refused(raw)


def test_a_chip_rate_the_converter_does_not_have_is_refused():
    raw = example()
    raw["devices"]["adc"]["driver"], raw["devices"]["adc"]["data_rate_sps"] = "ads1115", 3300
    assert "ADS1115 has no 3300 SPS" in refused(raw)


def test_the_fastest_period_is_the_sum_of_the_devices_wire_times():
    """ADS1115: one conversion wait (the other is pipelined between ticks) + 2 x 132 + 29 I2C
    clocks at 1 MHz + 50 us compute = 1.163 + 0.293 + 0.050 ms."""
    raw = example()
    raw["devices"]["adc"]["driver"], raw["devices"]["adc"]["data_rate_sps"] = "ads1115", 860
    message = refused(raw)
    assert "fastest this rig can meet is 1.506 ms (664 Hz)" in message
    assert "adc (ADS1115 at 860 SPS): 1 conversion wait(s)" in message and "dac (MCP4725)" in message
    raw["devices"]["adc"]["pipeline"] = False  # both conversions inside the tick
    assert "fastest this rig can meet is 2.669 ms (375 Hz)" in refused(raw)
    raw["loop"]["rate_hz"] = 370
    assert config_from_dict(raw).loop.rate_hz == 370


def test_a_slow_i2c_clock_limits_even_the_ads1015():
    raw = example()
    raw["buses"]["i2c"]["hz"] = 100_000
    assert "(ADS1015 at 3300 SPS)" in refused(raw) and "100 kHz" in refused(raw)


def test_a_slow_serial_link_limits_the_rate():
    raw = example("hil-serial.toml")
    raw["buses"]["daq"]["baud"] = 115_200
    assert "28 bytes on the wire per tick take 2.431 ms at 115200 baud" in refused(raw)


def test_an_extra_channel_is_part_of_the_rig_and_its_limits_are_checked():
    raw = example()
    raw["channels"]["load"] = {"device": "adc", "input": 2, "unit": "kg", "scale": 10.0, "min": -1.0, "max": 40.0}
    assert "1.081 ms (925 Hz): adc (ADS1015 at 3300 SPS): 2 conversion wait(s)" in refused(raw)  # a third channel
    raw["loop"]["rate_hz"] = 900
    config = config_from_dict(raw)
    load = config.rig.channel("load")
    assert load.field == "load_kg" and (load.minimum, load.maximum) == (-1.0, 40.0)
    raw["channels"]["load"]["min"] = 50.0
    assert "[channels.load] min 50.0 >= max 40.0" in refused(raw)


def test_trusted_keys_must_be_files_and_are_kept_as_paths(tmp_path):
    raw = example()
    raw["bundle"] = {"trusted_keys": ["lab.pub"]}
    with pytest.raises(ConfigError, match=r"\[bundle\] trusted_keys: 'lab.pub' is not a file"):
        config_from_dict(raw, str(tmp_path / "rig.toml"))
    (tmp_path / "lab.pub").write_text("key")
    config = config_from_dict(raw, str(tmp_path / "rig.toml"))
    assert config.bundle_trusted_keys == (tmp_path / "lab.pub",)
    raw["bundle"] = {"trusted_keys": "lab.pub"}
    assert "[bundle] trusted_keys = 'lab.pub' is not list[str]" in refused(raw)


def test_a_missing_file_bad_toml_a_directory_and_binary_are_one_line_errors(tmp_path):
    with pytest.raises(ConfigError, match="no such file; start from docs/examples/hil-rig.toml"):
        load_config(tmp_path / "nope.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[rig\nio = 1")
    with pytest.raises(ConfigError, match="not valid TOML"):
        load_config(bad)
    with pytest.raises(ConfigError, match="is a directory"):
        load_config(tmp_path)
    (tmp_path / "bin.toml").write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(ConfigError, match="not a text file"):
        load_config(tmp_path / "bin.toml")


@pytest.mark.parametrize(
    ("where", "change", "expected"),
    [
        (("channels", "estop"), {"input": -1}, "[channels.estop] input = -1 must be a GPIO line offset in 0..1023"),
        (("channels", "valve_enable"), {"input": 4096}, "[channels.valve_enable] input = 4096"),
        (("channels", "estop"), {"input": 17}, "[channels.estop] input = 17 is already [channels.valve_enable]'s"),
        (("channels", "contraction"), {"input": 7}, "[channels.contraction] input = 7 must be the ADS1015's AIN"),
        (("channels", "contraction"), {"input": 0}, "[channels.contraction] input = 0 is already [channels.pressure]"),
        (("channels", "pressure"), {"zero": 9.0}, "[channels.pressure] zero = 9 V is outside the ADS1015's +-4.096"),
        (("channels", "pressure"), {"scale": 1e9}, "[channels.pressure] scale = 1e+09 is outside"),
        (("channels", "valve"), {"input": 1}, "[channels.valve] input = 1: an MCP4725 has one output"),
        (("devices", "adc"), {"address": 0x50}, "[devices.adc] address = 0x50 is not an ADS1015 address"),
        (("devices", "dac"), {"address": 0x70}, "[devices.dac] address = 0x70 is not an MCP4725 address"),
        (("devices", "dac"), {"address": 0x48}, "[devices.dac] address = 0x48 on bus 'i2c' is already [devices.adc]'s"),
        (("devices", "dac"), {"address": 0x7F}, "[devices.dac] address = 0x7f is not a 7-bit I2C device address"),
    ],
)
def test_every_line_input_address_and_scale_is_range_checked_naming_the_key(where, change, expected):
    raw = tomllib.loads(HIL_RIG.read_text())
    raw[where[0]][where[1]].update(change)
    with pytest.raises(ConfigError) as info:
        config_from_dict(raw, "rig.toml")
    assert expected in str(info.value) and "\n" not in str(info.value)


def test_two_chips_at_one_address_are_refused():
    raw = tomllib.loads((HIL_RIG.parent / "hil-joint.toml").read_text())
    raw["devices"]["dac_b"]["address"] = 0x60
    with pytest.raises(
        ConfigError, match=r"\[devices.dac_b\] address = 0x60 on bus 'i2c' is already \[devices.dac_a\]"
    ):
        config_from_dict(raw, "joint.toml")
