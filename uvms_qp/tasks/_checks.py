"""Validators shared by the task classes, and the shape tests of :meth:`~uvms_qp.tasks.Task.fill`.

One validator per parameter kind: names, frame names, flags, gains, barrier gains.
"""

from __future__ import annotations

import inspect
from functools import cache
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError


def check_task_name(name: Any, default: str) -> str:
    """Return a valid task name (non-empty string without surrounding spaces)."""
    if name is None:
        return default
    if not isinstance(name, str) or not name.strip() or name != name.strip():
        raise InputError(
            f"name: expected a non-empty string without surrounding spaces, got {name!r}")
    return name


def check_frame_name(value: Any, label: str) -> str:
    """A frame name as given (checked against the model at bind): a non-empty string."""
    if not isinstance(value, str) or not value:
        raise InputError(f"{label}: expected a frame name, got {value!r}")
    return value


def check_flag(value: Any, label: str) -> bool:
    """A boolean parameter (``true`` or ``false`` in a scenario file)."""
    if not isinstance(value, bool):
        raise InputError(f"{label}: expected true or false")
    return value


def as_gain(value: Any, name: str = "gain") -> float | FloatArray:
    """Validate a gain [1/s]: a positive number or a list of positive numbers (one per row)."""
    if isinstance(value, list | tuple | np.ndarray):
        gains = as_vector(value, name)
        if np.any(gains < 0.0):
            raise InputError(f"{name}: expected non-negative gains, got {gains.tolist()}")
        return gains
    return as_scalar(value, name, nonnegative=True)


def check_barrier_gain(gain: float, dt: float, name: str, row: str) -> None:
    """Refuse a set-based row whose gain overshoots at period ``dt``: ``gain * dt > 1``.

    The row ``h_dot >= gain (h_min - h)`` (or its mirror) holds the distance to the bound
    ``d = h - h_min`` at ``d_{k+1} = (1 - gain dt) d_k`` while it binds: monotone for
    ``gain dt <= 1``, alternating around the bound (the row switching on and off every tick)
    above, divergent from 2.

    Raises:
        InputError: ``gain * dt > 1`` (the message gives the largest gain for this period).
    """
    if gain * dt > 1.0 + 1e-12:
        raise InputError(
            f"{name}: gain * dt = {gain:g} * {dt:g} = {gain * dt:.4g} > 1: the {row} would "
            f"overshoot its bound and switch on and off every tick (the distance to the bound "
            f"evolves as d_(k+1) = (1 - gain dt) d_k while the row binds); use gain <= "
            f"{1.0 / dt:.6g} [1/s] = 1 / dt")


def fits(side: Any, rows: int) -> bool:
    """True for a side of ``rows`` values or one value (a number, or an array of shape ())."""
    shape = getattr(side, "shape", None)
    if shape is not None:
        return bool(shape == (rows,) or shape == ())
    if isinstance(side, int | float):
        return True
    try:
        return len(side) == rows
    except TypeError:
        return False


def shape_of(value: Any) -> str:
    """``(r, c)`` of an array, ``None``, or the type of anything else (for error messages)."""
    if value is None:
        return "None"
    shape = getattr(value, "shape", None)
    if shape is None:
        try:
            shape = np.shape(value)
        except (ValueError, TypeError):
            return type(value).__name__
    return str(tuple(shape))


@cache
def constructor_keywords(cls: type) -> frozenset[str] | None:
    """The keyword arguments ``cls(...)`` accepts, or None when it takes any (``**kwargs``)."""
    parameters = inspect.signature(cls.__init__).parameters.values()  # type: ignore[misc]
    if any(p.kind is p.VAR_KEYWORD for p in parameters):
        return None
    return frozenset(p.name for p in parameters
                     if p.name != "self" and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD))
