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


class ScenarioWarning(UserWarning):
    """A scenario loads and runs, but likely not as its author meant (the message says why).

    Filter it like any warning: ``warnings.simplefilter("ignore", ScenarioWarning)``; the
    command line prints it as one ``warning:`` line.
    """


class ParameterError(ConfigError):
    """A physical parameter of a plant is invalid (negative mass, indefinite matrix, bad shape).

    Attributes:
        path: Key path of the parameter, e.g. ``vehicle.added_mass`` or ``links.axis_b.mass``.
        reason: The problem, without the file and path.
        file: The parameter file it was read from, or None.
        value: The offending value (as given), or None.
    """

    def __init__(self, message: str, path: str = "", *, file: str | None = None,
                 value: Any = None) -> None:
        self.reason = message
        self.file = file
        self.value = value
        where = f"{path}: {message}" if path else message
        if file is not None:
            where = f"{file}: {where}"
        super().__init__(message, path)
        self.args = (where,)

    def __str__(self) -> str:
        return str(self.args[0])


class UnknownParameterSetError(UnknownNameError):
    """A bundled plant parameter set name does not exist."""

    def __init__(self, name: Any, known: Iterable[str]) -> None:
        super().__init__("plant parameter set", name, known)


class PlantDataError(ModelError, LookupError):
    """A model lacks what a dynamic plant needs (no parameter set, a joint without a link body).

    The message names what is missing and how to provide it.
    """


class SimulationDiverged(UvmsQpError, ArithmeticError):
    """A physics step produced a non-finite state or a velocity beyond the plant's sanity bound.

    Attributes:
        t: Time at the start of the failed step [s].
        q: Configuration at the start of the failed step.
        v: Generalized velocity at the start of the failed step.
        reason: What was found (which entry, its value, the bound).
    """

    def __init__(self, message: str, *, t: float, q: Any, v: Any, reason: str) -> None:
        self.t = t
        self.q = q
        self.v = v
        self.reason = reason
        super().__init__(message)
