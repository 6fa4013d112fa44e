"""Closed-form recursive null-space solution of an equality hierarchy in the metric W.

The Siciliano-Slotine recursion extends the two-task priority formula of
Soylu et al. (2007), Eq. (10):
``zeta = J1^# x1_dot + (J2 N1)^# (x2_dot - J2 J1^# x1_dot)``, ``N1 = I - J1^# J1``,
to p levels. With ``u = W^(1/2) x``, ``Ã_k = D_k A_k W^(-1/2)`` and ``b̃_k = D_k b_k``
(``D_k = diag(sqrt(w_k))`` the row weights):

    u_0 = 0, P_0 = I
    u_k = u_{k-1} + (Ã_k P_{k-1})^+ (b̃_k - Ã_k u_{k-1})
    P_k = P_{k-1} - (Ã_k P_{k-1})^+ (Ã_k P_{k-1})
    x   = W^(-1/2) u_p

which is the weighted-pseudoinverse form (Soylu et al. (2007), Eq. (17)) at every level.
Each level gets the weighted least-squares optimum inside the null space of the levels above, and
the result has minimum ``x' W x`` among the lexicographic optima. Inequality levels are refused;
the hard box and rows are only checked, never enforced.

Near-singular levels get a rank decision with damping, so that the answer stays bounded: a
singular value of the projected level below ``rcond`` times the level's unprojected norm is zero
(no contribution: round-off of the projection), and one below ``damping`` times that norm
(``epsilon``) is inverted as ``sigma / epsilon^2`` instead of ``1 / sigma`` (the variable damping
of Nakamura and Hanafusa (1986), ``sigma / (sigma^2 + lambda^2)`` with
``lambda^2 = epsilon^2 - sigma^2``, continuous at ``sigma = epsilon``). Along a damped direction
the answer is at most ``|b| / epsilon`` and the level's row space is still removed from the
freedom of the levels below. A damped answer is not that level's optimum: the optimality
certificate of the measurement judges it like any answer, and the result's ``info["damped"]``
lists the damped levels. Damping only shrinks the answer along a weak direction
(``sigma / epsilon^2 <= 1 / sigma``), so the closed form never asks for more than the undamped
optimum would; its status is ``optimal`` only when the certificate proves every level of the
damped answer (met, or certified optimal: the damping cost no level more than its tolerance).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from time import perf_counter
from typing import Any

import numpy as np

from ..._validation import FloatArray, as_scalar
from ...errors import InputError
from ..problem import Problem
from ..registry import SolverSpec
from . import Answer

_OPTIONS = ("rcond", "atol", "damping")
#: Default damping threshold, relative to the norm of each level's weighted rows.
DAMPING = 1e-6


def nullspace_solve(problem: Problem, rcond: float = 1e-10, atol: float = 0.0,
                    damping: float = DAMPING) -> tuple[FloatArray, tuple[int, ...]]:
    r"""Recursive null-space solution of an equality hierarchy in the metric W (no checks).

    The recursion of the module docstring (Soylu et al. (2007), Eq. (10), extended to p
    levels, weighted pseudoinverse of their Eq. (17)). The rank of each
    projected block ``M_k = Ã_k P_{k-1}`` is decided against the level's *unprojected* size
    ``nu_k = |Ã_k|_F``: singular values ``sigma_i(M_k) <= max(atol, rcond * nu_k)`` are dropped.
    ``P_{k-1}`` is a projector (entries of order 1), so when the levels above have used up all
    freedom ``M_k`` is pure round-off, ``|M_k| ~ 1e-16 |Ã_k|``; a cut-off relative to ``M_k``
    itself would keep that round-off and invert it (``x ~ 1e15``), this one gives the level zero
    contribution. A level whose rows are all zero contributes nothing either. Singular values
    kept but below ``epsilon_k = damping * nu_k`` are damped (``sigma / epsilon_k^2``). Each
    level is scaled by ``1 / nu_k`` before its SVD, so rows of any magnitude (1e-300 as 1e100)
    are decomposed at the scale of 1.

    Trusted entry: every level must hold equality rows only (``lo`` is used as the target
    ``b``), the arrays are not validated, and the hard box and rows are ignored.

    Args:
        problem: A problem whose levels are all equality rows.
        rcond: Cut-off relative to the Frobenius norm of each level's weighted rows ``Ã_k``.
        atol: Absolute floor of the cut-off (same units as ``Ã_k``; 0 for a purely relative
            decision, e.g. ``1e-9`` to also treat rows of norm below it as singular).
        damping: Damping threshold relative to ``nu_k`` (0: none, the plain pseudoinverse).

    Returns:
        ``(x, damped)``: x, shape (n,), finite for finite input (minimum ``x' W x`` among the
        lexicographic optima of the equality levels when no level was damped), and the indices
        of the levels whose inverse was damped.
    """
    n = problem.n
    w_isqrt = 1.0 / np.sqrt(problem.W)
    u = np.zeros(n)
    P = np.eye(n)
    damped = []
    for k, level in enumerate(problem.levels):
        if level.m == 0:
            continue
        d = np.sqrt(level.weights if level.weights is not None else np.ones(level.m))
        At = (d[:, None] * level.A) * w_isqrt[None, :]
        nu = float(np.linalg.norm(At))
        if not nu > 0.0:
            continue  # zero rows: no contribution
        U, sv, Vt = np.linalg.svd((At / nu) @ P, full_matrices=False)
        keep = sv > max(atol / nu, rcond)
        if not keep.any():
            continue  # no freedom left for this level: no contribution
        s, Uk, Vk = sv[keep], U[:, keep], Vt[keep]
        eps = damping
        inv = np.where(s >= eps, 1.0 / s, s / (eps * eps)) if eps > 0.0 else 1.0 / s
        if eps > 0.0 and s[-1] < eps:
            damped.append(k)
        u = u + (Vk.T * (inv / nu)) @ (Uk.T @ (d * level.lower - At @ u))
        P = P - Vk.T @ Vk
        P = 0.5 * (P + P.T)  # keep the projector symmetric against round-off
    return w_isqrt * u, tuple(damped)


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
        damping: Damping threshold relative to the same norm (default :data:`DAMPING`; 0 for
            the plain pseudoinverse).

    Raises:
        InputError: a negative or non-finite ``rcond`` / ``atol`` / ``damping``, or another
            option.
    """

    factorises = True  # (an SVD per level)

    def __init__(self, spec: SolverSpec, **options: Any) -> None:
        known = ", ".join(sorted((*_OPTIONS, "hard_tol", "level_tol")))
        for key in options:
            if key not in _OPTIONS:
                raise InputError(f"options: unknown option {key!r} for solver {spec.name!r} "
                                 f"(known: {known})")
        self.spec = spec
        self.rcond = as_scalar(options.get("rcond", 1e-10), "options['rcond']", nonnegative=True)
        self.atol = as_scalar(options.get("atol", 0.0), "options['atol']", nonnegative=True)
        self.damping = as_scalar(options.get("damping", DAMPING), "options['damping']",
                                 nonnegative=True)
        self.end = math.inf  # a closed form: nothing to stop
        self.clock: Callable[[], float] = perf_counter

    def reset(self) -> None:
        """Nothing to forget (a closed form)."""

    def reduce(self, problem: Problem) -> bool:
        """Nothing to reduce: the rank decision leaves dependent rows out by design."""
        return False

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
        x, damped = nullspace_solve(problem, self.rcond, self.atol, self.damping)
        if not damped:
            return Answer(x)
        # a claim like any other: the measurement and the certificate decide whether the damped
        # answer is still the optimum (a damped direction the level hardly asks for changes
        # nothing), and say which level it cost when it is not
        return Answer(x, message=f"damped level(s) {', '.join(map(str, damped))}",
                      info={"damped": damped})
