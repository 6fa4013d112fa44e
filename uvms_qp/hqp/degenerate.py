"""Reduction of degenerate level rows before a back-end sees them.

A row of level k that lies in the span of the equality rows above it (hard equality rows and
the equality rows of levels < k) has the same value ``a x`` at every point that keeps the
higher levels optimal: the values of a level's equality rows are unique over its optimal set
(the level's weighted least-squares objective is strictly convex in them). Its violation is
therefore a constant of the lower level's problem, and the row can be removed from the solve and
measured afterwards without changing the lexicographic optimum. Zero rows are the trivial case.
Back-ends do not all survive such rows: DAQP 0.11's hierarchical mode drops a level whose row
repeats a higher one (``x2 = 5`` above ``x2 = 3`` returns ``x = 0`` with exit flag 1), and a zero
row with a nonzero target makes it fail.

The decision is a rank decision: a row counts as dependent when its distance to that span is at
most ``rtol`` times its norm, or when its norm is at most ``ztol`` times the largest row norm of
the problem (a "tiny" row with a nonzero target is treated as zero; the violation it carries
is still measured on the full problem).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._validation import FloatArray
from .problem import Problem
from .tolerances import DEPENDENT_TOL, ZERO_ROW_TOL

RTOL, ZTOL = DEPENDENT_TOL, ZERO_ROW_TOL  # (:mod:`uvms_qp.hqp.tolerances`)


def dependent_rows(A: FloatArray, lo: FloatArray, hi: FloatArray, n: int, mh: int,
                   sizes: Sequence[int], rtol: float = RTOL, ztol: float = ZTOL) -> np.ndarray:
    """Mask of the level rows that are constant over the higher levels' optimal set.

    Args:
        A: Stacked rows ``[I_n; A_H; A_0; ...]``, shape (M, n).
        lo: Lower sides, shape (M,).
        hi: Upper sides, shape (M,); ``lo == hi`` marks an equality row.
        n: Number of variables.
        mh: Number of hard rows.
        sizes: Rows per level, highest priority first.
        rtol: Relative distance to the span of the equality rows above.
        ztol: Norm, relative to the largest row norm, below which a row is zero.

    Returns:
        Boolean mask over the level rows (length ``sum(sizes)``); True rows can be removed from
        the solve (their violation is measured on the full problem afterwards).
    """
    head = n + mh
    norms = np.linalg.norm(A[head:], axis=1) if A.shape[0] > head else np.zeros(0)
    big = float(norms.max(initial=0.0))
    out = norms <= ztol * max(big, np.finfo(float).tiny)
    eq = lo == hi
    basis = np.zeros((n, 0))  # orthonormal basis of the equality rows seen so far
    if mh:
        hard_eq = A[n:head][eq[n:head]]
        basis = _extend(basis, hard_eq, rtol)
    start = 0
    for m in sizes:
        rows = A[head + start: head + start + m]
        if basis.shape[1] and m:
            proj = rows - (rows @ basis) @ basis.T
            dist = np.linalg.norm(proj, axis=1)
            out[start: start + m] |= dist <= rtol * norms[start: start + m]
        level_eq = rows[eq[head + start: head + start + m] & ~out[start: start + m]]
        basis = _extend(basis, level_eq, rtol)
        start += m
    return out


def _extend(basis: FloatArray, rows: FloatArray, rtol: float) -> FloatArray:
    """Orthonormal basis of ``span(basis) + span(rows)`` (rank decided by ``rtol``)."""
    if not rows.shape[0] or basis.shape[1] == basis.shape[0]:
        return basis
    R = rows.T - basis @ (basis.T @ rows.T)
    U, s, _ = np.linalg.svd(R, full_matrices=False)
    ref = float(np.linalg.norm(rows, axis=1).max())
    keep = s > rtol * max(ref, np.finfo(float).tiny)
    return np.hstack((basis, U[:, keep]))


def reduce_levels(A: FloatArray, lo: FloatArray, hi: FloatArray, n: int, mh: int,
                  sizes: Sequence[int], w: FloatArray, rtol: float = RTOL, ztol: float = ZTOL
                  ) -> tuple[FloatArray, FloatArray, FloatArray, tuple[int, ...], FloatArray,
                             np.ndarray]:
    """The stacked problem without its dependent level rows (:func:`dependent_rows`).

    Returns:
        ``(A, lo, hi, sizes, w, dropped)``: the reduced stacked arrays (box and hard rows kept),
        the reduced level sizes (a level may become empty) and the mask of dropped level rows.
        Solve the reduced problem, then measure the answer on the full one.
    """
    drop = dependent_rows(A, lo, hi, n, mh, sizes, rtol, ztol)
    keep = np.concatenate((np.ones(n + mh, dtype=bool), ~drop))
    new_sizes = []
    start = 0
    for m in sizes:
        new_sizes.append(int((~drop[start: start + m]).sum()))
        start += m
    return A[keep], lo[keep], hi[keep], tuple(new_sizes), w[~drop], drop


class Reduction:
    """A problem without some of its level rows, refilled from the full problem on demand.

    Args:
        problem: The full problem.
        drop: Mask of the level rows to leave out (length ``sum(problem.sizes)``), e.g.
            :func:`dependent_rows`.

    Attributes:
        drop: The mask.
        problem: The reduced problem (its own buffers; the same box, hard rows and metric).
    """

    __slots__ = ("drop", "problem", "rows", "version", "wrows")

    def __init__(self, problem: Problem, drop: np.ndarray) -> None:
        head = problem.head
        self.drop = drop
        self.wrows = np.flatnonzero(~drop)
        self.rows = np.concatenate((np.arange(head), head + self.wrows))
        sizes, start = [], 0
        for m in problem.sizes:
            sizes.append(int((~drop[start: start + m]).sum()))
            start += m
        # ``sides[:, rows]`` comes out column-major; its rows (``lo``, ``hi``) must be
        # contiguous, because a back-end reads them in place on every later solve
        self.problem = Problem(problem.n, problem.mh, sizes, problem.W,
                               A=problem.A[self.rows],
                               sides=np.ascontiguousarray(problem.sides[:, self.rows]),
                               w=problem.w[self.wrows])
        self.version = problem.weights_version

    def fill(self, problem: Problem) -> Problem:
        """The reduced problem with the current rows, sides, weights and metric of ``problem``."""
        reduced = self.problem
        np.take(problem.A, self.rows, axis=0, out=reduced.A)
        np.take(problem.sides, self.rows, axis=1, out=reduced.sides)
        if problem.weights_version != self.version:
            reduced.set_weights(problem.w[self.wrows])
            self.version = problem.weights_version
        reduced.W = problem.W
        return reduced
