"""Normalisation and validation of a lexicographic problem.

A problem over ``x`` in R^n is a list of levels L_1 > L_2 > ... > L_p, each level a stack of rows
``lo_k <= A_k x <= hi_k`` with positive per-row weights ``w_k``, hard rows
``lo_H <= A_H x <= hi_H`` and a hard box ``lower <= x <= upper`` that are never relaxed, and a
positive diagonal metric ``W`` for the final minimum-norm regularisation ``min x' W x``.

This module turns the user-facing forms (``Rows`` objects, ``(A, b)`` pairs, ``(A, lo, hi)``
triples) into one stacked float64 block per level, so that every back-end works on the same
plain arrays.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from .._validation import FloatArray, as_vector, check_bounds_order
from ..errors import InputError, ShapeError
from ..rows import Rows, pair_or_triple_arrays


@dataclass(frozen=True, eq=False)
class Block:
    """Stacked rows of one level (or of the hard rows): ``lo <= A x <= hi``.

    Attributes:
        A: Row matrix, shape (m, n).
        lo: Lower sides, shape (m,), ``-inf`` allowed.
        hi: Upper sides, shape (m,), ``+inf`` allowed.
        w: Positive row weights, shape (m,).
        eq: Boolean mask of equality rows (``lo == hi``), shape (m,).
        names: Names of the ``Rows`` the block was stacked from.
    """

    A: FloatArray
    lo: FloatArray
    hi: FloatArray
    w: FloatArray
    eq: np.ndarray
    names: tuple[str, ...] = ()

    @property
    def m(self) -> int:
        """Number of rows."""
        return int(self.A.shape[0])

    @property
    def all_equality(self) -> bool:
        """True when every row is an equality."""
        return bool(self.eq.all())

    def violation(self, x: FloatArray) -> FloatArray:
        """Signed slack ``s = A x - clip(A x, lo, hi)`` (> 0 above ``hi``, < 0 below ``lo``)."""
        y = self.A @ x
        return y - np.minimum(np.maximum(y, self.lo), self.hi)

    def residual(self, x: FloatArray) -> float:
        """Weighted violation norm ``sqrt(sum_i w_i s_i^2)``."""
        s = self.violation(x)
        return float(np.sqrt(self.w @ (s * s)))

    def scale(self) -> float:
        """Magnitude of the finite sides for relative tolerances: ``max(1, max |side|)``."""
        sides = np.concatenate((self.lo, self.hi))
        finite = sides[np.isfinite(sides)]
        return float(max(1.0, np.abs(finite).max())) if finite.size else 1.0


@dataclass(frozen=True, eq=False)
class Problem:
    """A normalised lexicographic problem (see the module docstring for the maths).

    Attributes:
        n: Number of variables.
        levels: One stacked block per level, highest priority first.
        hard: Stacked hard general rows (possibly with zero rows).
        lower: Hard lower bounds on x, shape (n,), ``-inf`` allowed.
        upper: Hard upper bounds on x, shape (n,), ``+inf`` allowed.
        W: Diagonal of the regularisation metric, shape (n,), positive.
    """

    n: int
    levels: tuple[Block, ...]
    hard: Block
    lower: FloatArray
    upper: FloatArray
    W: FloatArray

    @property
    def has_box(self) -> bool:
        """True when at least one bound is finite."""
        return bool(np.isfinite(self.lower).any() or np.isfinite(self.upper).any())

    @property
    def all_equality(self) -> bool:
        """True when every level holds only equality rows."""
        return all(level.all_equality for level in self.levels)

    @cached_property
    def stacked(self) -> Block:
        """All level rows stacked in priority order (computed once per problem)."""
        if len(self.levels) == 1:
            return self.levels[0]
        if not self.levels:
            return Block(np.zeros((0, self.n)), np.zeros(0), np.zeros(0), np.zeros(0),
                         np.zeros(0, dtype=bool))
        return Block(np.vstack([b.A for b in self.levels]),
                     np.concatenate([b.lo for b in self.levels]),
                     np.concatenate([b.hi for b in self.levels]),
                     np.concatenate([b.w for b in self.levels]),
                     np.concatenate([b.eq for b in self.levels]))

    @cached_property
    def offsets(self) -> np.ndarray:
        """Index of the first stacked row of each level."""
        return np.cumsum([0] + [b.m for b in self.levels[:-1]]).astype(np.intp)

    @cached_property
    def level_scales(self) -> np.ndarray:
        """``max(1, max |finite side|)`` of each level (for relative tolerances)."""
        st = self.stacked
        if not st.m or not all(b.m for b in self.levels):
            return np.array([b.scale() for b in self.levels])
        lo = np.where(np.isfinite(st.lo), np.abs(st.lo), 0.0)
        hi = np.where(np.isfinite(st.hi), np.abs(st.hi), 0.0)
        return np.maximum(np.maximum.reduceat(np.maximum(lo, hi), self.offsets), 1.0)

    @cached_property
    def hard_scale(self) -> float:
        """``max(1, max |finite bound or hard side|)``."""
        v = 1.0
        for side in (self.lower, self.upper, self.hard.lo, self.hard.hi):
            if side.size:
                v = max(v, float(np.where(np.isfinite(side), np.abs(side), 0.0).max()))
        return v

    @cached_property
    def active_tol(self) -> tuple[np.ndarray, np.ndarray]:
        """Tolerances deciding that a bound is active: ``1e-9 (1 + |bound|)``."""
        return (1e-9 * (1.0 + np.abs(np.where(np.isfinite(self.lower), self.lower, 0.0))),
                1e-9 * (1.0 + np.abs(np.where(np.isfinite(self.upper), self.upper, 0.0))))


def _fast_rows(item: tuple[Any, ...] | list[Any]) -> Rows | None:
    """Cheap acceptance test for a well-formed tuple; None sends it to the full validation.

    Only checks that pass for valid input run here (dtype, shapes, finiteness, ordering); any
    doubt falls back to :meth:`Rows.validated`, which produces the detailed error message.
    """
    arrays = pair_or_triple_arrays(item)
    if arrays is None:
        return None
    A, lo, hi = arrays
    if A.ndim != 2 or lo.ndim != 1 or hi.ndim != 1:
        return None
    m = A.shape[0]
    if lo.shape[0] != m or hi.shape[0] != m or not np.isfinite(A).all():
        return None
    if len(item) == 2:
        if not np.isfinite(lo).all():
            return None
    elif np.isnan(lo).any() or np.isnan(hi).any() or (lo > hi).any() or (lo == np.inf).any() or (
            hi == -np.inf).any():
        return None
    return Rows(A, lo, hi)


def _checked_rows(rows: Rows, label: str) -> Rows:
    """Check a caller's ``Rows`` (built directly, so never validated) like a tuple.

    Well-formed float rows pass with a few reductions; anything else is rebuilt through
    :meth:`Rows.validated`, which raises the error naming ``label`` (and the rows' name).
    """
    fast = _fast_rows((rows.A, rows.lower, rows.upper))
    w = rows.weights
    if fast is not None and (w is None or (
            type(w) is np.ndarray and w.dtype.kind == "f" and w.shape == fast.lower.shape
            and np.isfinite(w).all() and (w > 0.0).all())):
        if fast.A is rows.A and fast.lower is rows.lower and fast.upper is rows.upper:
            return rows
        return Rows(fast.A, fast.lower, fast.upper, w, rows.name)
    name = f"{label} ({rows.name})" if rows.name else label
    checked = Rows.validated(rows.A, rows.lower, rows.upper, rows.weights, name)
    return Rows(checked.A, checked.lower, checked.upper, checked.weights, rows.name)


def _as_rows(item: Any, label: str) -> Rows:
    """Turn one level item (Rows, (A, b) or (A, lo, hi)) into validated ``Rows``."""
    if isinstance(item, Rows):
        return _checked_rows(item, label)
    if isinstance(item, tuple | list) and len(item) in (2, 3):
        fast = _fast_rows(item)
        if fast is not None:
            return fast
    if isinstance(item, tuple | list) and len(item) == 2:
        return Rows.equality(item[0], item[1], name=label)
    if isinstance(item, tuple | list) and len(item) == 3:
        return Rows.inequality(item[0], item[1], item[2], name=label)
    raise InputError(
        f"{label}: expected Rows, an (A, b) pair or an (A, lo, hi) triple, "
        f"got {type(item).__name__}"
    )


def _stack(items: Sequence[Any], n: int | None, label: str) -> tuple[Block, int | None]:
    """Stack the rows of one level into a :class:`Block`; returns the block and the column count."""
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
    width = 0 if n is None else n
    if len(rows) == 1:
        r = rows[0]
        A, lo, hi = r.A, r.lower, r.upper
        w = r.weights if r.weights is not None else np.ones(r.m)
    elif rows:
        A = np.vstack([r.A for r in rows])
        lo = np.concatenate([r.lower for r in rows])
        hi = np.concatenate([r.upper for r in rows])
        w = np.concatenate([r.weights if r.weights is not None else np.ones(r.m) for r in rows])
    else:
        A, lo, hi, w = np.zeros((0, width)), np.zeros(0), np.zeros(0), np.zeros(0)
    return Block(A, lo, hi, w, lo == hi, tuple(r.name for r in rows)), n


def normalize_problem(
    levels: Sequence[Any],
    lower: Any = None,
    upper: Any = None,
    weights: Any = None,
    hard: Sequence[Any] | None = None,
    n: int | None = None,
) -> Problem:
    """Validate the user's problem and stack it into a :class:`Problem`.

    Args:
        levels: Levels, highest priority first; a level is a list of ``Rows``, ``(A, b)`` pairs
            or ``(A, lo, hi)`` triples.
        lower: Hard lower bounds on x (length n, ``-inf`` allowed) or None.
        upper: Hard upper bounds on x (length n, ``+inf`` allowed) or None.
        weights: Diagonal of the metric W (length n, positive) or None for the identity.
        hard: Hard general rows (same forms as a level) or None.
        n: Number of variables when it cannot be read from the rows (e.g. no levels).

    Returns:
        The stacked problem.

    Raises:
        InputError: malformed levels or non-positive weights.
        ShapeError: inconsistent column counts or vector lengths.
        NonFiniteError: NaN anywhere, or inf in a matrix / equality target.
        BoundsError: a lower side above its upper side.
    """
    if isinstance(levels, Rows) or not isinstance(levels, Sequence) or isinstance(
        levels, str | bytes
    ):
        raise InputError(f"levels: expected a list of levels, got {type(levels).__name__}")
    blocks = []
    for k, level in enumerate(levels):
        block, n = _stack(level, n, f"levels[{k}]")
        blocks.append(block)
    hard_block, n = _stack(list(hard) if hard is not None else [], n, "hard")
    if n == 0:
        raise ShapeError("levels: the rows have 0 columns (at least one variable is needed)")
    if n is None:
        for vec in (lower, upper, weights):
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
    W = np.ones(n) if weights is None else as_vector(weights, "weights", n, positive=True)
    if hard_block.m == 0 and hard_block.A.shape[1] != n:
        hard_block = Block(np.zeros((0, n)), np.zeros(0), np.zeros(0), np.zeros(0),
                           np.zeros(0, dtype=bool))
    for k, block in enumerate(blocks):
        if block.m == 0 and block.A.shape[1] != n:
            blocks[k] = Block(np.zeros((0, n)), np.zeros(0), np.zeros(0), np.zeros(0),
                              np.zeros(0, dtype=bool))
    return Problem(n, tuple(blocks), hard_block, lo, hi, W)
