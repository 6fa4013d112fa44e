"""``uvms-qp scenarios``: list the bundled scenarios, one line each, with their description.

Each name runs with ``uvms-qp run NAME --out DIR`` (and ``uvms-qp compare NAME --out DIR`` for
the schemes it names). The files are read, not run: the list is quick.
"""

from __future__ import annotations

import argparse
from typing import Any

from ._common import plain


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add the ``scenarios`` sub-command to the ``uvms-qp`` parser."""
    parser: argparse.ArgumentParser = subparsers.add_parser(
        "scenarios",
        help="list the bundled scenarios with a one-line description",
        description=plain(__doc__),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.set_defaults(func=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Print one line per bundled scenario: name, model and description."""
    from ..sim.config import read_toml
    from ..sim.scenario import bundled_scenarios, resolve_scenario

    rows = []
    for name in bundled_scenarios():
        data = read_toml(resolve_scenario(name))
        model = data.get("model")
        model_text = model if isinstance(model, str) else "[model] table"
        rows.append((name, str(model_text), str(data.get("description", "")).strip()))
    headers = ("scenario", "model", "description")
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers[:-1])]
    for row in (headers, *rows):
        cells = [cell.ljust(w) for cell, w in zip(row[:-1], widths, strict=True)]
        print("  ".join([*cells, row[-1]]).rstrip())
    return 0
