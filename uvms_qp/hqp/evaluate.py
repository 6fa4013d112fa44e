"""Turn a back-end's raw ``x`` into a :class:`HierarchyResult` with verified diagnostics.

Every back-end ends here, so statuses mean the same thing everywhere: the hard box and rows are
measured at ``x`` (never trusted from the back-end), each level's weighted residual
``r_k = sqrt(sum_i w_i s_i^2)`` is recomputed, and the first level with
``r_k > level_tol * scale_k`` (``scale_k = max(1, max |finite side|)``) is reported as unmet.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import FloatArray
from .problem import Problem
from .result import HierarchyResult, StackedResult, Status
from .workspace import Workspace, finite_abs_max

_CLAIMED = (Status.OPTIMAL, Status.LEVEL_INFEASIBLE)


def hard_violation(problem: Problem, x: FloatArray) -> float:
    """Largest violation of the hard box and hard rows at ``x`` (0 when feasible)."""
    v = max(0.0, float((problem.lower - x).max()), float((x - problem.upper).max()))
    if problem.hard.m:
        v = max(v, float(np.abs(problem.hard.violation(x)).max()))
    return v


def hard_scale(problem: Problem) -> float:
    """Magnitude of the finite hard sides: ``max(1, max |finite bound or side|)``."""
    return problem.hard_scale


def polish_hard(problem: Problem, x: FloatArray) -> FloatArray:
    """Remove round-off outside the hard set by alternating projections.

    Clip to the box, then take a least-norm step onto the violated hard rows with the variables
    that are off their bounds, repeated (at most 50 times) until every hard violation is below
    1e-12 relative. Back-ends leave violations of about 1e-9 (interior-point tolerances, DAQP's
    soft-row regularisation); the steps are of that size, far below the level tolerances.
    """
    x = np.minimum(np.maximum(x, problem.lower), problem.upper)
    hard = problem.hard
    if not hard.m:
        return x
    tol = 1e-12 * hard_scale(problem)
    for _ in range(50):
        s = hard.violation(x)
        bad = np.abs(s) > tol
        if not bad.any():
            break
        # move only variables off their bounds, so that clipping does not undo the step
        free = (x > problem.lower) & (x < problem.upper)
        if not free.any():
            free[:] = True
        step = np.zeros_like(x)
        step[free] = np.linalg.lstsq(hard.A[bad][:, free], s[bad], rcond=None)[0]
        x = np.minimum(np.maximum(x - step, problem.lower), problem.upper)
    return x


def safe_x(problem: Problem, x: FloatArray | None) -> FloatArray:
    """Return a finite stand-in for a missing or non-finite ``x``: zero clipped to the box."""
    if x is not None and np.all(np.isfinite(x)):
        return x
    return np.clip(np.zeros(problem.n), problem.lower, problem.upper)


def evaluate(
    problem: Problem,
    x: FloatArray | None,
    solver: str,
    status: Status,
    message: str,
    *,
    level_tol: float,
    hard_tol: float,
    solve_time: float,
    info: dict[str, object] | None = None,
) -> HierarchyResult:
    """Measure ``x`` against the problem and build the result.

    Args:
        problem: The normalised problem.
        x: The back-end's solution (None or non-finite on failure).
        solver: Back-end name for the report.
        status: The back-end's own verdict; OPTIMAL means "the back-end claims success".
        message: Back-end detail to keep in the result.
        level_tol: Relative tolerance deciding whether a level is met.
        hard_tol: Relative tolerance on the hard box and rows.
        solve_time: Wall time of the solve [s].
        info: Back-end extras.

    Returns:
        The result; a claimed success that violates the hard rows is downgraded to BACKEND_ERROR.
    """
    if x is None or not np.all(np.isfinite(x)):
        if status in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE):
            status = Status.BACKEND_ERROR
            message = (message + "; " if message else "") + "back-end returned no finite x"
        x = safe_x(problem, x)
    stacked = problem.stacked
    offsets = problem.offsets
    if stacked.m and all(b.m for b in problem.levels):
        y = stacked.A @ x
        s_all = y - np.minimum(np.maximum(y, stacked.lo), stacked.hi)
        res = np.sqrt(np.add.reduceat(stacked.w * s_all * s_all, offsets))
        ends = [*offsets[1:].tolist(), stacked.m]
        slacks = [s_all[i:j] for i, j in zip(offsets.tolist(), ends, strict=True)]
    else:
        slacks = [block.violation(x) for block in problem.levels]
        res = np.array([np.sqrt(b.w @ (v * v)) for b, v in zip(problem.levels, slacks,
                                                                strict=True)])
    residuals = res.tolist()
    hv = hard_violation(problem, x)
    infeasible_level = None
    if status in (Status.OPTIMAL, Status.LEVEL_INFEASIBLE):
        if hv > hard_tol * problem.hard_scale:
            status = Status.BACKEND_ERROR
            message = (message + "; " if message else "") + f"hard rows violated by {hv:.2e}"
        else:
            status = Status.OPTIMAL
            unmet = np.flatnonzero(res > level_tol * problem.level_scales)
            if unmet.size:
                infeasible_level = int(unmet[0])
                status = Status.LEVEL_INFEASIBLE
    tol_lo, tol_hi = problem.active_tol
    return HierarchyResult(
        x=x,
        status=status,
        solver=solver,
        level_residuals=residuals,
        level_slacks=slacks,
        infeasible_level=infeasible_level,
        active_lower=x - problem.lower <= tol_lo,
        active_upper=problem.upper - x <= tol_hi,
        hard_violation=hv,
        solve_time=solve_time,
        message=message,
        info=info or {},
    )


def evaluate_stacked(
    ws: Workspace,
    x: FloatArray,
    s: FloatArray,
    lo: FloatArray,
    hi: FloatArray,
    w: FloatArray,
    hv: float,
    solver: str,
    status: Status,
    message: str,
    *,
    level_tol: float,
    hard_tol: float,
    solve_time: float,
    info: dict[str, object] | None = None,
) -> HierarchyResult:
    """:func:`evaluate` on the stacked layout of a :class:`~uvms_qp.hqp.workspace.Workspace`.

    Same measurements and decisions as :func:`evaluate`, in a few array operations:
    ``r = sqrt(G (w * s_L * s_L))`` for the level residuals, the largest ``|s|`` of the box and
    hard rows for the hard violation; the scales ``max(1, max |finite side|)`` are computed only
    when a value exceeds its bare tolerance (a scale is never below 1). Slacks and active-bound
    masks are built on first access (:class:`~uvms_qp.hqp.result.StackedResult`).

    Args:
        ws: The workspace whose ``A`` holds the problem's rows.
        x: The finite solution, shape (n,).
        s: ``ws.slacks(x, lo, hi)``: signed slacks of box, hard rows and level rows, finite.
        lo: Stacked lower sides ``[lower; lo_H; lo_1; ...]`` (fresh, kept by the result).
        hi: Stacked upper sides.
        w: Level row weights, shape (sum m_k,).
        hv: Largest box/hard violation at ``x``
            (:func:`~uvms_qp.hqp.workspace.box_and_hard_violation` of ``s``).
        solver: Back-end name.
        status: The back-end's verdict (OPTIMAL or LEVEL_INFEASIBLE: claims success).
        message: Back-end detail.
        level_tol: Relative tolerance deciding whether a level is met.
        hard_tol: Relative tolerance on the hard box and rows.
        solve_time: Wall time of the solve [s].
        info: Back-end extras.
    """
    head = ws.head
    sl = s[head:]
    r = np.sqrt(ws.G.dot(w * sl * sl))
    residuals = r.tolist()
    infeasible_level = None
    if status in _CLAIMED:
        if hv > hard_tol and hv > hard_tol * finite_abs_max(lo[:head], hi[:head]):
            status = Status.BACKEND_ERROR
            message = (message + "; " if message else "") + f"hard rows violated by {hv:.2e}"
        else:
            status = Status.OPTIMAL
            for k, value in enumerate(residuals):
                if value > level_tol:
                    a, b = head + ws.starts[k], head + ws.ends[k]
                    if value > level_tol * finite_abs_max(lo[a:b], hi[a:b]):
                        infeasible_level = k
                        status = Status.LEVEL_INFEASIBLE
                        break
    return StackedResult(x, status, solver, residuals, infeasible_level, hv, solve_time, message,
                         info or {}, slacks=s, head=head, spans=ws.spans, lower=lo, upper=hi)


def hard_feasible(problem: Problem) -> bool:
    """Independent feasibility check of the hard box and rows (HiGHS LP through SciPy)."""
    return _hard_lp(problem).status != 2


def hard_point(problem: Problem) -> FloatArray | None:
    """A point of the hard set (a vertex from HiGHS' LP through SciPy), or None if none found."""
    res = _hard_lp(problem)
    return np.asarray(res.x, dtype=np.float64) if res.status == 0 and res.x is not None else None


def _hard_lp(problem: Problem) -> Any:
    """``linprog`` of the zero objective over the hard box and rows."""
    from scipy.optimize import linprog

    hard = problem.hard
    A_ub, b_ub, A_eq, b_eq = [], [], None, None
    if hard.m:
        ineq = ~hard.eq
        hi, lo = hard.hi[ineq], hard.lo[ineq]
        up, dn = np.isfinite(hi), np.isfinite(lo)
        if up.any():
            A_ub.append(hard.A[ineq][up])
            b_ub.append(hi[up])
        if dn.any():
            A_ub.append(-hard.A[ineq][dn])
            b_ub.append(-lo[dn])
        if hard.eq.any():
            A_eq, b_eq = hard.A[hard.eq], hard.lo[hard.eq]
    bounds = [(None if not np.isfinite(lo) else lo, None if not np.isfinite(hi) else hi)
              for lo, hi in zip(problem.lower, problem.upper, strict=True)]
    return linprog(np.zeros(problem.n), A_ub=np.vstack(A_ub) if A_ub else None,
                   b_ub=np.concatenate(b_ub) if b_ub else None, A_eq=A_eq, b_eq=b_eq,
                   bounds=bounds, method="highs")
