"""MkDocs hook: the command reference, generated from ``host.cli.build_parser()`` at build time.

A page holding the marker ``<!-- cli-reference -->`` gets, in its place, one section per
command and subcommand (every level, ``pmactl edge ...`` included) with its ``--help`` text, so
the reference cannot drift from the parser. Listed in ``mkdocs.yml`` under ``hooks``.
"""

from __future__ import annotations

import argparse
import os
from collections.abc import Iterator

MARKER = "<!-- cli-reference -->"
HELP_WIDTH = "100"  # argparse wraps --help to $COLUMNS: fixed, so the page does not depend on the terminal


def commands(
    parser: argparse.ArgumentParser, path: tuple[str, ...] = ("pmactl",)
) -> Iterator[tuple[tuple[str, ...], str, argparse.ArgumentParser]]:
    """(command path, one-line help, parser) of every subcommand under ``parser``, depth first."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            helps = {a.dest: a.help or "" for a in action._choices_actions}
            for name, child in action.choices.items():
                yield (*path, name), helps.get(name, ""), child
                yield from commands(child, (*path, name))


def anchor(path: tuple[str, ...]) -> str:
    return "-".join(path)


def reference_markdown() -> str:
    """The generated reference: an index table, then each command's ``--help``."""
    from host.cli import build_parser

    previous = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = HELP_WIDTH
    try:
        parser = build_parser()
        found = list(commands(parser))
        out = ["| command | what it does |", "|---|---|"]
        out += [f"| [`{' '.join(p)}`](#{anchor(p)}) | {h} |" for p, h, _ in found]
        out += ["", f"## pmactl {{#{anchor(('pmactl',))}}}", "", "```text", parser.format_help().rstrip(), "```", ""]
        for path, summary, child in found:
            out += [f"{'#' * min(2 + len(path) - 2, 4)} {' '.join(path)} {{#{anchor(path)}}}", ""]
            if summary:
                out += [summary[0].upper() + summary[1:] + ".", ""]
            out += ["```text", child.format_help().rstrip(), "```", ""]
        return "\n".join(out)
    finally:
        if previous is None:
            os.environ.pop("COLUMNS", None)
        else:
            os.environ["COLUMNS"] = previous


def on_page_markdown(markdown: str, page: object, config: object, files: object) -> str:  # noqa: ARG001
    if MARKER not in markdown:
        return markdown
    return markdown.replace(MARKER, reference_markdown())
