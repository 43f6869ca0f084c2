"""``pmactl diagnose --rules FIELD=VALUE,...``: v3's rules changed from the command line
(host/diagnose/rules.with_overrides), named in the verdict, bad input one line and exit 2."""

from __future__ import annotations

import json

import pytest

from host.cli import main
from host.diagnose.rules import RULES, with_overrides
from tests.test_diagnose_v3 import runs_of, write_runs


def test_overrides_change_the_fields_and_name_the_version():
    rules = with_overrides("column_first=true, alpha=0.01,output_lags_s=0/0.05")
    assert (rules.column_first, rules.alpha, rules.output_lags_s) == (True, 0.01, (0.0, 0.05))
    assert rules.version == "v3.1+column_first=true,alpha=0.01,output_lags_s=0/0.05"
    assert with_overrides(rules.version.partition("+")[2]) == rules  # the method string is --rules text
    assert with_overrides("") is RULES and with_overrides("max_folds=3").max_folds == 3


@pytest.mark.parametrize(
    "text, message",
    [
        ("colum_first=true", "unknown field 'colum_first'"),
        ("version=v9", "unknown field 'version'"),
        ("column_first=maybe", "column_first=maybe is not true or false"),
        ("alpha", "alpha needs a value"),
        ("alpha=x", "alpha=x is not a number"),
        ("max_folds=2.5", "max_folds=2.5 is not a whole number"),
        ("output_lags_s=0/a", "not numbers separated by '/'"),
        ("node_ridge=-1", "node_ridge takes finite values of 0 or more"),
        ("node_ridge=inf", "finite values of 0 or more"),
        ("alpha=1", "between 0 and 1"),
        ("alpha=0", "above 0 and at most 1"),
        ("ladder_drop=1.5", "above 0 and at most 1"),
        ("max_folds=0", "max_folds takes finite values of 2 or more"),
        ("bootstrap_draws=0", "bootstrap_draws takes finite values of 19 or more"),
        ("output_lags_s=/", "holds no number"),
    ],
)
def test_bad_overrides_say_which_field_and_what_it_takes(text, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(")):
        with_overrides(text)


def test_the_cli_runs_v3_with_the_rules_given_and_writes_them_into_the_json(tmp_path, capsys):
    write_runs(runs_of(5, 12, "load"), tmp_path / "runs")
    out = tmp_path / "v3.json"
    code = main(
        ["diagnose", str(tmp_path / "runs" / "*.csv"), "--rules", "column_heldout_surrogates=true", "--json", str(out)]
    )
    assert code == 0
    payload = json.loads(out.read_text())
    assert payload["method"] == "v3.1+column_heldout_surrogates=true"
    assert payload["rules"]["column_heldout_surrogates"] is True
    assert payload["cause"] == "load_dependence" and payload["heldout_surrogates"]["load_dependence"]["copies"] == 199
    assert "method v3.1+column_heldout_surrogates=true" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, message",
    [
        (["{a}", "{b}", "--rules", "alpha=2"], "a share or a probability"),
        (["{a}", "--rules", "alpha=0.01"], "--rules sets the rules of method v3"),
        (["--train", "{a}", "--test", "{b}", "--rules", "alpha=0.01"], "--rules sets the rules of the runs method"),
        (["--train", "{a}", "--test", "{b}", "--method", "v3", "--rules", "alpha=0.01"], "the runs method"),
    ],
)
def test_bad_rules_on_the_command_line_are_one_line_and_exit_2(tmp_path, capsys, args, message):
    a, b = write_runs(runs_of(8, 2, "none"), tmp_path)
    code = main(["diagnose", *[arg.format(a=a, b=b) for arg in args]])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and message in err[0]
