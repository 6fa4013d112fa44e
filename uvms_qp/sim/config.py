"""Strict reading of TOML tables into typed values and objects, with field paths in every error.

Two tools used by the scenario loader (:mod:`uvms_qp.sim.scenario`):

- :class:`Table` wraps one TOML table and its path (``levels[1].tasks[0]``); each ``take_*``
  method reads, type-checks and range-checks one key, and :meth:`Table.finish` rejects any key that
  was not read (unknown keys are errors, with the list of known ones). A missing required key is
  reported only after the table's unknown keys, so a misspelt required key (``durration``) is
  named as the unknown key it is.
- :func:`construct` builds an object (task, constraint, trajectory) from a table by introspecting
  its class's keyword constructor: keys must be constructor parameters, values are checked against
  the simple type hints (``float``, ``int``, ``str``, ``bool``, ``list[float]``, ``Literal[...]``,
  ``X | None``), required parameters must be present, and errors raised by the constructor itself
  (:class:`~uvms_qp.errors.InputError` and friends) come back as :class:`ConfigError` carrying the
  field path, e.g. ``levels[1].tasks[0].gain: expected a positive number, got -1.0``.

Every error is a :class:`~uvms_qp.errors.ConfigError` whose ``path`` names the field.
"""

from __future__ import annotations

import difflib
import inspect
import math
import re
import tomllib
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal

from ..errors import ConfigError, UnknownNameError, UvmsQpError

#: Hook that may turn a raw TOML value into an object for a parameter; returns ``_NOT_HANDLED``
#: to fall back to the generic type check. Called as ``resolver(name, hint, value, path)``.
Resolver = Callable[[str, Any, Any, str], Any]


class _NotHandled:
    def __repr__(self) -> str:
        return "NOT_HANDLED"


NOT_HANDLED: Any = _NotHandled()


#: Largest scenario or model file read [bytes]; a larger file is rejected before it is parsed.
MAX_FILE_BYTES = 4 * 1024 * 1024
#: Deepest nesting of arrays and tables in a file (the top-level table is depth 0).
MAX_DEPTH = 32


def read_toml(path: str | Path, what: str = "scenario file") -> dict[str, Any]:
    """Parse a TOML file of at most :data:`MAX_FILE_BYTES` nested at most :data:`MAX_DEPTH` deep.

    Args:
        path: The file.
        what: What the file is, for messages (``"scenario file"``, ``"model file"``).

    Raises:
        ConfigError: the file cannot be read, is too large, is not valid UTF-8 TOML (message with
            line and column) or nests arrays and tables too deeply.
    """
    file = Path(path)
    try:
        with file.open("rb") as handle:
            raw = handle.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError as exc:
        raise ConfigError(f"{what} not found: {file}") from exc
    except OSError as exc:
        raise ConfigError(f"cannot read {what} {file}: {exc.strerror or exc}") from exc
    if len(raw) > MAX_FILE_BYTES:
        raise ConfigError(f"{file}: larger than {MAX_FILE_BYTES // (1024 * 1024)} MiB; "
                          f"a {what} is at most {MAX_FILE_BYTES} bytes")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(f"{file}: not UTF-8 text (byte {exc.start}): TOML files are UTF-8"
                          ) from exc
    too_deep = ConfigError(f"{file}: arrays and tables nested more than {MAX_DEPTH} deep")
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{file}: malformed TOML: {exc}") from exc
    except RecursionError:  # the parser recurses once per nesting level
        raise too_deep from None
    if _depth(data) > MAX_DEPTH:
        raise too_deep
    return data


def _depth(value: Any) -> int:
    """Nesting depth of parsed TOML (the top-level table is 0, ``a = [1]`` is 1), no recursion."""
    deepest = 0
    pending: list[tuple[Any, int]] = [(value, 0)]
    while pending:
        node, depth = pending.pop()
        if isinstance(node, dict | list):
            deepest = max(deepest, depth)
        if isinstance(node, dict):
            pending.extend((child, depth + 1) for child in node.values())
        elif isinstance(node, list):
            pending.extend((child, depth + 1) for child in node)
    return deepest


def did_you_mean(key: str, known: Sequence[str]) -> str:
    """``"; did you mean 'gain'?"`` when a known name is close to ``key``, else ``""``."""
    close = difflib.get_close_matches(key, list(known), n=1, cutoff=0.75)
    return f"; did you mean {close[0]!r}?" if close else ""


def join(path: str, key: str | int) -> str:
    """Append a key (``.key``) or an index (``[i]``) to a field path."""
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def describe(value: Any) -> str:
    """Name the TOML type of a value for error messages."""
    if isinstance(value, bool):
        return "a boolean"
    if isinstance(value, int):
        return "an integer"
    if isinstance(value, float):
        return "a float"
    if isinstance(value, str):
        return "a string"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def is_number(value: Any) -> bool:
    """True for TOML integers and floats (not booleans)."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def check_number(
    value: Any,
    path: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    integer: bool = False,
    minimum: float | None = None,
    maximum: float | None = None,
) -> float:
    """Check a TOML number and its range; return it as float (or int when ``integer``).

    Raises:
        ConfigError: not a number, not finite, or out of range.
    """
    kind = "integer" if integer else "number"
    what = (
        f"a positive {kind}" if positive
        else f"a non-negative {kind}" if nonnegative
        else ("an integer" if integer else "a number")
    )
    if not is_number(value) or (integer and not isinstance(value, int)):
        raise ConfigError(f"expected {what}, got {describe(value)}", path)
    if not math.isfinite(value):
        raise ConfigError(f"expected a finite number, got {value}", path)
    if (positive and not value > 0) or (nonnegative and value < 0):
        raise ConfigError(f"expected {what}, got {value}", path)
    if minimum is not None and value < minimum:
        raise ConfigError(f"expected a value >= {minimum:g}, got {value}", path)
    if maximum is not None and value > maximum:
        raise ConfigError(f"expected a value <= {maximum:g}, got {value}", path)
    return int(value) if integer else float(value)


def check_numbers(value: Any, path: str, size: int | None = None) -> list[float]:
    """Check an array of finite numbers, optionally of a given length."""
    if not isinstance(value, list):
        raise ConfigError(f"expected an array of numbers, got {describe(value)}", path)
    if size is not None and len(value) != size:
        raise ConfigError(f"expected {size} numbers, got {len(value)}", path)
    return [check_number(v, join(path, i)) for i, v in enumerate(value)]


class Table:
    """A TOML table being read, with its field path; every key must be read exactly once.

    Args:
        data: The parsed table.
        path: Its field path (``""`` for the top level).
        keys: Every key the table may hold, when the reader knows them up front; a missing
            required key is then reported after any key not in this list. Without it, a key
            close to the missing one (a misspelling) is reported instead.
    """

    def __init__(self, data: Any, path: str, keys: Sequence[str] | None = None) -> None:
        if not isinstance(data, dict):
            raise ConfigError(f"expected a table, got {describe(data)}", path)
        self.data: dict[str, Any] = data
        self.path = path
        self.keys = None if keys is None else tuple(keys)
        self._read: set[str] = set()

    def at(self, key: str) -> str:
        """Field path of ``key`` in this table."""
        return join(self.path, key)

    def has(self, key: str) -> bool:
        """True when the key is present."""
        return key in self.data

    def raw(self, key: str, default: Any = None, *, required: bool = False) -> Any:
        """Return the raw value of ``key`` (marking it read), or ``default`` when absent."""
        self._read.add(key)
        if key not in self.data:
            if required:
                self._check_unknown_before_missing(key)
                raise ConfigError(f"missing required field {key!r}", self.path or key)
            return default
        return self.data[key]

    def _check_unknown_before_missing(self, missing: str) -> None:
        """Raise on an unknown key before ``missing`` is reported as absent.

        With declared :attr:`keys`, any key outside them is unknown; otherwise only an unread key
        that looks like a misspelling of ``missing`` (``difflib`` ratio >= 0.75) is, since the
        table's other keys may still be read later.

        Raises:
            ConfigError: at the unknown key, suggesting ``missing`` when it is close.
        """
        if self.keys is not None:
            unknown = [k for k in self.data if k not in self.keys]
        else:
            unread = [k for k in self.data if k not in self._read]
            unknown = difflib.get_close_matches(missing, unread, n=1, cutoff=0.75)
        if not unknown:
            return
        key = unknown[0]
        close = difflib.get_close_matches(key, [missing], n=1, cutoff=0.75)
        hint = f" (did you mean {missing!r}?)" if close else ""
        known = "" if self.keys is None else f"; known keys: {', '.join(sorted(self.keys))}"
        raise ConfigError(f"unknown key {key!r}{hint}{known}", self.at(key))

    def take_number(
        self, key: str, default: float | None = None, *, required: bool = False, **checks: Any
    ) -> float | None:
        """Read a number with optional range checks (see :func:`check_number`)."""
        value = self.raw(key, required=required)
        if value is None:
            return default
        return check_number(value, self.at(key), **checks)

    def take_str(
        self,
        key: str,
        default: str | None = None,
        *,
        required: bool = False,
        choices: Sequence[str] | None = None,
    ) -> str | None:
        """Read a string, optionally one of ``choices``."""
        value = self.raw(key, required=required)
        if value is None:
            return default
        if not isinstance(value, str):
            raise ConfigError(f"expected a string, got {describe(value)}", self.at(key))
        if choices is not None and value not in choices:
            listing = ", ".join(repr(c) for c in choices)
            raise ConfigError(f"expected one of {listing}, got {value!r}", self.at(key))
        return value

    def take_bool(self, key: str, default: bool = False) -> bool:
        """Read a boolean (TOML ``true``/``false``; numbers and strings are errors)."""
        value = self.raw(key)
        if value is None:
            return default
        if not isinstance(value, bool):
            raise ConfigError(f"expected a boolean, got {describe(value)}", self.at(key))
        return value

    def take_numbers(
        self, key: str, default: list[float] | None = None, *, size: int | None = None,
        required: bool = False,
    ) -> list[float] | None:
        """Read an array of numbers, optionally of a given length."""
        value = self.raw(key, required=required)
        if value is None:
            return default
        return check_numbers(value, self.at(key), size)

    def take_strs(self, key: str, default: list[str] | None = None) -> list[str] | None:
        """Read an array of strings."""
        value = self.raw(key)
        if value is None:
            return default
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ConfigError(f"expected an array of strings, got {describe(value)}", self.at(key))
        return list(value)

    def take_table(
        self, key: str, *, required: bool = False, keys: Sequence[str] | None = None
    ) -> Table | None:
        """Read a sub-table (``keys``: its possible keys, see :class:`Table`)."""
        value = self.raw(key, required=required)
        if value is None:
            return None
        return Table(value, self.at(key), keys)

    def take_tables(
        self, key: str, *, required: bool = False, keys: Sequence[str] | None = None
    ) -> list[Table]:
        """Read an array of tables (``[[key]]``; ``keys``: their possible keys)."""
        value = self.raw(key, required=required)
        if value is None:
            return []
        if not isinstance(value, list):
            raise ConfigError(f"expected an array of tables, got {describe(value)}", self.at(key))
        return [Table(item, join(self.at(key), i), keys) for i, item in enumerate(value)]

    def finish(self) -> None:
        """Raise on any key that was not read: unknown keys are errors.

        Raises:
            ConfigError: with the path of the first unknown key and the known keys.
        """
        unknown = [key for key in self.data if key not in self._read]
        if unknown:
            names = sorted(self._read.union(self.keys or ()))
            known = ", ".join(names) or "(none)"
            hint = did_you_mean(unknown[0], names)
            message = f"unknown key {unknown[0]!r}; known keys: {known}{hint}"
            raise ConfigError(message, self.at(unknown[0]))


# ----------------------------------------------------------------------------------------------
# Introspective construction


def keyword_parameters(cls: type) -> dict[str, inspect.Parameter]:
    """Return the parameters of ``cls``'s constructor that a scenario may set by keyword."""
    signature = inspect.signature(cls)
    return {
        name: p
        for name, p in signature.parameters.items()
        if p.kind in (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    }


def parameter_hints(cls: type) -> dict[str, Any]:
    """Resolved type hints of ``cls``'s constructor parameters (unresolvable ones are omitted)."""
    init = vars(cls).get("__init__") or next(
        vars(base)["__init__"] for base in cls.__mro__ if "__init__" in vars(base)
    )
    try:
        return typing.get_type_hints(init)
    except Exception:  # a forward reference that cannot be resolved: go one by one
        pass
    hints: dict[str, Any] = {}
    module = inspect.getmodule(init)
    namespace = dict(vars(module)) if module is not None else {}
    for name, annotation in getattr(init, "__annotations__", {}).items():
        if not isinstance(annotation, str):
            hints[name] = annotation
            continue
        try:
            hints[name] = eval(annotation, namespace)  # annotations of the library's own classes
        except Exception:  # leave this parameter unchecked
            continue
    return hints


def _union_members(hint: Any) -> tuple[Any, ...] | None:
    origin = typing.get_origin(hint)
    if origin is typing.Union or origin is types.UnionType:
        return typing.get_args(hint)
    return None


def convert(value: Any, hint: Any, path: str) -> Any:
    """Check a TOML value against a simple type hint and return it converted.

    Understood hints: ``float``, ``int``, ``str``, ``bool``, ``list[float]`` / ``Sequence[float]``
    / ``tuple[float, ...]`` (and of ``str``/``int``), nested sequences, ``Literal[...]``,
    ``X | None`` and other unions. Anything else is passed through for the constructor to check.

    Raises:
        ConfigError: the value does not match the hint.
    """
    if hint is Any or hint is inspect.Parameter.empty:
        return value
    members = _union_members(hint)
    if members is not None:
        errors: list[ConfigError] = []
        for member in (m for m in members if m is not type(None)):
            try:
                return convert(value, member, path)
            except ConfigError as exc:
                errors.append(exc)
        if errors:
            raise errors[0]  # the first alternative's complaint, e.g. "expected a number"
        return value
    origin = typing.get_origin(hint)
    if origin is Literal:
        choices = typing.get_args(hint)
        if not any(type(value) is type(c) and value == c for c in choices):
            listing = ", ".join(repr(c) for c in choices)
            raise ConfigError(f"expected one of {listing}, got {value!r}", path)
        return value
    if hint is float:
        return check_number(value, path)
    if hint is int:
        return check_number(value, path, integer=True)
    if hint is bool:
        if not isinstance(value, bool):
            raise ConfigError(f"expected a boolean, got {describe(value)}", path)
        return value
    if hint is str:
        if not isinstance(value, str):
            raise ConfigError(f"expected a string, got {describe(value)}", path)
        return value
    if origin in (list, tuple, Sequence):
        args = [a for a in typing.get_args(hint) if a is not Ellipsis]
        if not isinstance(value, list):
            item = _name_of(args[0]) if args else "values"
            raise ConfigError(f"expected an array of {item}, got {describe(value)}", path)
        if not args:
            return list(value)
        item_hint = args[0]
        return [convert(v, item_hint, join(path, i)) for i, v in enumerate(value)]
    if origin in (dict, Mapping) and not isinstance(value, dict):
        raise ConfigError(f"expected a table, got {describe(value)}", path)
    return value


def _name_of(hint: Any) -> str:
    if hint is float:
        return "numbers"
    if hint is int:
        return "integers"
    if hint is str:
        return "strings"
    if hint is bool:
        return "booleans"
    return "values"


_LEADING_NAME = re.compile(
    r"^(?:[^\s:]+\.)?([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)\s*:\s*(.*)$", re.DOTALL
)


def config_error_from(
    exc: Exception,
    path: str,
    parameters: Sequence[str] = (),
    values: Mapping[str, Any] | None = None,
) -> ConfigError:
    """Turn an error raised while building an object into a :class:`ConfigError` at ``path``.

    A message that starts with one of the constructor's parameter names, possibly prefixed by the
    object's name (``"gain: expected a positive number"``, ``"tool.gain: ..."``), is moved into the
    path (``levels[0].tasks[1].gain: expected ...``). An unknown frame/joint name is attributed to
    the field in ``values`` that holds it (``levels[0].tasks[0].frame: unknown frame 'ee2'; ...``).
    """
    message = str(exc)
    if isinstance(exc, UnknownNameError) and values:
        for key, value in values.items():
            if isinstance(value, str) and value == exc.name:
                return ConfigError(message, join(path, key))
            if isinstance(value, list) and exc.name in value:
                return ConfigError(message, join(join(path, key), value.index(exc.name)))
    match = _LEADING_NAME.match(message)
    if match and match.group(1) in parameters:
        return ConfigError(match.group(3), join(path, match.group(1)) + match.group(2))
    return ConfigError(message, path)


def keyword_arguments(
    cls: type,
    table: Table,
    *,
    skip: Sequence[str] = ("type",),
    exclude: Sequence[str] = (),
    resolver: Resolver | None = None,
    kind: str = "",
    label: str = "",
) -> dict[str, Any]:
    """Read a TOML table as the keyword arguments of ``cls``'s constructor, checked by type.

    Args:
        cls: Class whose keyword constructor (with simple type hints) the table describes.
        table: The table; keys in ``skip`` are read by the caller and ignored here.
        skip: Keys not passed to the constructor.
        exclude: Constructor parameters a table may not set.
        resolver: Optional hook turning raw values into objects (trajectory references, ...).
        kind: Word used in messages (``"task"``, ``"constraint"``).
        label: What the table describes in messages (default: the ``kind`` and ``type``, or the
            class name).

    Returns:
        The converted keyword arguments (values the constructor itself still validates).

    Raises:
        ConfigError: unknown key (known ones listed, a close one suggested), missing required
            parameter or value of the wrong type, with the field path.
    """
    parameters = {k: p for k, p in keyword_parameters(cls).items() if k not in exclude}
    hints = parameter_hints(cls)
    kwargs: dict[str, Any] = {}
    for key in skip:
        table.raw(key)
    for key, value in table.data.items():
        if key in skip:
            continue
        if key not in parameters:
            known = ", ".join([*skip, *parameters])
            what = label or (f"{kind} type {table.data.get('type')!r}" if kind else cls.__name__)
            hint = did_you_mean(key, list(parameters))
            message = f"unknown key {key!r} for {what}; known keys: {known}{hint}"
            raise ConfigError(message, table.at(key))
        table.raw(key)
        hint = hints.get(key, inspect.Parameter.empty)
        converted = NOT_HANDLED
        if resolver is not None:
            converted = resolver(key, hint, value, table.at(key))
        if converted is NOT_HANDLED:
            converted = convert(value, hint, table.at(key))
        kwargs[key] = converted
    missing = [
        name
        for name, p in parameters.items()
        if p.default is inspect.Parameter.empty and name not in kwargs
    ]
    if missing:
        raise ConfigError(f"missing required field {missing[0]!r}", table.path)
    table.finish()
    return kwargs


def instantiate(cls: type, kwargs: Mapping[str, Any], path: str) -> Any:
    """``cls(**kwargs)``, with the constructor's own errors as :class:`ConfigError` at ``path``.

    Raises:
        ConfigError: the constructor rejected a value; a message that starts with a parameter
            name moves it into the path (see :func:`config_error_from`).
    """
    try:
        return cls(**kwargs)
    except (UvmsQpError, ValueError, TypeError) as exc:
        raise config_error_from(exc, path, list(keyword_parameters(cls)), kwargs) from exc


def construct(
    cls: type,
    table: Table,
    *,
    skip: Sequence[str] = ("type",),
    resolver: Resolver | None = None,
    kind: str = "",
) -> Any:
    """Build ``cls(**kwargs)`` from a TOML table by introspecting its keyword constructor.

    :func:`keyword_arguments` then :func:`instantiate`.

    Raises:
        ConfigError: unknown key (known ones listed), missing required parameter, value of the
            wrong type, or any validation error raised by the constructor, with the field path.
    """
    kwargs = keyword_arguments(cls, table, skip=skip, resolver=resolver, kind=kind)
    return instantiate(cls, kwargs, table.path)
