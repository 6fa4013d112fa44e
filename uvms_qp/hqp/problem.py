"""The lexicographic problem in its one stacked layout.

A problem over ``x`` in R^n has a hard box ``lower <= x <= upper``, ``m_H`` hard rows
``lo_H <= A_H x <= hi_H`` (never relaxed) and levels ``L_0 > ... > L_(p-1)`` of rows
``lo_k <= A_k x <= hi_k`` with positive row weights ``w_k``, and a positive diagonal metric ``W``
for the final regularisation ``min x' W x``. Every part of the library holds it the same way:

    A  = [ I_n ; A_H ; A_0 ; ... ; A_p-1 ]        (M, n),  M = n + m_H + sum m_k
    lo = [ lower ; lo_H ; lo_0 ; ... ; lo_p-1 ]    (M,)     -inf allowed
    hi = [ upper ; hi_H ; hi_0 ; ... ; hi_p-1 ]    (M,)     +inf allowed
    w  = [ w_0 ; ... ; w_p-1 ]                     (sum m_k,)

so that one product ``A x`` measures every bound, hard row and level row at once
(:mod:`uvms_qp.hqp.measure`). ``lo`` and ``hi`` are the two rows of one ``(2, M)`` array
``sides``. The arrays are buffers: a controller writes each tick's rows straight into them,
:func:`uvms_qp.hqp.validate.normalize_problem` fills them from user input, and back-ends read them
in place (DAQP is handed pointers into ``A``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from itertools import pairwise
from typing import Any

import numpy as np

from .._validation import FloatArray, as_vector
from ..errors import InputError
from ..rows import Rows
from .linalg import single_threaded


def _count(value: Any, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
        raise InputError(f"{name}: expected an integer >= {least}, got {value!r}")
    return int(value)


def scale_of(sides: FloatArray) -> float:
    """``max(1, max |finite entry|)`` of a ``(2, m)`` block of sides."""
    lo, hi = sides.tolist()
    values = lo if lo == hi else lo + hi  # equality rows: one side is enough
    big = max(map(abs, values), default=0.0)
    if big == math.inf:
        big = max(filter(math.isfinite, map(abs, values)), default=0.0)
    return big if big > 1.0 else 1.0


class Problem:
    """Buffers of one problem structure ``(n, m_H, (m_0, ..., m_p-1))`` (see the module docstring).

    Args:
        n: Number of variables.
        hard_rows: Number of hard general rows ``m_H``.
        sizes: Rows per level, highest priority first (0 allowed: an empty level).
        W: Diagonal metric (n,), positive; None for the identity.
        A: Use this (M, n) array as ``A`` instead of a new one (its first n rows must be the
            identity); for problems that share rows with another (e.g. fewer levels).
        sides: Use this (2, M) array as ``sides``.
        w: Use this array as the level row weights.

    Attributes:
        n: Number of variables.
        mh: Number of hard rows.
        sizes: Rows per level.
        head: ``n + mh``: the rows of the box and the hard rows, before the level rows.
        M: Number of stacked rows.
        A: Stacked rows (M, n); write rows ``A[n:]`` only.
        sides: ``(2, M)``: lower sides, then upper sides.
        lo: ``sides[0]``.
        hi: ``sides[1]``.
        W: Diagonal metric (n,).
        w: Level row weights (sum m_k,); change them with :meth:`set_weights` only (other
            parts derive data from them, refreshed on :attr:`weights_version`).
        weights_version: Incremented by every :meth:`set_weights`.
        spans: ``(start, end)`` of each level in the stacked rows.
        G: ``(1 + p, M)``: row 0 sums the box and hard rows, row ``k + 1`` the weighted rows of
            level ``k`` (``G @ (s * s)`` gives every squared residual in one product).
        unit_weights: Every level row weight is 1.
        signs: ``(2, M)`` rows of +1 and -1 (``vdot(sides, signs) = sum(lo) - sum(hi)``).
        flags: Scratch booleans (M,) for checks.
        box: ``sides[:, :n]``: the hard box as rows ``lower``, ``upper`` (a view).
        level_sides: ``sides[:, a:b]`` of each level (views).
        flat_rows: ``A[n:]`` flattened (a view: the hard and level rows in one vector).
        squares: Scratch (M,) for squared slacks.
        single_threaded: The products of a solve of this size never run a second BLAS thread
            (:func:`~uvms_qp.hqp.linalg.single_threaded`): a solve skips the thread limit.

    Raises:
        InputError: a size that is not a non-negative integer, or a bad metric.
    """

    __slots__ = (
        "A",
        "G",
        "M",
        "W",
        "__weakref__",
        "box",
        "flags",
        "flat_rows",
        "head",
        "hi",
        "level_sides",
        "lo",
        "mh",
        "n",
        "sides",
        "signs",
        "single_threaded",
        "sizes",
        "spans",
        "squares",
        "unit_weights",
        "w",
        "weights_version",
    )

    def __init__(self, n: int, hard_rows: int = 0, sizes: Sequence[int] = (), W: Any = None, *,
                 A: FloatArray | None = None, sides: FloatArray | None = None,
                 w: FloatArray | None = None) -> None:
        n = _count(n, "n", 1)
        mh = _count(hard_rows, "hard_rows", 0)
        if isinstance(sizes, str | bytes) or not isinstance(sizes, Sequence):
            raise InputError(f"sizes: expected a list of row counts, got {sizes!r}")
        self.sizes = tuple(_count(m, f"sizes[{k}]", 0) for k, m in enumerate(sizes))
        self.n, self.mh, self.head = n, mh, n + mh
        ml = sum(self.sizes)
        self.M = M = self.head + ml
        self.single_threaded = single_threaded(M, n)
        if A is None:
            A = np.zeros((M, n))
            A[:n] = np.eye(n)
        if sides is None:
            sides = np.empty((2, M))
            sides[0], sides[1] = -np.inf, np.inf
        if not A.flags.c_contiguous:  # read in place through flat views (checks, DAQP)
            raise InputError("A: expected a C-contiguous array (the problem's own buffer)")
        if not (sides[0].flags.c_contiguous and sides[1].flags.c_contiguous):
            # DAQP reads lo and hi in place on every solve after its set-up: a strided side
            # would be copied once at the set-up and every later solve would see those values
            raise InputError("sides: expected rows that are C-contiguous (the problem's own "
                             "buffer)")
        self.A, self.sides = A, sides
        self.box = sides[:, :n]
        self.flat_rows = A[n:].reshape(-1)
        self.lo, self.hi = sides[0], sides[1]
        self.signs = np.ones((2, M))  # [+1; -1]: vdot(sides, signs) = sum(lo) - sum(hi)
        self.signs[1] = -1.0
        self.flags = np.zeros(M, dtype=bool)  # scratch of the checks
        self.W = np.ones(n) if W is None else as_vector(W, "W", n, positive=True)
        ends = np.cumsum((self.head, *self.sizes)).tolist()
        self.spans = tuple(pairwise(ends))
        self.level_sides = tuple(sides[:, a:b] for a, b in self.spans)
        self.squares = np.empty(M)
        self.w = np.ones(ml) if w is None else w
        self.weights_version = 0
        self.G = np.zeros((1 + len(self.sizes), M))
        self.G[0, :self.head] = 1.0
        self.set_weights(self.w)

    # ------------------------------------------------------------------------------- views
    @property
    def lower(self) -> FloatArray:
        """Hard lower bounds on x (n,), a view of ``lo``."""
        return self.lo[:self.n]

    @property
    def upper(self) -> FloatArray:
        """Hard upper bounds on x (n,), a view of ``hi``."""
        return self.hi[:self.n]

    @property
    def hard(self) -> Rows:
        """The hard rows as :class:`~uvms_qp.rows.Rows` (views)."""
        n, h = self.n, self.head
        return Rows(self.A[n:h], self.lo[n:h], self.hi[n:h])

    def level(self, k: int) -> Rows:
        """The rows of level ``k`` as :class:`~uvms_qp.rows.Rows` (views, weights always set)."""
        a, b = self.spans[k]
        h = self.head
        return Rows(self.A[a:b], self.lo[a:b], self.hi[a:b], self.w[a - h:b - h])

    @property
    def levels(self) -> tuple[Rows, ...]:
        """Every level's rows, highest priority first (views)."""
        return tuple(self.level(k) for k in range(len(self.sizes)))

    def scale(self, start: int, end: int) -> float:
        """``max(1, max |finite side|)`` over stacked rows ``start:end`` (relative tolerances)."""
        return scale_of(self.sides[:, start:end])

    def level_scale(self, k: int) -> float:
        """:meth:`scale` of the rows of level ``k``."""
        return scale_of(self.level_sides[k])

    @property
    def hard_scale(self) -> float:
        """``max(1, max |finite bound or hard side|)``."""
        return self.scale(0, self.head)


    # ----------------------------------------------------------------------------- changes
    def set_weights(self, w: Any = None, rows: slice | None = None) -> None:
        """Write level row weights (all of them, or ``rows`` of the level part); None for ones.

        The weights must be positive and finite (checked by the writers: the validator, the
        controller's tasks).
        """
        target = self.w if rows is None else self.w[rows]
        if w is None:
            target.fill(1.0)
        elif w is not target:
            target[...] = w
        G, h = self.G, self.head
        for k, (a, b) in enumerate(self.spans):
            G[k + 1, a:b] = self.w[a - h:b - h]
        self.unit_weights = bool((self.w == 1.0).all())
        self.weights_version += 1

    def relaxed(self, keep: int) -> Problem:
        """The problem with only the ``keep`` highest levels, on the same buffers."""
        end = self.spans[keep - 1][1] if keep else self.head
        ml = end - self.head
        return Problem(self.n, self.mh, self.sizes[:keep], self.W, A=self.A[:end],
                       sides=self.sides[:, :end], w=self.w[:ml])

    def regrouped(self, sizes: Sequence[int], w: FloatArray | None = None) -> Problem:
        """The same rows split into other levels (same total), with their own weights."""
        if sum(sizes) != self.M - self.head:
            raise InputError(f"sizes: expected {self.M - self.head} rows in all, got {sum(sizes)}")
        return Problem(self.n, self.mh, sizes, self.W, A=self.A, sides=self.sides,
                       w=np.ones(self.M - self.head) if w is None else w)

    def copy(self) -> Problem:
        """A problem with copies of every buffer (a snapshot of this tick's values)."""
        return Problem(self.n, self.mh, self.sizes, self.W.copy(), A=self.A.copy(),
                       sides=self.sides.copy(), w=self.w.copy())

    def __repr__(self) -> str:
        return f"Problem(n={self.n}, hard_rows={self.mh}, sizes={list(self.sizes)})"
