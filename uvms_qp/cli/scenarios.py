"""``uvms-qp scenarios``: list the bundled scenarios with their model and description.

Each name runs with ``uvms-qp run NAME --out DIR`` (and ``uvms-qp compare NAME --out DIR`` for
the schemes it names). The files are read, not run: the list is quick. On a terminal a long
description wraps to the terminal's width; in a pipe each scenario is one line.
"""

from __future__ import annotations

import argparse
from typing import Any

from ._common import plain, print_table


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
    """Print a row per bundled scenario: name, model and description."""
    from ..sim.config import read_toml
    from ..sim.scenario import bundled_scenarios, resolve_scenario

    rows = []
    for name in bundled_scenarios():
        data = read_toml(resolve_scenario(name))
        model = data.get("model")
        model_text = model if isinstance(model, str) else "[model] table"
        rows.append((name, str(model_text), str(data.get("description", "")).strip()))
    print_table(("scenario", "model", "description"), rows)
    return 0
