"""The ``uvms-qp`` command line (also ``python -m uvms_qp`` and ``python -m uvms_qp.cli``).

Each sub-command lives in its own module of this package and exposes
``register(subparsers) -> argparse.ArgumentParser`` which sets ``func=run`` on its parser.
Adding a command is a one-file change: the modules are discovered at start-up. Any error of the
input (a scenario file, a model file, an option) is one line on stderr and exit status 2; a
scenario that loads but likely not as meant (:class:`~uvms_qp.errors.ScenarioWarning`) is one
``warning:`` line on stderr, and the command goes on.
"""

from __future__ import annotations

import argparse
import importlib
import os
import pkgutil
import sys
import warnings
from collections.abc import Sequence
from typing import Any, NoReturn

from .. import __version__
from ..errors import ScenarioWarning, UvmsQpError


class _Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line (the usage is one ``--help`` away)."""

    def error(self, message: str) -> NoReturn:
        """Print ``PROG: error: MESSAGE (see PROG --help)`` on stderr and exit with status 2."""
        self.exit(2, f"{self.prog}: error: {one_line(message)} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    """Return the top-level parser with every discovered sub-command registered."""
    parser = _Parser(
        prog="uvms-qp",
        description="Task-priority kinematic control for underwater vehicle-manipulator systems.",
    )
    parser.add_argument("--version", action="version", version=f"uvms-qp {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(__path__), key=lambda i: i.name):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        register = getattr(module, "register", None)
        if register is not None:
            register(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``uvms-qp`` console script; returns the process exit code.

    When the reader of stdout goes away (``uvms-qp solvers | head -1``), the command stops
    quietly with exit status 1, as the Python documentation advises for a closed pipe: the
    rest of stdout goes to the null device, so the interpreter's last flush does not fail.
    """
    try:
        try:
            return _main(argv)
        finally:
            sys.stdout.flush()
    except BrokenPipeError:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 1


def _main(argv: Sequence[str] | None) -> int:
    """Parse ``argv``, run its sub-command and return the exit code (input errors: 2)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always", ScenarioWarning)
            warnings.showwarning = _warning_line(args.command, warnings.showwarning)
            return int(args.func(args) or 0)
    except UvmsQpError as exc:
        print(f"uvms-qp {args.command}: error: {one_line(str(exc))}", file=sys.stderr)
        return 2


def _warning_line(command: str, show: Any) -> Any:
    """``warnings.showwarning`` that prints a :class:`ScenarioWarning` as one line on stderr."""

    def show_warning(message: Any, category: type[Warning], *args: Any, **kwargs: Any) -> None:
        if issubclass(category, ScenarioWarning):
            print(f"uvms-qp {command}: warning: {one_line(str(message))}", file=sys.stderr)
        else:
            show(message, category, *args, **kwargs)

    return show_warning


def one_line(message: str) -> str:
    """A message on one line: its non-empty lines joined with ``"; "``."""
    return "; ".join(line.strip() for line in message.splitlines() if line.strip())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
