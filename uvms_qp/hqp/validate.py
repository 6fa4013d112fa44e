"""The one validator: user-facing levels into the stacked :class:`~uvms_qp.hqp.problem.Problem`.

A level is a list of ``Rows`` objects, ``(A, b)`` equality pairs or ``(A, lo, hi)`` inequality
triples over x (A of shape (m, n)); hard rows take the same forms; the box is two vectors of
length n (``-inf`` / ``+inf`` allowed). :class:`Validator` copies every row and side into the
buffers of a problem (reused while the structure ``(n, m_H, level sizes)`` repeats) and checks
the whole stack with a few reductions (:func:`sides_and_rows_ok`):

* no NaN side, no lower side ``+inf`` and no upper side ``-inf`` (e.g. an infinite equality
  target), no lower side above its upper side;
* no NaN or inf in a matrix;
* the row weights are finite and positive.

When the input is not in this common form or a check fails, the items are validated one by one,
which raises the error naming the culprit (``levels[1][0].A: expected 2 columns, got 3``); an
overflowing reduction on legitimate values (entries near 1e154) passes that second look and the
problem is solved as filled.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validation import FloatArray, as_vector, check_bounds_order
from ..errors import InputError, ShapeError
from ..rows import Rows, pair_or_triple_arrays
from .problem import Problem

_Item = tuple[FloatArray, FloatArray, FloatArray, FloatArray | None]
_MIN = np.minimum.reduce


def _fast_item(item: Any) -> _Item | None:
    """``(A, lo, hi, weights)`` of one item in the common form, or None (shapes checked)."""
    if isinstance(item, Rows):
        try:
            A = np.asarray(item.A, dtype=np.float64)
            lo = np.asarray(item.lower, dtype=np.float64)
            hi = np.asarray(item.upper, dtype=np.float64)
            w = None if item.weights is None else np.asarray(item.weights, dtype=np.float64)
        except (TypeError, ValueError):
            return None
        if w is not None and w.shape != lo.shape:
            return None
    elif isinstance(item, tuple | list) and len(item) in (2, 3):
        arrays = pair_or_triple_arrays(item)
        if arrays is None:
            return None
        A, lo, hi = arrays
        w = None
    else:
        return None
    if A.ndim != 2 or lo.shape != (A.shape[0],) or hi.shape != lo.shape:
        return None
    return A, lo, hi, w


def _fast_parse(levels: Any, hard: Any) -> tuple[list[_Item], int, list[int]] | None:
    """Items of the hard rows and the levels, the number of hard items and the level sizes.

    None when the input is not in the common form (then :func:`_one_by_one` decides).
    """
    if not isinstance(levels, list | tuple):
        return None
    items: list[_Item] = []
    if hard is not None:
        if not isinstance(hard, list | tuple):
            return None
        for element in hard:
            got = _fast_item(element)
            if got is None:
                return None
            items.append(got)
    n_hard = len(items)
    sizes = []
    for level in levels:
        if not isinstance(level, list | tuple) or (level and not isinstance(
                level[0], Rows | tuple | list)):
            return None
        m = 0
        for element in level:
            got = _fast_item(element)
            if got is None:
                return None
            items.append(got)
            m += got[0].shape[0]
        sizes.append(m)
    return items, n_hard, sizes


# -------------------------------------------------------------------------- one by one
def _as_rows(item: Any, label: str) -> Rows:
    """One item (Rows, (A, b) or (A, lo, hi)) validated; raises the error naming ``label``."""
    if isinstance(item, Rows):
        name = f"{label} ({item.name})" if item.name else label
        return Rows.validated(item.A, item.lower, item.upper, item.weights, name)
    if isinstance(item, tuple | list) and len(item) == 2:
        return Rows.equality(item[0], item[1], name=label)
    if isinstance(item, tuple | list) and len(item) == 3:
        return Rows.inequality(item[0], item[1], item[2], name=label)
    raise InputError(
        f"{label}: expected Rows, an (A, b) pair or an (A, lo, hi) triple, "
        f"got {type(item).__name__}"
    )


def _level_rows(items: Any, n: int | None, label: str) -> tuple[list[Rows], int | None]:
    """Validated rows of one level (or of the hard rows) and the column count."""
    if isinstance(items, Rows) or (isinstance(items, tuple) and items and not isinstance(
            items[0], Rows | tuple | list)):
        items = [items]  # a single Rows or a bare (A, b) tuple given as a level
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
                ) -> tuple[list[_Item], int, list[int], FloatArray, FloatArray]:
    """Validate every item with errors naming the culprit; items, hard items, sizes, box."""
    if isinstance(levels, Rows) or not isinstance(levels, Sequence) or isinstance(
            levels, str | bytes):
        raise InputError(f"levels: expected a list of levels, got {type(levels).__name__}")
    per_level = []
    for k, level in enumerate(levels):
        rows, n = _level_rows(level, n, f"levels[{k}]")
        per_level.append(rows)
    hard_rows, n = _level_rows(list(hard) if hard is not None else [], n, "hard")
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
    items: list[_Item] = [(r.A, r.lower, r.upper, r.weights) for r in hard_rows]
    sizes = []
    for rows in per_level:
        items.extend((r.A, r.lower, r.upper, r.weights) for r in rows)
        sizes.append(sum(r.m for r in rows))
    return items, len(hard_rows), sizes, lo, hi


class Validator:
    """Validates user levels into a :class:`Problem`, reusing the one of the last structure.

    A problem handed out is overwritten by the next call of the same structure: keep
    :meth:`Problem.copy` of it to hold on to its values.
    """

    def __init__(self) -> None:
        self._problem: Problem | None = None
        self._ones = False  # the kept problem's row weights are all ones
        self._constant: dict[int, tuple[FloatArray, FloatArray, FloatArray]] = {}

    def _constants(self, n: int) -> tuple[FloatArray, FloatArray, FloatArray]:
        """``(-inf, +inf, ones)`` vectors of length n (shared, never written)."""
        got = self._constant.get(n)
        if got is None:
            got = self._constant[n] = (np.full(n, -np.inf), np.full(n, np.inf), np.ones(n))
        return got

    @staticmethod
    def _box(value: Any, n: int, default: FloatArray) -> FloatArray | None:
        if value is None:
            return default
        try:
            side = np.asarray(value, dtype=np.float64)
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
        parsed = _fast_parse(levels, hard)
        lo_box = hi_box = None
        if parsed is not None and parsed[0]:
            items, n_hard, sizes = parsed
            n = items[0][0].shape[1]
            if n and all(it[0].shape[1] == n for it in items):
                lo_inf, hi_inf, _ = self._constants(n)
                lo_box, hi_box = self._box(lower, n, lo_inf), self._box(upper, n, hi_inf)
        checked = lo_box is None or hi_box is None
        if checked:
            items, n_hard, sizes, lo_box, hi_box = _one_by_one(levels, lower, upper, hard, given)
        n = lo_box.shape[0]
        mh = sum(it[0].shape[0] for it in items[:n_hard])
        problem = self._problem
        if problem is None or problem.n != n or problem.mh != mh or problem.sizes != tuple(sizes):
            problem = self._problem = Problem(n, mh, sizes)
            self._ones = True
        if items:
            np.concatenate([it[0] for it in items], out=problem.A[n:])
        np.concatenate([lo_box, *[it[1] for it in items], hi_box, *[it[2] for it in items]],
                       out=problem.sides.reshape(-1))
        if not checked and not sides_and_rows_ok(problem):
            _one_by_one(levels, lower, upper, hard, n)  # raises, or the sums only overflowed
        level_items = items[n_hard:]
        if any(it[3] is not None for it in level_items):
            w = np.concatenate([it[3] if it[3] is not None else np.ones(it[0].shape[0])
                                for it in level_items])
            if not (math.isfinite(float(w.sum())) and _MIN(w) > 0.0):
                _one_by_one(levels, lower, upper, hard, n)  # names the rows at fault
            problem.set_weights(w)
            self._ones = False
        elif not self._ones:
            problem.set_weights(None)
            self._ones = True
        problem.W = self._constants(n)[2] if W is None else W
        return problem


def sides_and_rows_ok(problem: Problem) -> bool:
    """The checks of the module docstring on a filled problem, in four warning-free calls.

    ``sum(lo) - sum(hi)`` is finite or ``-inf`` exactly when no side is NaN, no lower side is
    ``+inf`` and no upper side ``-inf`` (``+inf`` and ``-inf`` together give NaN; a finite
    overflow only sends the problem to the detailed check); ``vdot(A, A)`` is finite exactly
    when every row entry is (up to the same overflow).
    """
    v = float(np.vdot(problem.sides, problem.signs))
    if not (v == -math.inf or math.isfinite(v)):
        return False
    if np.count_nonzero(np.greater(problem.lo, problem.hi, out=problem.flags)):
        return False
    rows = problem.A[problem.n:]
    return not rows.size or math.isfinite(float(np.vdot(rows, rows)))


def normalize_problem(levels: Any, lower: Any = None, upper: Any = None, weights: Any = None,
                      hard: Any = None, n: int | None = None) -> Problem:
    """Validate a user problem into a fresh :class:`Problem` (see :class:`Validator`).

    Args:
        levels: Levels, highest priority first; a level is a list of ``Rows``, ``(A, b)`` pairs
            or ``(A, lo, hi)`` triples.
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
    return problem
