"""Argument set-up shared by the scenario sub-commands (``run``, ``compare``)."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any


def scenario_command(
    subparsers: Any,
    name: str,
    *,
    help: str,
    description: str | None,
    func: Callable[[argparse.Namespace], int],
    quiet_help: str,
    options: Callable[[argparse.ArgumentParser], None] | None = None,
) -> argparse.ArgumentParser:
    """Add a sub-command that runs a scenario and writes into an output directory.

    Its arguments: the positional ``scenario`` (TOML file or bundled name), ``--out DIR``
    (required), the command's own ``options``, then ``--no-plots`` and ``--quiet``.

    Args:
        subparsers: The ``uvms-qp`` sub-parsers.
        name: Sub-command name.
        help: One-line help in the command list.
        description: Full description (the module docstring), shown verbatim.
        func: Handler stored as ``args.func``.
        quiet_help: Help of ``--quiet`` (what the command stops printing).
        options: Adds the command's own arguments.

    Returns:
        The sub-command parser.
    """
    parser: argparse.ArgumentParser = subparsers.add_parser(
        name,
        help=help,
        description=description,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("scenario", help="scenario file (.toml) or bundled scenario name")
    parser.add_argument("--out", required=True, help="output directory")
    if options is not None:
        options(parser)
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    parser.add_argument("--quiet", action="store_true", help=quiet_help)
    parser.set_defaults(func=func)
    return parser
