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

from typing import Any

import numpy as np

from ..._validation import FloatArray, as_scalar
from ...errors import InputError
from ..problem import Problem
from ..registry import SolverSpec
from . import Answer

_OPTIONS = ("rcond", "atol")


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

    Trusted entry: every level must hold equality rows only (``lo`` is used as the target
    ``b``), the arrays are not validated, and the hard box and rows are ignored.

    Args:
        problem: A problem whose levels are all equality rows.
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
        d = np.sqrt(level.weights if level.weights is not None else np.ones(level.m))
        At = (d[:, None] * level.A) * w_isqrt[None, :]
        M = At @ P
        U, sv, Vt = np.linalg.svd(M, full_matrices=False)
        keep = sv > max(atol, rcond * float(np.linalg.norm(At)))
        if not keep.any():
            continue  # no freedom left for this level (or zero rows): no contribution
        Mp = (Vt[keep].T / sv[keep]) @ U[:, keep].T
        u = u + Mp @ (d * level.lower - At @ u)
        P = P - Mp @ M
        P = 0.5 * (P + P.T)  # keep the projector symmetric against round-off
    return w_isqrt * u


def inequality_rows(problem: Problem) -> tuple[int, int] | None:
    """``(level, row)`` of the first inequality row of the levels, or None."""
    for k, level in enumerate(problem.levels):
        ineq = np.flatnonzero(level.lower != level.upper)
        if ineq.size:
            return k, int(ineq[0])
    return None


class NullspaceBackend:
    """Recursive null-space projection: equality levels only, the hard set is not enforced.

    The measurement reports any bound or hard row the closed form breaks.

    Args:
        spec: Registry entry (tolerances).
        rcond: Singular-value cut-off of the pseudoinverses relative to the norm of each
            level's unprojected rows (rank decision, see :func:`nullspace_solve`).
        atol: Absolute singular-value floor of the rank decision.

    Raises:
        InputError: a negative or non-finite ``rcond`` / ``atol``, or another option.
    """

    def __init__(self, spec: SolverSpec, **options: Any) -> None:
        known = ", ".join(sorted((*_OPTIONS, "hard_tol", "level_tol")))
        for key in options:
            if key not in _OPTIONS:
                raise InputError(f"options: unknown option {key!r} for solver {spec.name!r} "
                                 f"(known: {known})")
        self.spec = spec
        self.rcond = as_scalar(options.get("rcond", 1e-10), "options['rcond']", nonnegative=True)
        self.atol = as_scalar(options.get("atol", 0.0), "options['atol']", nonnegative=True)

    def reset(self) -> None:
        """Nothing to forget (a closed form)."""

    def solve(self, problem: Problem) -> Answer:
        """Solve the equality hierarchy (the measurement reports any broken bound or hard row).

        Raises:
            InputError: an inequality row in a level.
        """
        where = inequality_rows(problem)
        if where is not None:
            raise InputError(
                f"levels[{where[0]}] row {where[1]}: the nullspace solver handles equality rows "
                "only; use solver='daqp' or a cascade for inequality levels")
        return Answer(nullspace_solve(problem, self.rcond, self.atol))
