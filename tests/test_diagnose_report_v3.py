"""The v3 report a lab user reads: the verdict in plain words with units, the evidence table per
cause, the held-out check, a line per run, figures per group of runs; no raw dumps, no long floats."""

from __future__ import annotations

import re

import pytest

from host.diagnose.report_figures import p_value, run_groups
from host.diagnose.report_v3 import write_report_v3
from host.diagnose.v3 import DiagnosisV3, diagnose_runs
from tests.test_diagnose_v3 import runs_of


@pytest.fixture(scope="module")
def load_case() -> DiagnosisV3:
    return diagnose_runs(runs_of(5, 12, "load"))


def test_the_report_states_the_verdict_its_gain_in_units_and_what_to_record(tmp_path, load_case):
    d = load_case
    assert d.cause == "load_dependence", d.reason
    text = write_report_v3(d, tmp_path, "12 runs", "mm").read_text()
    verdict = text.split("\n\n")[1]
    assert verdict.startswith("**Verdict: `load_dependence`.** The measured data show that the relation changes")
    h = d.heldout
    assert h is not None
    assert f"from {h.base_rmse:.3g} to {h.ext_rmse:.3g} mm RMS" in verdict
    assert "the same protocol at three or more loads" in verdict  # what to record next


def test_the_evidence_table_has_a_row_per_cause_with_units_and_readable_p_values(tmp_path, load_case):
    text = write_report_v3(load_case, tmp_path, "12 runs", "mm").read_text()
    table = [line for line in text.splitlines() if line.startswith("| ") and line.count("|") == 11]
    assert table[0].startswith("| cause | df | unique statistic | unique p | marginal p") and "MDE [mm]" in table[0]
    rows = {line.split("|")[1].strip(): line for line in table[1:]}
    assert set(rows) == set(load_case.tests)
    assert rows["load_dependence"].rstrip().endswith("**named** |")
    assert "<= 0.005" in rows["load_dependence"]  # 199 surrogates: the smallest p they can give
    assert "Nulls: 1." in text


def test_the_report_has_a_line_per_run_and_the_figures(tmp_path, load_case):
    text = write_report_v3(load_case, tmp_path, "12 runs", "mm").read_text()
    assert "## Per run" in text and "+ load_dependence [mm]" in text
    assert len(re.findall(r"^\| run\d\d \| \d+ \|", text, flags=re.M)) == 12
    assert (tmp_path / "failure.png").stat().st_size > 10_000
    assert (tmp_path / "failure_by_run.png").stat().st_size > 10_000


def test_no_raw_dumps_or_long_floats(tmp_path, load_case):
    text = write_report_v3(load_case, tmp_path, "12 runs", "mm").read_text()
    assert not re.search(r"\d\.\d{6,}", text), re.search(r".{30}\d\.\d{6,}.{10}", text)
    assert not re.search(r"\de-\d", text.split("## The method's reason")[0]), "scientific notation before the reason"
    assert "{" not in text and "array(" not in text


def test_an_effect_free_record_says_none_and_how_large_an_effect_it_would_find(tmp_path):
    d = diagnose_runs(runs_of(4, 12, "none"))  # a plant where v3 names none (the report's text is tested here)
    assert d.cause == "none", d.reason
    text = write_report_v3(d, tmp_path, "12 runs", "mm").read_text()
    assert "**Verdict: none.** No cause is" in text  # significant, or named (with why)
    assert re.search(r"move the output by about [\d.]+ mm RMS to be found", text)


def test_many_runs_are_grouped_into_at_most_eight_panels_of_consecutive_runs():
    assert [len(g) for g in run_groups(5)] == [1] * 5
    groups = run_groups(38)
    assert len(groups) <= 8 and [i for g in groups for i in g] == list(range(38))


@pytest.mark.parametrize(
    "p, resolution, shown", [(0.002, 0.002, "<= 0.002"), (0.0004, None, "< 0.001"), (0.0312, 0.002, "0.031")]
)
def test_p_values_read_as_a_person_writes_them(p, resolution, shown):
    assert p_value(p, resolution) == shown
