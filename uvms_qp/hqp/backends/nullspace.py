"""Closed-form recursive null-space solution of an equality hierarchy in the metric W.

The Siciliano-Slotine recursion extends the two-task priority formula of
``000_7b5f597fe4e36aa4.txt, Eq. (10)``,
``zeta = J1^# x1_dot + (J2 N1)^# (x2_dot - J2 J1^# x1_dot)``, ``N1 = I - J1^# J1``,
to p levels. With ``u = W^(1/2) x``, ``Ã_k = D_k A_k W^(-1/2)`` and ``b̃_k = D_k b_k``
(``D_k = diag(sqrt(w_k))`` the row weights):

    u_0 = 0, P_0 = I
    u_k = u_{k-1} + (Ã_k P_{k-1})^+ (b̃_k - Ã_k u_{k-1})
    P_k = P_{k-1} - (Ã_k P_{k-1})^+ (Ã_k P_{k-1})
    x   = W^(-1/2) u_p

which is the weighted-pseudoinverse form (``000_7b5f597fe4e36aa4.txt, Eq. (17)``) at every level.
Each level gets the weighted least-squares optimum inside the null space of the levels above, and
the result has minimum ``x' W x`` among the lexicographic optima. Inequality levels are refused;
the hard box and rows are only checked, never enforced.
"""

from __future__ import annotations

import numpy as np

from ..._validation import FloatArray
from ...errors import InputError
from ..evaluate import hard_scale, hard_violation
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status
from . import BackendOutput


def nullspace_solve(problem: Problem, rcond: float = 1e-10, atol: float = 0.0) -> FloatArray:
    r"""Recursive null-space solution of an equality hierarchy in the metric W (no checks).

    The recursion of the module docstring (``000_7b5f597fe4e36aa4.txt, Eq. (10)`` extended to p
    levels, weighted pseudoinverse of ``000_7b5f597fe4e36aa4.txt, Eq. (17)``). The rank of each
    projected block ``M_k = Ã_k P_{k-1}`` is decided against the level's *unprojected* size:
    singular values ``sigma_i(M_k) <= max(atol, rcond * |Ã_k|_F)`` are dropped. ``P_{k-1}`` is a
    projector (entries of order 1), so when the levels above have used up all freedom ``M_k`` is
    pure round-off, ``|M_k| ~ 1e-16 |Ã_k|``; a cut-off relative to ``M_k`` itself would keep
    that round-off and invert it (``x ~ 1e15``), this one gives the level zero contribution.
    A level whose rows are all zero contributes nothing either.

    Trusted entry for hot loops: every level must hold equality rows only (``lo`` is used as the
    target ``b``), the arrays are not validated, and the hard box and rows are ignored.

    Args:
        problem: A normalised problem whose levels are all equality rows.
        rcond: Cut-off relative to the Frobenius norm of each level's weighted rows ``Ã_k``.
        atol: Absolute floor of the cut-off (same units as ``Ã_k``; 0 for a purely relative
            decision, e.g. ``1e-9`` to also treat rows of norm below it as singular).

    Returns:
        x, shape (n,), finite for finite input; minimum ``x' W x`` among the lexicographic
        optima of the equality levels.
    """
    n = problem.n
    w_isqrt = 1.0 / np.sqrt(problem.W)
    u = np.zeros(n)
    P = np.eye(n)
    for level in problem.levels:
        if level.m == 0:
            continue
        d = np.sqrt(level.w)
        At = (d[:, None] * level.A) * w_isqrt[None, :]
        M = At @ P
        U, sv, Vt = np.linalg.svd(M, full_matrices=False)
        keep = sv > max(atol, rcond * float(np.linalg.norm(At)))
        if not keep.any():
            continue  # no freedom left for this level (or zero rows): no contribution
        Mp = (Vt[keep].T / sv[keep]) @ U[:, keep].T
        u = u + Mp @ (d * level.lo - At @ u)
        P = P - Mp @ M
        P = 0.5 * (P + P.T)  # keep the projector symmetric against round-off
    return w_isqrt * u


class NullspaceBackend:
    """Recursive null-space projection (equality levels only).

    Args:
        spec: Registry entry (tolerances).
        rcond: Singular-value cut-off of the pseudoinverses relative to the norm of each
            level's unprojected rows (rank decision, see :func:`nullspace_solve`).
        atol: Absolute singular-value floor of the rank decision.
    """

    def __init__(self, spec: SolverSpec, rcond: float = 1e-10, atol: float = 0.0) -> None:
        self.spec = spec
        self.rcond = float(rcond)
        self.atol = float(atol)

    def solve(self, problem: Problem) -> BackendOutput:
        """Solve the equality hierarchy; report (not enforce) hard-row violations."""
        for k, level in enumerate(problem.levels):
            if not level.all_equality:
                i = int(np.flatnonzero(~level.eq)[0])
                raise InputError(
                    f"levels[{k}] row {i}: the nullspace solver handles equality rows only; "
                    "use solver='daqp' or a cascade for inequality levels")
        x = nullspace_solve(problem, self.rcond, self.atol)
        hv = hard_violation(problem, x)
        if hv > self.spec.hard_tol * hard_scale(problem):
            where = self._where(problem, x)
            return BackendOutput(
                x, Status.BACKEND_ERROR,
                f"the null-space solution violates {where} by {hv:.3g}; the nullspace solver "
                "cannot enforce bounds (use solver='daqp' or a cascade)")
        return BackendOutput(x)

    @staticmethod
    def _where(problem: Problem, x: np.ndarray) -> str:
        lo = problem.lower - x
        hi = x - problem.upper
        i_lo, i_hi = int(np.argmax(lo)), int(np.argmax(hi))
        if lo[i_lo] > 0 and lo[i_lo] >= hi[i_hi]:
            return f"lower bound {i_lo}"
        if hi[i_hi] > 0:
            return f"upper bound {i_hi}"
        return "a hard row"
