"""Input validation helpers shared by every public boundary.

They convert inputs to float64 numpy arrays and raise the library's own errors with a message that
names the culprit (the argument name passed by the caller).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .errors import BoundsError, InputError, NonFiniteError, ShapeError, UnknownNameError

FloatArray = NDArray[np.float64]


_KIND_NAMES = {"b": "booleans", "c": "complex numbers", "U": "strings", "S": "bytes",
               "M": "dates", "m": "time spans", "V": "records"}


def _holds_bool(value: Any) -> bool:
    """True when a (nested) list or tuple holds a boolean (numpy would read it as 0 or 1)."""
    if isinstance(value, bool | np.bool_):
        return True
    if isinstance(value, list | tuple):
        return any(_holds_bool(v) for v in value)
    return False


_F64 = np.dtype(np.float64)


def as_array(value: Any, name: str) -> FloatArray:
    """``value`` as a float64 array of any shape, accepting only real numbers.

    Booleans, complex numbers, strings and other objects are rejected instead of converted
    (numpy would read ``True`` as 1, ``"2"`` as 2 and drop an imaginary part). An input that is
    already a float64 array is returned as is (not copied).

    Raises:
        InputError: not an array of real numbers (ragged nesting, strings, booleans, complex).
    """
    if type(value) is np.ndarray:  # the common case: no scan needed
        dtype = value.dtype
        if dtype is _F64:
            return value
        if dtype.kind in "fiu":
            return value.astype(np.float64, copy=False)
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nesting
        raise InputError(f"{name}: expected numbers, got {type(value).__name__}") from exc
    kind = array.dtype.kind
    if kind == "O":
        flat = array.reshape(-1).tolist()
        if not all(isinstance(v, numbers.Real) and not isinstance(v, bool | np.bool_)
                   for v in flat):
            bad = next(v for v in flat if not isinstance(v, numbers.Real)
                       or isinstance(v, bool | np.bool_))
            raise InputError(f"{name}: expected real numbers, got {type(bad).__name__} {bad!r}")
    elif kind not in "fiu":
        raise InputError(f"{name}: expected real numbers, got "
                         f"{_KIND_NAMES.get(kind, array.dtype.name)}")
    elif _holds_bool(value):
        raise InputError(f"{name}: expected real numbers, got a boolean")
    try:
        return array.astype(np.float64, copy=False)
    except (TypeError, ValueError, OverflowError) as exc:
        raise InputError(f"{name}: expected real numbers ({exc})") from exc


def _check_finite(array: FloatArray, name: str, allow_inf: bool) -> None:
    square = float(np.vdot(array, array))  # NaN exactly when an entry is; inf when one is (or
    # an overflow, which the entry-by-entry test below clears); vdot sets no warning
    if square == square and (allow_inf or square != math.inf):
        return
    if allow_inf:
        bad = np.isnan(array)
        what = "NaN"
    else:
        bad = ~np.isfinite(array)
        what = "NaN or inf"
    if bad.any():
        index = tuple(int(i) for i in np.argwhere(bad)[0])
        where = index[0] if len(index) == 1 else index
        raise NonFiniteError(f"{name} contains {what} (first at index {where})")


def as_vector(
    value: Any, name: str, size: int | None = None, *, allow_inf: bool = False,
    positive: bool = False,
) -> FloatArray:
    """Return ``value`` as a finite 1-D float64 array, optionally of a given length.

    Args:
        value: Array-like input (a scalar is accepted only when ``size`` is 1 or None).
        name: Argument name used in error messages.
        size: Required length, or None for any.
        allow_inf: Accept +/-inf (for bounds); NaN is always rejected.
        positive: Require every entry > 0 (weights, metrics).

    Raises:
        ShapeError: wrong number of dimensions or wrong length.
        NonFiniteError: NaN (or inf when not allowed).
        InputError: an entry <= 0 with ``positive``.
    """
    array = as_array(value, name)
    if array.ndim == 0:
        array = array.reshape(1)
    if array.ndim != 1:
        raise ShapeError(f"{name}: expected a 1-D array, got shape {array.shape}")
    if size is not None and array.shape[0] != size:
        raise ShapeError(f"{name}: expected length {size}, got {array.shape[0]}")
    _check_finite(array, name, allow_inf)
    if positive and array.size and not array.min() > 0.0:
        raise InputError(f"{name}: expected positive entries, got min {array.min():g}")
    return array


def as_matrix(
    value: Any,
    name: str,
    rows: int | None = None,
    cols: int | None = None,
    *,
    allow_inf: bool = False,
) -> FloatArray:
    """Return ``value`` as a finite 2-D float64 array with optional row/column counts.

    Raises:
        ShapeError: not 2-D or wrong row/column count.
        NonFiniteError: NaN or inf entries.
    """
    array = as_array(value, name)
    if array.ndim != 2:
        raise ShapeError(f"{name}: expected a 2-D array, got shape {array.shape}")
    if rows is not None and array.shape[0] != rows:
        raise ShapeError(f"{name}: expected {rows} rows, got {array.shape[0]}")
    if cols is not None and array.shape[1] != cols:
        raise ShapeError(f"{name}: expected {cols} columns, got {array.shape[1]}")
    _check_finite(array, name, allow_inf)
    return array


def as_scalar(
    value: Any,
    name: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
    allow_inf: bool = False,
) -> float:
    """Return ``value`` as a finite float, optionally checking its sign.

    Raises:
        InputError: not a real number, or sign requirement violated.
        NonFiniteError: NaN (or inf when not allowed).
    """
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{name}: expected a number, got {type(value).__name__}")
    number = float(value)
    if math.isnan(number) or (math.isinf(number) and not allow_inf):
        raise NonFiniteError(f"{name}: expected a finite number, got {number}")
    if positive and not number > 0.0:
        raise InputError(f"{name}: expected a positive number, got {number}")
    if nonnegative and number < 0.0:
        raise InputError(f"{name}: expected a non-negative number, got {number}")
    return number


def as_time(t: Any) -> float:
    """A time ``t`` [s] as a finite float (a real number; not a boolean, string or None).

    Raises:
        InputError: not a real number.
        NonFiniteError: NaN or inf.
    """
    if type(t) is float and t - t == 0.0:  # the common case: finite (NaN and inf give NaN)
        return t
    return as_scalar(t, "t")


def check_bounds_order(lower: FloatArray, upper: FloatArray, name: str) -> None:
    """Raise :class:`BoundsError` if any ``lower[i] > upper[i]``."""
    bad = np.flatnonzero(lower > upper)
    if bad.size:
        i = int(bad[0])
        raise BoundsError(
            f"{name}: lower > upper at index {i} ({lower[i]:.6g} > {upper[i]:.6g})"
        )


def check_name(name: Any, known: Iterable[str], kind: str) -> str:
    """Return ``name`` if it is one of ``known``; otherwise raise :class:`UnknownNameError`."""
    known = tuple(known)
    if not isinstance(name, str) or name not in known:
        raise UnknownNameError(kind, name, known)
    return name
