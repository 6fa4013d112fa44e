"""The one validator: user-facing levels into the stacked :class:`~uvms_qp.hqp.problem.Problem`.

A level is a list of ``Rows`` objects, ``(A, b)`` equality pairs or ``(A, lo, hi)`` inequality
triples over x (A an array of shape (m, n)), or one such item alone; hard rows take the same
forms; the box is two vectors of length n (``-inf`` / ``+inf`` allowed). :class:`Validator`
copies every row and side into the buffers of a problem (reused while the structure
``(n, m_H, level sizes)`` repeats) and checks the whole stack with a few reductions
(:func:`sides_and_rows_ok`):

* no NaN side, no lower side ``+inf`` and no upper side ``-inf`` (e.g. an infinite equality
  target), no lower side above its upper side;
* no NaN or inf in a matrix;
* every finite number within the accepted magnitudes (below);
* the row weights are finite and positive.

Accepted magnitudes: every finite row entry, side and box bound is at most
:data:`MAX_MAGNITUDE` (1e15) in absolute value, every row weight and metric entry within
``[1 / MAX_MAGNITUDE, MAX_MAGNITUDE]``; zero entries and infinite sides are always accepted. The
back-ends read large finite numbers as infinite (HiGHS and Clarabel from 1e20, OSQP and PIQP from
1e30: a bound there is silently dropped, or the problem refused with text on the console) and the
cascade hands them sides shifted by rows times points, so given numbers stay five orders below
the smallest of those thresholds. Beyond about 1e154 the squares the back-ends form overflow and
their linear algebra (LAPACK fed inf or NaN) fails or never returns. A problem outside the range
is refused with an :class:`~uvms_qp.errors.InputError` naming the entry: scale it (other units, a
smaller gain). Tiny rows are accepted: whatever a back-end makes of them is measured like any
answer.

When the input is not in this common form or a check fails, the items are validated one by one,
which raises the error naming the culprit (``levels[1][0].A: expected 2 columns, got 3``); a
reduction that only looks out of range (the sum of many squared entries near the limit) passes
that second look and the problem is solved as filled.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from .._validation import FloatArray, as_array, as_vector, check_bounds_order
from ..errors import InputError, ShapeError
from ..rows import Rows
from .linalg import absolute as _ABS
from .linalg import concatenate as _concatenate
from .linalg import count_nonzero as _count
from .linalg import isfinite as _FINITE
from .linalg import max_of as _MAX
from .linalg import min_of as _MIN
from .linalg import vdot as _vdot
from .problem import Problem

_Item = tuple[FloatArray, FloatArray, FloatArray, FloatArray | None]
_Parsed = tuple[list[FloatArray], list[FloatArray], list[FloatArray], list[FloatArray | None],
                int, list[int]]
"""Rows, lower sides, upper sides and weights of every item (hard items first), the number of
hard items and the level sizes."""
_F64 = np.dtype(np.float64)
_ND = np.ndarray

MAX_MAGNITUDE = 1e15
"""Largest absolute value of a finite row entry, side or box bound; weights and metric entries
lie within ``[1 / MAX_MAGNITUDE, MAX_MAGNITUDE]`` (see the module docstring)."""
_MAX_SQUARE = MAX_MAGNITUDE * MAX_MAGNITUDE
_MIN_WEIGHT = 1.0 / MAX_MAGNITUDE


def check_magnitude(values: FloatArray, name: str, *, weights: bool = False) -> None:
    """Raise when a finite entry of ``values`` lies outside the accepted magnitudes.

    Args:
        values: A validated float array (NaN already refused; infinities are skipped).
        name: The argument named in the message, e.g. ``levels[0][1].A``.
        weights: Positive weights or a metric: entries must also be at least
            ``1 / MAX_MAGNITUDE``.

    Raises:
        InputError: naming the first entry out of range, its index and the accepted range.
    """
    size = np.abs(values)
    bad = np.isfinite(size) & (size > MAX_MAGNITUDE)
    if weights:
        bad |= size < _MIN_WEIGHT
    if not bad.any():
        return
    flat = int(np.flatnonzero(bad.reshape(-1))[0])
    index = np.unravel_index(flat, values.shape)
    where = int(index[0]) if len(index) == 1 else tuple(int(i) for i in index)
    accepted = (f"within [{_MIN_WEIGHT:g}, {MAX_MAGNITUDE:g}]" if weights
                else f"at most {MAX_MAGNITUDE:g} in magnitude")
    raise InputError(f"{name}: entry {values.reshape(-1)[flat]:.6g} at index {where} is out of "
                     f"range (accepted: {accepted}); scale the problem, e.g. other units")


def _float(value: Any) -> FloatArray:
    """``value`` as a float64 array of real numbers (no copy when it is one already).

    The parser tests for a float64 array itself and calls this for anything else.

    Raises:
        InputError: not real numbers (strings, booleans, complex numbers are not converted).
    """
    return as_array(value, "value")


def _bare_item(items: Any) -> bool:
    """True for a level (or the hard rows) given as one item instead of a list of items.

    A ``Rows``, or a tuple whose first entry is not itself an item (``(A, b)``, ``(A, lo, hi)``
    with ``A`` an array).
    """
    return isinstance(items, Rows) or (isinstance(items, tuple) and bool(items) and not isinstance(
        items[0], Rows | tuple | list))


def _fast_parse(levels: Any, hard: Any) -> tuple[_Parsed, int, int, bool] | None:
    """The items in the common form, their column count, hard rows and whether any is weighted.

    The column count is -1 when the items disagree. None when the input is not in the common
    form (then :func:`_one_by_one` decides).
    """
    if type(levels) is not list and type(levels) is not tuple:
        return None
    As: list[FloatArray] = []
    los: list[FloatArray] = []
    his: list[FloatArray] = []
    ws: list[FloatArray | None] = []
    sizes: list[int] = []
    n_hard = mh = 0
    cols = 0
    weighted = False
    groups = levels if hard is None else [hard, *levels]
    for g, group in enumerate(groups):
        if type(group) is not list:  # (a list of items: the common form)
            if _bare_item(group):
                group = (group,)
            elif type(group) is not tuple:
                return None
        is_hard = hard is not None and g == 0
        m = 0
        for item in group:
            kind = type(item)
            try:
                if kind is tuple or kind is list:
                    if len(item) == 2:
                        A, lo = item
                        if type(lo) is not _ND or lo.dtype is not _F64:
                            lo = _float(lo)
                        hi = lo
                    elif len(item) == 3:
                        A, lo, hi = item
                        if type(lo) is not _ND or lo.dtype is not _F64:
                            lo = _float(lo)
                        if type(hi) is not _ND or hi.dtype is not _F64:
                            hi = _float(hi)
                    else:
                        return None
                    w = None
                elif isinstance(item, Rows):
                    lo, hi = _float(item.lower), _float(item.upper)
                    A, w = item.A, item.weights
                    if w is not None:
                        if is_hard:  # (hard rows have no weights: checked one by one)
                            return None
                        w = _float(w)
                        if w.shape != lo.shape:
                            return None
                        weighted = True
                else:
                    return None
                if type(A) is not _ND or A.dtype is not _F64:
                    A = _float(A)
            except (TypeError, ValueError):
                return None
            shape = A.shape
            if len(shape) != 2:
                return None
            rows, width = shape
            if lo.shape != (rows,) or hi.shape != (rows,):
                return None
            if width != cols:
                cols = width if not As else -1
            As.append(A)
            los.append(lo)
            his.append(hi)
            ws.append(w)
            m += rows
        if hard is not None and g == 0:
            n_hard, mh = len(As), m
        else:
            sizes.append(m)
    return (As, los, his, ws, n_hard, sizes), cols, mh, weighted


# -------------------------------------------------------------------------- one by one
def _as_rows(item: Any, label: str) -> Rows:
    """One item (Rows, (A, b) or (A, lo, hi)) validated; raises the error naming ``label``."""
    if isinstance(item, Rows):
        label = f"{label} ({item.name})" if item.name else label
        rows = Rows.validated(item.A, item.lower, item.upper, item.weights, label)
    elif isinstance(item, tuple | list) and len(item) == 2:
        rows = Rows.equality(item[0], item[1], name=label)
        check_magnitude(rows.A, f"{label}.A")
        check_magnitude(rows.lower, f"{label}.b")
    elif isinstance(item, tuple | list) and len(item) == 3:
        rows = Rows.inequality(item[0], item[1], item[2], name=label)
    else:
        raise InputError(
            f"{label}: expected Rows, an (A, b) pair or an (A, lo, hi) triple, "
            f"got {type(item).__name__}"
        )
    check_magnitude(rows.A, f"{label}.A")
    check_magnitude(rows.lower, f"{label}.lower")
    check_magnitude(rows.upper, f"{label}.upper")
    if rows.weights is not None:
        check_magnitude(rows.weights, f"{label}.weights", weights=True)
    return rows


def _level_rows(items: Any, n: int | None, label: str) -> tuple[list[Rows], int | None]:
    """Validated rows of one level (or of the hard rows) and the column count."""
    if _bare_item(items):
        items = [items]
    if not isinstance(items, Sequence) or isinstance(items, str | bytes):
        raise InputError(f"{label}: expected a list of rows, got {type(items).__name__}")
    rows = [_as_rows(item, f"{label}[{i}]") for i, item in enumerate(items)]
    for i, r in enumerate(rows):
        if n is None:
            n = r.n
        elif r.n != n:
            raise ShapeError(f"{label}[{i}].A: expected {n} columns, got {r.n}")
    return rows, n


def _one_by_one(levels: Any, lower: Any, upper: Any, hard: Any, n: int | None
                ) -> tuple[_Parsed, FloatArray, FloatArray]:
    """Validate every item with errors naming the culprit; the parsed items and the box."""
    if isinstance(levels, Rows) or not isinstance(levels, Sequence) or isinstance(
            levels, str | bytes):
        raise InputError(f"levels: expected a list of levels, got {type(levels).__name__}")
    per_level = []
    for k, level in enumerate(levels):
        rows, n = _level_rows(level, n, f"levels[{k}]")
        per_level.append(rows)
    if hard is None:
        hard = []
    elif isinstance(hard, Iterator):  # e.g. a generator of rows
        hard = list(hard)
    hard_rows, n = _level_rows(hard, n, "hard")
    if n == 0:
        raise ShapeError("levels: the rows have 0 columns (at least one variable is needed)")
    if n is None:
        for vec in (lower, upper):
            if vec is not None:
                n = int(np.size(vec))
                break
    if n is None or n < 1:
        raise InputError("levels: cannot infer the number of variables (no rows and no bounds)")
    lo = np.full(n, -np.inf) if lower is None else as_vector(lower, "lower", n, allow_inf=True)
    hi = np.full(n, np.inf) if upper is None else as_vector(upper, "upper", n, allow_inf=True)
    check_bounds_order(lo, hi, "bounds")
    if np.any(lo == np.inf) or np.any(hi == -np.inf):
        raise InputError("bounds: a lower bound is +inf or an upper bound is -inf")
    check_magnitude(lo, "lower")
    check_magnitude(hi, "upper")
    every = [*hard_rows, *[r for rows in per_level for r in rows]]
    parsed = ([r.A for r in every], [r.lower for r in every], [r.upper for r in every],
              [r.weights for r in every], len(hard_rows), [sum(r.m for r in rows)
                                                           for rows in per_level])
    return parsed, lo, hi


class Validator:
    """Validates user levels into a :class:`Problem`, reusing the one of the last structure.

    A problem handed out is overwritten by the next call of the same structure: keep
    :meth:`Problem.copy` of it to hold on to its values.
    """

    def __init__(self) -> None:
        self._problem: Problem | None = None
        self._ones = False  # the kept problem's row weights are all ones
        self._flat = np.zeros(0)  # the kept problem's sides as one (2 M,) view
        self._rows = np.zeros((0, 0))  # the kept problem's hard and level rows (a view)
        self._constant: dict[int, tuple[FloatArray, FloatArray, FloatArray]] = {}
        self._last = (np.zeros(0), np.zeros(0), np.zeros(0))

    def _constants(self, n: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(-inf, +inf, ones)`` vectors of length n (shared, never written)."""
        got = self._last
        if got[2].shape[0] != n:
            kept = self._constant.get(n)
            if kept is None:
                kept = self._constant[n] = (np.full(n, -np.inf), np.full(n, np.inf), np.ones(n))
            self._last = got = kept
        return got

    @staticmethod
    def _box(value: Any, n: int, default: FloatArray) -> FloatArray | None:
        if value is None:
            return default
        try:
            side = _float(value)
        except (TypeError, ValueError):
            return None
        return side if side.shape == (n,) else None

    def __call__(self, levels: Any, lower: Any = None, upper: Any = None, hard: Any = None,
                 W: FloatArray | None = None, n: int | None = None) -> Problem:
        """Validate and load; returns the problem (``W``: the validated metric, None for ones).

        Raises:
            InputError: malformed levels or items.
            ShapeError: inconsistent column counts or vector lengths.
            NonFiniteError: NaN anywhere, or inf in a matrix / equality target.
            BoundsError: a lower side above its upper side.
        """
        given = n
        fast = _fast_parse(levels, hard)
        lo_box: FloatArray | None = None
        hi_box: FloatArray | None = None
        if fast is not None and fast[1] > 0 and (given is None or given == fast[1]):
            parsed, cols, mh, weighted = fast
            consts = self._last  # (the constants of the last call's width, usually this one)
            lo_inf, hi_inf, _ = consts if consts[2].shape[0] == cols else self._constants(cols)
            # a float64 vector of the right length is taken as it is (the common case)
            if type(lower) is _ND and lower.dtype is _F64 and lower.shape == (cols,):
                lo_box = lower
            else:
                lo_box = self._box(lower, cols, lo_inf)
            if type(upper) is _ND and upper.dtype is _F64 and upper.shape == (cols,):
                hi_box = upper
            else:
                hi_box = self._box(upper, cols, hi_inf)
        checked = lo_box is None or hi_box is None
        if lo_box is None or hi_box is None:
            parsed, lo_box, hi_box = _one_by_one(levels, lower, upper, hard, given)
            mh = sum(A.shape[0] for A in parsed[0][:parsed[4]])
            weighted = any(w is not None for w in parsed[3][parsed[4]:])  # (level rows only)
        width = int(lo_box.shape[0])
        As, los, his, ws, n_hard, sizes = parsed
        problem = self._problem
        if problem is None or problem.n != width or problem.mh != mh or (
                problem.sizes != tuple(sizes)):
            problem = self._problem = Problem(width, mh, sizes)
            self._flat = problem.sides.reshape(-1)
            self._rows = problem.A[width:]
            self._ones = True
        if As:
            _concatenate(As, out=self._rows)
        _concatenate((lo_box, *los, hi_box, *his), out=self._flat)
        if not checked and not sides_and_rows_ok(problem):
            _one_by_one(levels, lower, upper, hard, width)  # raises, or a sum only looked bad
        if weighted:
            w = _concatenate([w if w is not None else np.ones(A.shape[0])
                                for A, w in zip(As[n_hard:], ws[n_hard:], strict=True)])
            if w.size and not (_MIN(w) >= _MIN_WEIGHT and _MAX(w) <= MAX_MAGNITUDE):  # (NaN)
                _one_by_one(levels, lower, upper, hard, width)  # names the rows at fault
            problem.set_weights(w)
            self._ones = False
        elif not self._ones:
            problem.set_weights(None)
            self._ones = True
        problem.W = (self._last[2] if self._last[2].shape[0] == width
                     else self._constants(width)[2]) if W is None else W
        return problem


def finite_ok(problem: Problem) -> bool:
    """No NaN or inf in the rows, no NaN side, no lower side ``+inf``, no upper side ``-inf``.

    Two warning-free reductions: ``sum(lo) - sum(hi)`` is finite or ``-inf`` exactly when the
    sides are legitimate (``+inf`` and ``-inf`` together give NaN), ``A . A`` over the rows is
    finite exactly when every row entry is; a finite overflow (entries beyond ~1e154) gives a
    false alarm only, for the caller's detailed check to clear.
    """
    v = float(_vdot(problem.sides, problem.signs))
    if not (v == -math.inf or math.isfinite(v)):
        return False
    rows = problem.flat_rows
    return math.isfinite(float(_vdot(rows, rows)))


def sides_and_rows_ok(problem: Problem) -> bool:
    """Legitimate sides, rows within the accepted magnitudes, no lower side above its upper.

    Warning-free, by a dot product and counts (a ufunc reduction's set-up costs several times
    either): ``vdot(sides, signs)`` is finite or ``-inf`` exactly when no side is NaN, no lower
    side ``+inf`` and no upper side ``-inf``; ``A . A <= MAX_MAGNITUDE**2`` holds when every
    row entry is in range (and is false on NaN or inf; a false alarm, many entries near the
    limit, is cleared by the detailed check); every finite side is within the magnitude
    exactly when as many sides are within it as are finite; then no lower side may lie above
    its upper side.
    """
    v = float(_vdot(problem.sides, problem.signs))
    if not (v == -math.inf or math.isfinite(v)):
        return False
    rows = problem.flat_rows
    if rows.size and not float(_vdot(rows, rows)) <= _MAX_SQUARE:
        return False
    sides = problem.sides
    if _count(_ABS(sides) <= MAX_MAGNITUDE) != _count(_FINITE(sides)):
        return False
    return not _count(problem.lo > problem.hi)


def normalize_problem(levels: Any, lower: Any = None, upper: Any = None, weights: Any = None,
                      hard: Any = None, n: int | None = None) -> Problem:
    """Validate a user problem into a fresh :class:`Problem` (see :class:`Validator`).

    Args:
        levels: Levels, highest priority first; a level is a list of ``Rows``, ``(A, b)`` pairs
            or ``(A, lo, hi)`` triples, or one of them alone.
        lower: Hard lower bounds on x (length n, ``-inf`` allowed) or None.
        upper: Hard upper bounds on x (length n, ``+inf`` allowed) or None.
        weights: Diagonal of the metric W (length n, positive) or None for the identity.
        hard: Hard general rows (same forms as a level) or None.
        n: Number of variables when it cannot be read from the rows (e.g. no levels).

    Raises:
        InputError, ShapeError, NonFiniteError, BoundsError: see :meth:`Validator.__call__`.
    """
    problem = Validator()(levels, lower, upper, hard, None, n)
    if weights is not None:
        problem.W = as_vector(weights, "weights", problem.n, positive=True)
        check_magnitude(problem.W, "weights", weights=True)
    return problem
