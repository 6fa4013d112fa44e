"""The hard set of a problem (box and hard rows): feasibility, a point of it, projection onto it."""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import linprog

from .._validation import FloatArray
from ..rows import Rows
from .linalg import one_blas_thread
from .problem import Problem


def polish_hard(problem: Problem, x: FloatArray) -> FloatArray:
    """Remove round-off outside the hard set by alternating projections.

    Clip to the box, then take a least-norm step onto the violated hard rows with the variables
    that are off their bounds, repeated (at most 50 times) until every hard violation is below
    1e-12 relative. Back-ends leave violations of about 1e-9 (interior-point tolerances, DAQP's
    soft-row regularisation); the steps are of that size, far below the level tolerances.

    Returns:
        A fresh array inside the box.
    """
    lower, upper = problem.lower, problem.upper
    x = np.minimum(np.maximum(x, lower), upper)
    hard = problem.hard
    if not hard.m:
        return x
    tol = 1e-12 * problem.hard_scale
    with one_blas_thread:  # (least squares: a small problem's solve runs without the limit)
        return _project(problem, hard, x, tol)


def _project(problem: Problem, hard: Rows, x: FloatArray, tol: float) -> FloatArray:
    """The alternating projections of :func:`polish_hard` from ``x`` (inside the box)."""
    lower, upper = problem.lower, problem.upper
    for _ in range(50):
        y = hard.A @ x
        s = y - np.minimum(np.maximum(y, hard.lower), hard.upper)
        bad = np.abs(s) > tol
        if not bad.any():
            break
        # move only variables off their bounds, so that clipping does not undo the step
        free = (x > lower) & (x < upper)
        if not free.any():
            free[:] = True
        step = np.zeros_like(x)
        step[free] = np.linalg.lstsq(hard.A[bad][:, free], s[bad], rcond=None)[0]
        x = np.minimum(np.maximum(x - step, lower), upper)
    return x


def hard_feasible(problem: Problem, time_limit: float | None = None) -> bool:
    """Independent feasibility check of the hard box and rows (HiGHS LP through SciPy).

    Args:
        problem: The problem whose hard set is judged.
        time_limit: Time HiGHS may take [s] (None: no limit). An LP stopped by it has proven
            nothing, and the hard set counts as feasible (the caller reports a back-end
            failure, not an empty hard set).

    Returns:
        False only when the hard set is proven empty.
    """
    if (problem.lo[:problem.head] > problem.hi[:problem.head]).any():
        return False  # an empty interval: no LP needed (and SciPy refuses such bounds)
    if not problem.hard.m:
        return True  # a box with every interval nonempty: no LP needed
    return _hard_lp(problem, time_limit).status != 2


def hard_point(problem: Problem) -> FloatArray | None:
    """A point of the hard set (a vertex from HiGHS' LP through SciPy), or None if none found."""
    if not hard_feasible(problem):
        return None
    res = _hard_lp(problem)
    return np.asarray(res.x, dtype=np.float64) if res.status == 0 and res.x is not None else None


def _hard_lp(problem: Problem, time_limit: float | None = None) -> Any:
    """``linprog`` of the zero objective over the hard box and rows (within ``time_limit`` [s])."""
    hard = problem.hard
    A_ub, b_ub, A_eq, b_eq = [], [], None, None
    if hard.m:
        eq = hard.lower == hard.upper
        ineq = ~eq
        hi, lo = hard.upper[ineq], hard.lower[ineq]
        up, dn = np.isfinite(hi), np.isfinite(lo)
        if up.any():
            A_ub.append(hard.A[ineq][up])
            b_ub.append(hi[up])
        if dn.any():
            A_ub.append(-hard.A[ineq][dn])
            b_ub.append(-lo[dn])
        if eq.any():
            A_eq, b_eq = hard.A[eq], hard.lower[eq]
    bounds = [(None if not np.isfinite(lo) else lo, None if not np.isfinite(hi) else hi)
              for lo, hi in zip(problem.lower, problem.upper, strict=True)]
    return linprog(np.zeros(problem.n), A_ub=np.vstack(A_ub) if A_ub else None,
                   b_ub=np.concatenate(b_ub) if b_ub else None, A_eq=A_eq, b_eq=b_eq,
                   bounds=bounds, method="highs",
                   options=None if time_limit is None else {"time_limit": max(time_limit, 1e-6)})
