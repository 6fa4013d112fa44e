"""Rows: the one currency between tasks and the lexicographic solver.

A block of ``m`` linear rows over the decision vector ``x`` (``zeta`` for a robot):

    lower <= A @ x <= upper        (an equality when lower == upper)

with optional positive per-row weights. Weights only matter within a level: a level minimises
``sum_i weights[i] * violation_i**2`` where ``violation_i`` is the distance of ``(A @ x)_i`` to
``[lower_i, upper_i]``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ._validation import FloatArray, as_matrix, as_vector, check_bounds_order
from .errors import InputError


@dataclass(frozen=True, eq=False)
class Rows:
    """A validated block of rows ``lower <= A x <= upper``.

    Attributes:
        A: Row matrix, shape (m, n).
        lower: Lower sides, shape (m,); ``-inf`` allowed.
        upper: Upper sides, shape (m,); ``+inf`` allowed.
        weights: Positive per-row weights, shape (m,), or None for all ones.
        name: Label used in diagnostics (e.g. the task name).
    """

    A: FloatArray
    lower: FloatArray
    upper: FloatArray
    weights: FloatArray | None = None
    name: str = ""

    @classmethod
    def equality(cls, A: Any, b: Any, weights: Any = None, name: str = "") -> Rows:
        """Build equality rows ``A x = b`` (validated)."""
        label = name or "rows"
        A_ = as_matrix(A, f"{label}.A")
        b_ = as_vector(b, f"{label}.b", A_.shape[0])
        return cls.validated(A_, b_, b_, weights, name)

    @classmethod
    def inequality(
        cls, A: Any, lower: Any, upper: Any, weights: Any = None, name: str = ""
    ) -> Rows:
        """Build inequality rows ``lower <= A x <= upper`` (validated; infinities allowed)."""
        return cls.validated(A, lower, upper, weights, name)

    @classmethod
    def validated(
        cls, A: Any, lower: Any, upper: Any, weights: Any = None, name: str = ""
    ) -> Rows:
        """Validate shapes, finiteness and ordering, then build the rows."""
        label = name or "rows"
        A_ = as_matrix(A, f"{label}.A")
        m = A_.shape[0]
        lo = as_vector(lower, f"{label}.lower", m, allow_inf=True)
        hi = as_vector(upper, f"{label}.upper", m, allow_inf=True)
        check_bounds_order(lo, hi, label)
        if np.any(lo == np.inf) or np.any(hi == -np.inf):
            raise InputError(f"{label}: a lower side is +inf or an upper side is -inf")
        w = None
        if weights is not None:
            w = as_vector(weights, f"{label}.weights", m, positive=True)
        return cls(A_, lo, hi, w, name)

    @property
    def m(self) -> int:
        """Number of rows."""
        return int(self.A.shape[0])

    @property
    def n(self) -> int:
        """Number of columns (size of the decision vector)."""
        return int(self.A.shape[1])

    @property
    def is_equality(self) -> bool:
        """True when every row is an equality (``lower == upper``)."""
        return bool(np.array_equal(self.lower, self.upper))

    def violation(self, x: FloatArray) -> FloatArray:
        """Signed-free violation of each row at ``x``: distance of ``A x`` to ``[lower, upper]``."""
        y = self.A @ x
        return np.maximum(self.lower - y, 0.0) + np.maximum(y - self.upper, 0.0)
