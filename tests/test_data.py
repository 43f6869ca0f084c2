"""Measured-data loader: one clear error per problem, resampling said out loud."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from edge.errors import DataError
from host.data import ResampledWarning, load_measurement


def write(tmp_path, text, name="d.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def rows(n=20, dt=0.01):
    return "\n".join(f"{i * dt:.4f},{np.sin(i / 3):.4f},{np.cos(i / 3):.4f}" for i in range(n))


def test_loads_required_and_optional_columns(tmp_path):
    body = "\n".join(f"{i * 0.01:.2f},{i},{2 * i},{0.5},{20 + i}" for i in range(20))
    m = load_measurement(write(tmp_path, "t,u,y,load,temperature\n" + body))
    assert len(m) == 20 and m.dt == pytest.approx(0.01)
    assert set(m.extras) == {"load", "temperature"}
    np.testing.assert_allclose(m.y, 2 * m.u)


def test_missing_column_names_what_was_found(tmp_path):
    with pytest.raises(DataError, match=r"column\(s\) 'y' missing; found \['t', 'u', 'x'\]"):
        load_measurement(write(tmp_path, "t,u,x\n" + rows()))


def test_nan_rows_are_refused_with_their_line_numbers(tmp_path):
    text = "t,u,y\n" + rows(5) + "\n0.05,nan,1\n0.06,1,\n" + rows(20, 0.01).split("\n", 7)[-1]
    with pytest.raises(DataError, match=r"2 row\(s\) with NaN.*file lines 7, 8"):
        load_measurement(write(tmp_path, text))


def test_a_hole_in_a_load_or_temperature_column_is_refused_with_its_line(tmp_path):
    body = [f"{i * 0.01:.2f},{i},{2 * i},0.5,{20 + i}" for i in range(20)]
    body[11] = "0.11,11,22,nan,31"
    with pytest.raises(DataError, match=r"1 row\(s\) with NaN.*'load' column \(file lines 13\).*delete the column"):
        load_measurement(write(tmp_path, "t,u,y,load,temperature\n" + "\n".join(body)))


def test_a_hole_in_the_pressure_column_is_refused_too(tmp_path):
    body = [f"{i * 0.01:.2f},{i},{2 * i},{1 + i / 10}" for i in range(20)]
    body[3] = "0.03,3,6,inf"
    with pytest.raises(DataError, match=r"'p' column \(file lines 5\)"):
        load_measurement(write(tmp_path, "t,u,y,p\n" + "\n".join(body)))


def test_a_hole_in_an_unnamed_extra_column_is_kept(tmp_path):
    body = [f"{i * 0.01:.2f},{i},{2 * i},{i % 3}" for i in range(20)]
    body[4] = "0.04,4,8,"
    m = load_measurement(write(tmp_path, "t,u,y,pwm_in\n" + "\n".join(body)))
    assert np.isnan(m.extras["pwm_in"][4])


def test_non_increasing_time_is_refused(tmp_path):
    text = "t,u,y\n0,1,1\n0.1,1,1\n0.1,2,2\n" + "\n".join(f"{0.2 + i / 10},1,1" for i in range(20))
    with pytest.raises(DataError, match="not strictly increasing at file line 4"):
        load_measurement(write(tmp_path, text))


def irregular(tmp_path):
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.01, 0.03, 200))
    return write(tmp_path, "t,u,y\n" + "\n".join(f"{ti},{np.sin(ti)},{np.cos(ti)}" for ti in t))


def test_irregular_sampling_is_resampled_with_a_warning(tmp_path):
    with pytest.warns(ResampledWarning, match="resampled from irregular steps"):
        m = load_measurement(irregular(tmp_path))
    assert np.ptp(np.diff(m.t)) < 1e-9
    assert m.notes and "linear interpolation" in m.notes[0]
    np.testing.assert_allclose(m.u, np.sin(m.t), atol=2e-4)


def test_irregular_sampling_can_be_refused(tmp_path):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(DataError, match="irregular sampling"):
            load_measurement(irregular(tmp_path), irregular="refuse")


@pytest.mark.parametrize(
    "content, message",
    [
        ("", "file is empty"),
        ("t,u,y\n0,1,2\n0.1,1,2\n", "only 2 samples"),
        ("t;u;y\n0;1;2\n", "only 1 samples"),
        ("a;b\n0;1\n", "missing.*--columns"),
    ],
)
def test_unusable_files(tmp_path, content, message):
    with pytest.raises(DataError, match=message):
        load_measurement(write(tmp_path, content))


def test_unreadable_file(tmp_path):
    with pytest.raises(DataError, match="cannot read file"):
        load_measurement(tmp_path / "absent.csv")
    binary = tmp_path / "b.csv"
    binary.write_bytes(b"\xff\xfe\x00\x81" * 10)
    with pytest.raises(DataError):
        load_measurement(binary)


def test_utf8_byte_order_mark_is_read_as_text(tmp_path):
    path = tmp_path / "excel.csv"
    path.write_bytes(b"\xef\xbb\xbf" + ("t,u,y\n" + rows()).encode())
    m = load_measurement(path)
    assert len(m) == 20 and m.u[1] == pytest.approx(np.sin(1 / 3), abs=1e-4)


def test_quoted_numbers_are_numbers(tmp_path):
    body = "\n".join('"' + line.replace(",", '","') + '"' for line in rows().splitlines())
    m = load_measurement(write(tmp_path, '"t","u","y"\n' + body))
    assert len(m) == 20 and np.all(np.isfinite(m.y))


@pytest.mark.parametrize("broken, fields", [("0.05,0.1", 2), ("0.05,0.1,0.2,0.3", 4)])
def test_a_row_with_the_wrong_field_count_is_refused_with_its_line(tmp_path, broken, fields):
    lines = rows().splitlines()
    lines[4] = broken
    with pytest.raises(DataError, match=rf"line 6 has {fields} field\(s\) but the header has 3"):
        load_measurement(write(tmp_path, "t,u,y\n" + "\n".join(lines)))


def test_a_duplicated_column_name_is_refused(tmp_path):
    body = "\n".join(line + ",0" for line in rows().splitlines())
    with pytest.raises(DataError, match=r"line 1: column 'y' appears twice \(columns 3 and 4\)"):
        load_measurement(write(tmp_path, "t,u,y,y\n" + body))


def test_values_too_large_to_fit_are_refused_with_their_lines(tmp_path):
    lines = rows().splitlines()
    lines[2] = "0.0200,1e300,0.5"
    with pytest.raises(DataError, match=r"beyond \+-1e\+100 \(file lines 4\)"):
        load_measurement(write(tmp_path, "t,u,y\n" + "\n".join(lines)))


def test_a_long_time_gap_is_a_split_record_refused_at_its_position(tmp_path):
    first = [f"{i * 1e-4:.4f},{np.sin(i / 9):.4f},{np.cos(i / 9):.4f}" for i in range(50)]
    second = [f"{1000 + i * 1e-4:.4f},{np.sin(i / 9):.4f},{np.cos(i / 9):.4f}" for i in range(50)]
    with pytest.raises(DataError, match=r"t jumps by 1000 s .* between file lines 51 and 52 .* split it there"):
        load_measurement(write(tmp_path, "t,u,y\n" + "\n".join(first + second)))


def test_line_numbers_count_blank_and_comment_lines(tmp_path):
    lines = rows().splitlines()
    text = "t,u,y\n# exported by the rig\n" + "\n".join(lines[:3]) + "\n\n0.03,nan,1\n" + "\n".join(lines[4:])
    with pytest.raises(DataError, match=r"file lines 7\)"):
        load_measurement(write(tmp_path, text))
