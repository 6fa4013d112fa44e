"""The exception hierarchy of uvms-qp.

Every error raised at a public boundary derives from :class:`UvmsQpError`, so a caller can catch
the library's errors in one clause. Subclasses also derive from the matching builtin
(``ValueError``, ``LookupError``, ``FileNotFoundError``) so generic handlers keep working.

Messages name the culprit: the argument, frame, joint, task, solver or file path at fault, and, for
unknown names, the valid choices.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any


class UvmsQpError(Exception):
    """Base class of every error raised by uvms-qp."""


class InputError(UvmsQpError, ValueError):
    """An argument has the wrong shape, type or value."""


class ShapeError(InputError):
    """An array has the wrong number of dimensions or the wrong length."""


class NonFiniteError(InputError):
    """An array that must be finite holds NaN or inf."""


class BoundsError(InputError):
    """Lower and upper limits are inconsistent (lower > upper) or otherwise invalid."""


class ConfigError(InputError):
    """A scenario file or declarative stack is invalid.

    Attributes:
        path: Location of the offending field, e.g. ``levels[1].tasks[0].gain`` (may be empty).
    """

    def __init__(self, message: str, path: str = "") -> None:
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


class UnknownNameError(UvmsQpError, LookupError):
    """A name (frame, joint, model, task type, solver, ...) is not known.

    Attributes:
        kind: What was looked up (``"frame"``, ``"joint"``, ...).
        name: The unknown name.
        known: The valid names.
    """

    def __init__(self, kind: str, name: Any, known: Iterable[str], hint: str = "") -> None:
        self.kind = kind
        self.name = name
        self.known = tuple(known)
        listing = ", ".join(self.known) if self.known else "(none)"
        message = f"unknown {kind} {name!r}; known {kind}s: {listing}"
        if hint:
            message += f". {hint}"
        super().__init__(message)

    def __str__(self) -> str:  # LookupError would otherwise quote the message like a KeyError
        return str(self.args[0])


class UnknownFrameError(UnknownNameError):
    """A frame name is not part of the model."""

    def __init__(self, name: Any, known: Iterable[str]) -> None:
        super().__init__("frame", name, known)


class UnknownJointError(UnknownNameError):
    """A joint name is not part of the model."""

    def __init__(self, name: Any, known: Iterable[str]) -> None:
        super().__init__("joint", name, known)


class UnknownModelError(UnknownNameError):
    """A bundled model name does not exist."""

    def __init__(self, name: Any, known: Iterable[str]) -> None:
        super().__init__("model", name, known)


class UnknownSolverError(UnknownNameError):
    """A solver name is unknown or its back-end is not installed."""

    def __init__(self, name: Any, known: Iterable[str], hint: str = "") -> None:
        super().__init__("solver", name, known, hint)


class ModelError(UvmsQpError):
    """A robot description cannot be built (bad DH table, bad mount, inconsistent limits...)."""


class ModelFileError(ModelError, FileNotFoundError):
    """A robot description file is missing or cannot be parsed."""


class SolverError(UvmsQpError):
    """A back-end failed in a way the caller asked to hear about (strict mode).

    Attributes:
        result: The solver result object describing the failure, when one exists.
    """

    def __init__(self, message: str, result: Any = None) -> None:
        self.result = result
        super().__init__(message)


class NoSolutionFound(SolverError):
    """No verified solution could be produced; ``result`` keeps the failed problem."""
