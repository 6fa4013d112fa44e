"""Shared by the sub-commands: plain help texts, tables, model files, the output folder."""

from __future__ import annotations

import argparse
import os
import re
import shutil
import sys
import tempfile
import textwrap
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..errors import ConfigError

_ROLE = re.compile(r":[a-z]+:`~?(?:[\w.]*\.)?([^`]+)`")


def plain(doc: str | None) -> str:
    """A docstring as plain text for ``--help``: no ``literal`` markup, roles or ``::``."""
    text = _ROLE.sub(r"\1", doc or "")
    text = text.replace("``", "")
    return re.sub(r"::$", ":", text, flags=re.MULTILINE)


def print_warnings(lines: Sequence[str]) -> None:
    """Print each line as a ``warning:`` line on stderr (what a run reports but does not refuse)."""
    for line in lines:
        print(f"warning: {line}", file=sys.stderr)


def run_warnings(result: Any) -> list[str]:
    """What a run reports but does not refuse: non-finite commands, a payload beyond the rating."""
    from ..sim.dynamic_metrics import rating_notes  # the plant's metrics load only when used

    nan = [f"{result.nan_steps} steps produced a non-finite command"] if result.nan_steps else []
    return nan + rating_notes(result.metrics(), result.plant_settings)


def print_table(headers: Sequence[str], rows: Sequence[Sequence[str]]) -> None:
    """Print left-aligned columns, one row per line.

    On a terminal the last column wraps onto indented lines to fit the terminal's width (at least
    20 characters of it per line); in a pipe or a file every row stays on one line.
    """
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(headers[:-1])]
    indent = sum(widths) + 2 * len(widths)
    room = None
    if sys.stdout.isatty():
        room = max(20, shutil.get_terminal_size().columns - 1 - indent)
    for row in (headers, *rows):
        cells = "".join(cell.ljust(w + 2) for cell, w in zip(row[:-1], widths, strict=True))
        lines = [row[-1]]
        if room:
            lines = textwrap.wrap(row[-1], room, break_on_hyphens=False) or [""]
        print(f"{cells}{lines[0]}".rstrip())
        for line in lines[1:]:
            print(" " * indent + line)


def add_model_path(parser: argparse.ArgumentParser) -> None:
    """Add ``--model-path FILE`` (repeatable): model files whose models scenarios may name."""
    parser.add_argument(
        "--model-path", action="append", default=[], metavar="FILE",
        help="a model file (TOML, see docs/models.md) whose model scenarios can then name; "
             "repeat for several",
    )


def register_model_paths(args: argparse.Namespace) -> list[str]:
    """Register the models of ``args.model_path``; returns their names.

    Raises:
        ConfigError: an invalid model file, or two files naming the same model (``--model-path``).
    """
    from ..sim.model_file import register_model_file  # the model stack loads only when used

    names: list[str] = []
    for path in args.model_path:
        name = register_model_file(path, replace=True)
        if name in names:
            raise ConfigError(f"two model files name the model {name!r}", "--model-path")
        names.append(name)
    return names


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
    (required), the command's own ``options``, then ``--model-path``, ``--no-plots`` and
    ``--quiet``.

    Args:
        subparsers: The ``uvms-qp`` sub-parsers.
        name: Sub-command name.
        help: One-line help in the command list.
        description: Full description (the module docstring), shown as plain text.
        func: Handler stored as ``args.func``.
        quiet_help: Help of ``--quiet`` (what the command stops printing).
        options: Adds the command's own arguments.

    Returns:
        The sub-command parser.
    """
    parser: argparse.ArgumentParser = subparsers.add_parser(
        name,
        help=help,
        description=plain(description),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("scenario", help="scenario file (.toml) or bundled scenario name "
                                         "(uvms-qp scenarios lists them)")
    parser.add_argument("--out", required=True, help="output directory")
    if options is not None:
        options(parser)
    add_model_path(parser)
    parser.add_argument("--no-plots", action="store_true", help="skip the PNG figures")
    parser.add_argument("--quiet", action="store_true", help=quiet_help)
    parser.set_defaults(func=func)
    return parser


def _out_error(exc: OSError, out: str) -> ConfigError:
    """``exc`` as the one-line ``--out: <reason>`` error of the CLI."""
    path = Path(out)
    if path.exists() and not path.is_dir():
        reason = f"{out!r} exists and is not a directory"
    else:
        where = exc.filename if exc.filename is not None else out
        reason = f"cannot create or write {str(where)!r}: {exc.strerror or exc}"
    return ConfigError(reason, "--out")


def prepare_output(out: str) -> Path:
    """Create the output directory ``out`` and check that a file can be written into it.

    Called before the simulation, so an unusable ``--out`` fails at once with a one-line message
    instead of after a long run.

    Raises:
        ConfigError: ``out`` is a file, cannot be created, or is not writable (path ``--out``).
    """
    directory = Path(out)
    try:
        directory.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=directory):
            pass
    except OSError as exc:
        raise _out_error(exc, out) from None
    return directory


@contextmanager
def writing_output(out: str) -> Iterator[None]:
    """Report an OS error while writing the outputs into ``out`` as the ``--out`` error."""
    try:
        yield
    except OSError as exc:
        raise _out_error(exc, out) from None


@contextmanager
def output_directory(out: str) -> Iterator[Path]:
    """:func:`prepare_output` around a run, undone if the run fails before writing anything.

    Yields:
        The output directory; removed again when this call created it and the body raised
        while it is still empty.
    """
    existed = os.path.isdir(out)
    directory = prepare_output(out)
    try:
        yield directory
    except BaseException:
        if not existed and not any(directory.iterdir()):
            directory.rmdir()
        raise
