"""``python -m bench.plants NAME [DURATION_S]``: the Markdown table of every case of a family."""

from __future__ import annotations

import sys

from bench.plants.engine import report_table
from bench.plants.registry import specs


def main(argv: list[str]) -> int:
    known = specs()
    if not argv or argv[0] not in known:
        print(f"usage: python -m bench.plants NAME [DURATION_S]; NAME one of {', '.join(known)}", file=sys.stderr)
        return 2
    try:
        duration_s = float(argv[1]) if len(argv) > 1 else 100.0
    except ValueError:
        print(f"duration {argv[1]!r} is not a number of seconds; give e.g. 100", file=sys.stderr)
        return 2
    if known[argv[0]].custom_record is not None:
        print(f"family {argv[0]} records its cases itself and has no table; pick another", file=sys.stderr)
        return 2
    print(report_table(known[argv[0]], duration_s))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
