"""Preallocated stacked arrays of one problem structure, reused while the structure repeats.

A problem over ``x`` in R^n with a box, ``m_H`` hard rows and levels of sizes ``m_1..m_p`` is laid
out as one augmented row matrix and one pair of side vectors (``M = n + m_H + sum m_k`` rows):

    A_aug = [ I_n ; A_H ; A_1 ; ... ; A_p ]          (M, n), rows filled in place every call
    lo    = [ lower ; lo_H ; lo_1 ; ... ; lo_p ]      (M,), a fresh array every call
    hi    = [ upper ; hi_H ; hi_1 ; ... ; hi_p ]      (M,)

so that one product ``z = A_aug x`` and three element-wise operations give the signed slack of
every box bound, hard row and level row at once, ``s = z - min(max(z, lo), hi)``. DAQP takes
``A_aug[n:]`` (its first ``n`` sides are the simple bounds), and the level residuals are
``r = sqrt(G (w * s_L * s_L))`` with ``G`` the (p, sum m_k) 0/1 matrix that sums each level's
rows (empty levels give 0). Only ``A_aug`` and DAQP's clamped copies of the sides are reused
buffers; everything a result keeps (``lo``, ``hi``, ``s``, ``x``) is fresh, so a result stays valid
after the next call.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .._validation import FloatArray
from .problem import Problem

DAQP_INF = 1e30
"""DAQP's infinity: sides beyond it are clamped before they are handed over."""


class Workspace:
    """Buffers of one structure ``(n, m_H, (m_1, ..., m_p))``.

    Args:
        n: Number of variables.
        hard_rows: Number of hard general rows ``m_H``.
        sizes: Rows per level, highest priority first.

    Attributes:
        key: ``(n, m_H, sizes)``.
        A: Augmented row matrix ``[I; A_H; A_1; ...; A_p]``, shape (M, n).
        daqp_A: View ``A[n:]`` of the general rows handed to DAQP.
        bu: DAQP upper sides (``hi`` clamped to ``1e30``), shape (M,).
        bl: DAQP lower sides (``lo`` clamped to ``-1e30``), shape (M,).
        G: Level-summing 0/1 matrix, shape (p, sum m_k).
        starts: First row of each level inside the level part, length p.
        ones: Unit row weights of the level part (used when no level carries weights).
    """

    def __init__(self, n: int, hard_rows: int, sizes: Sequence[int]) -> None:
        self.n = int(n)
        self.mh = int(hard_rows)
        self.sizes = tuple(int(m) for m in sizes)
        self.key = (self.n, self.mh, self.sizes)
        ml = sum(self.sizes)
        self.ml = ml
        self.head = self.n + self.mh  # rows of the box and the hard rows
        self.M = self.head + ml
        self.A = np.zeros((self.M, self.n))
        self.A[: self.n] = np.eye(self.n)
        self.bu = np.empty(self.M)
        self.bl = np.empty(self.M)
        bounds = np.cumsum((0, *self.sizes))
        self.starts = tuple(int(v) for v in bounds[:-1])
        self.ends = tuple(int(v) for v in bounds[1:])
        self.spans = tuple(zip(self.starts, self.ends, strict=True))
        self.hard_rows = slice(self.n, self.head)
        self.level_rows = tuple(slice(self.head + a, self.head + b) for a, b in self.spans)
        self.G = np.zeros((len(self.sizes), ml))
        for k, (a, b) in enumerate(zip(self.starts, self.ends, strict=True)):
            self.G[k, a:b] = 1.0
        self.ones = np.ones(ml)
        self.daqp_A = self.A[self.n:]  # the general rows DAQP sees: hard rows, then levels

    def load_problem(self, problem: Problem) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Copy a normalised problem into the buffers; return fresh ``(lo, hi, w)``.

        When the problem carries its stacked level rows already (e.g. a controller's contiguous
        row buffer, ``problem.__dict__["stacked"]``) one copy moves every level.
        """
        hard = problem.hard
        A = self.A
        if self.mh:
            A[self.hard_rows] = hard.A
        stacked = problem.__dict__.get("stacked")
        if stacked is not None:
            A[self.head:] = stacked.A
            sides = np.concatenate((problem.lower, hard.lo, stacked.lo,
                                    problem.upper, hard.hi, stacked.hi))
            w = stacked.w
        else:
            levels = problem.levels
            for block, rows in zip(levels, self.level_rows, strict=True):
                A[rows] = block.A
            sides = np.concatenate([problem.lower, hard.lo, *[b.lo for b in levels],
                                    problem.upper, hard.hi, *[b.hi for b in levels]])
            w = np.concatenate([b.w for b in levels]) if levels else self.ones
        lo, hi = sides[: self.M], sides[self.M:]
        self.clamp(lo, hi)
        return lo, hi, w

    def clamp(self, lo: FloatArray, hi: FloatArray) -> None:
        """Write DAQP's clamped sides ``bl = max(lo, -1e30)``, ``bu = min(hi, 1e30)``."""
        np.minimum(hi, DAQP_INF, out=self.bu)
        np.maximum(lo, -DAQP_INF, out=self.bl)

    def slacks(self, x: FloatArray, lo: FloatArray, hi: FloatArray) -> FloatArray:
        """Signed slack of every box bound, hard row and level row at ``x`` (fresh (M,) array).

        ``s = z - min(max(z, lo), hi)`` with ``z = A_aug x``: positive above ``hi``, negative
        below ``lo``, zero inside (``Block.violation`` on every block at once).
        """
        z = self.A.dot(x)
        s = np.maximum(z, lo)
        np.minimum(s, hi, out=s)
        np.subtract(z, s, out=s)
        return s


def finite_abs_max(*sides: FloatArray) -> float:
    """``max(1, max |v|)`` over the finite entries of the given side vectors."""
    top = 1.0
    for side in sides:
        values = side.tolist()
        if values:
            big = max(max(values), -min(values))
            if big == math.inf:
                big = max((abs(v) for v in values if abs(v) != math.inf), default=0.0)
            top = max(top, big)
    return top


def box_and_hard_violation(s: FloatArray, head: int) -> float:
    """Largest violation of the box and hard rows from the first ``head`` slacks (0 if none).

    ``s`` must be finite (the caller checked it); the value equals
    :func:`uvms_qp.hqp.evaluate.hard_violation`.
    """
    if not head:
        return 0.0
    values = s[:head].tolist()
    return max(max(values), -min(values), 0.0)
