"""The documentation cannot drift: the command reference lists every subcommand the parser has,
and the README's test command installs what .ci/run installs."""

from __future__ import annotations

import argparse
import importlib.util
import re

from host.cli import build_parser
from tests.conftest import REPO


def _hook():
    spec = importlib.util.spec_from_file_location("cli_reference", REPO / "docs" / "hooks" / "cli_reference.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def every_command(parser: argparse.ArgumentParser, path: tuple[str, ...] = ("pmactl",)) -> list[tuple[str, ...]]:
    found = []
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, child in action.choices.items():
                found += [(*path, name), *every_command(child, (*path, name))]
    return found


def test_the_generated_reference_has_a_section_for_every_subcommand():
    text = _hook().reference_markdown()
    commands = every_command(build_parser())
    assert ("pmactl", "edge", "run") in commands and len(commands) > 20
    for path in commands:
        assert f"{' '.join(path)} {{#{'-'.join(path)}}}" in text, path


def test_the_reference_replaces_only_its_marker():
    hook = _hook()
    assert hook.on_page_markdown("# plain page", None, None, None) == "# plain page"
    assert "pmactl fit" in hook.on_page_markdown(hook.MARKER, None, None, None)


def test_the_readme_is_a_front_door_and_its_test_command_is_what_ci_runs():
    readme = (REPO / "README.md").read_text()
    assert len(readme.splitlines()) <= 300
    ci_install = re.search(r"pip install --quiet (.*)", (REPO / ".ci" / "run").read_text())
    assert ci_install and ci_install.group(1) in readme
