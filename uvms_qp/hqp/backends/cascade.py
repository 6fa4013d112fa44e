"""A cascade of QPs through qpsolvers: one QP per level, frozen slacks, null-space elimination.

Level k solves, over ``x = x_p + Z y`` (``Z`` spans the null space of every frozen equality row,
so the frozen equalities hold by construction and dependent rows are harmless) and one slack
``t_i`` per inequality row of the level:

    min_{y, t}  sum_{i in eq_k} w_i (a_i x - b_i)^2 + sum_{i in ineq_k} w_i t_i^2 + rho |y|^2
    s.t.        lower <= x <= upper,  lo_H <= A_H x <= hi_H                      (hard)
                lo_j - |v_j| - m <= a_j x <= hi_j + |v_j| + m   (frozen inequality rows j)
                lo_i <= a_i x + t_i <= hi_i                          (inequality rows of level k)

with ``v_j`` the violation reached by the higher level and ``m`` a per-back-end margin (data in
the registry). The equality rows of level k are then frozen at the values ``a_i x`` they reached
(unique, because the weighted least-squares objective is strictly convex in ``A x``) and eliminated:
``Z <- Z null(A_k Z)`` and ``x_p <- x`` (so ``y = 0`` stays feasible for every later QP). A last QP
minimises ``x' W x`` over what is left. Only inequality rows are given to qpsolvers, which sidesteps
wrappers that mishandle equality rows. ``rho`` (relative 1e-10) keeps small dense solvers strictly
convex; results are measured, never trusted, in :mod:`uvms_qp.hqp.evaluate`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..._validation import FloatArray
from ..evaluate import hard_scale, hard_violation
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status
from . import BackendOutput


def _null_space(M: FloatArray, rtol: float) -> tuple[FloatArray, int]:
    """Orthonormal basis of the null space of ``M`` and its rank (SVD with relative cut-off)."""
    if M.shape[0] == 0:
        return np.eye(M.shape[1]), 0
    _, s, Vt = np.linalg.svd(M, full_matrices=True)
    rank = int(np.sum(s > rtol * max(1.0, s[0]))) if s.size else 0
    return Vt[rank:].T.copy(), rank


class _Rows:
    """Accumulates inequality rows ``lo <= C z <= hi`` as qpsolvers' one-sided ``G z <= h``."""

    def __init__(self, width: int) -> None:
        self.width = width
        self.G: list[FloatArray] = []
        self.h: list[FloatArray] = []

    def add(self, C: FloatArray, lo: FloatArray, hi: FloatArray) -> None:
        up = np.isfinite(hi)
        dn = np.isfinite(lo)
        if up.any():
            self.G.append(C[up])
            self.h.append(hi[up])
        if dn.any():
            self.G.append(-C[dn])
            self.h.append(-lo[dn])

    def arrays(self) -> tuple[FloatArray | None, FloatArray | None]:
        if not self.G:
            return None, None
        return np.vstack(self.G), np.concatenate(self.h)


class CascadeBackend:
    """One QP per level through ``qpsolvers.solve_qp`` (dense matrices).

    Args:
        spec: Registry entry: qpsolvers name, settings, margins.
        options: Overrides: ``rank_tol`` (relative SVD cut-off, default 1e-10), ``reg`` (relative
            regularisation rho, default 1e-10), and back-end settings passed to qpsolvers.
    """

    def __init__(self, spec: SolverSpec, options: dict[str, Any] | None = None) -> None:
        import qpsolvers

        opts = dict(options or {})
        self._qpsolvers = qpsolvers
        self.spec = spec
        self.rank_tol = float(opts.pop("rank_tol", 1e-10))
        self.reg = float(opts.pop("reg", 1e-10))
        self.settings = {**spec.settings, **opts}

    # -- one QP -------------------------------------------------------------------------------
    def _qp(self, P: FloatArray, q: FloatArray, rows: _Rows, lb: FloatArray | None,
            ub: FloatArray | None) -> FloatArray | None:
        G, h = rows.arrays()
        if G is None and lb is None and ub is None:
            return np.linalg.lstsq(P, -q, rcond=None)[0]
        if self.spec.sparse:
            from scipy import sparse

            P = sparse.csc_matrix(P)
            G = sparse.csc_matrix(G) if G is not None else None
        try:
            z = self._qpsolvers.solve_qp(P, q, G, h, None, None, lb, ub,
                                         solver=self.spec.qp_name, **self.settings)
        except Exception:  # a back-end crash is a failed level, reported truthfully
            return None
        if z is None or not np.all(np.isfinite(z)):
            return None
        return np.asarray(z, dtype=np.float64)

    def _constraints(self, problem: Problem, xp: FloatArray, Z: FloatArray, width: int,
                     frozen: list[tuple[FloatArray, FloatArray, FloatArray]]
                     ) -> tuple[_Rows, FloatArray | None, FloatArray | None]:
        """Hard box, hard inequality rows and frozen rows over ``z = [y, t]``."""
        p = Z.shape[1]
        rows = _Rows(width)
        lb = ub = None

        def over_y(C: FloatArray) -> FloatArray:
            CZ = C @ Z
            return np.hstack((CZ, np.zeros((CZ.shape[0], width - p)))) if width > p else CZ

        if problem.has_box:
            if Z.shape[1] == problem.n and not xp.any() and np.array_equal(Z, np.eye(problem.n)):
                lb = np.concatenate((problem.lower, np.full(width - p, -np.inf)))
                ub = np.concatenate((problem.upper, np.full(width - p, np.inf)))
            else:
                rows.add(over_y(np.eye(problem.n)), problem.lower - xp, problem.upper - xp)
        hard = problem.hard
        ineq = ~hard.eq
        if ineq.any():
            base = hard.A[ineq] @ xp
            rows.add(over_y(hard.A[ineq]), hard.lo[ineq] - base, hard.hi[ineq] - base)
        for A, lo, hi in frozen:
            base = A @ xp
            rows.add(over_y(A), lo - base, hi - base)
        return rows, lb, ub

    # -- the cascade --------------------------------------------------------------------------
    def solve(self, problem: Problem) -> BackendOutput:
        """Solve level by level; on a failed QP return the last verified point and say so."""
        n = problem.n
        xp = np.zeros(n)
        Z = np.eye(n)
        hard = problem.hard
        if hard.eq.any():
            E, e = hard.A[hard.eq], hard.lo[hard.eq]
            xp = np.linalg.lstsq(E, e, rcond=None)[0]
            gap = float(np.max(np.abs(E @ xp - e)))
            if gap > self.spec.hard_tol * hard_scale(problem):
                return BackendOutput(xp, Status.HARD_INFEASIBLE,
                                     f"hard equality rows are inconsistent (gap {gap:.2e})")
            Z, _ = _null_space(E, self.rank_tol)
        frozen: list[tuple[FloatArray, FloatArray, FloatArray]] = []
        margin = self.spec.freeze_margin
        x = xp.copy()
        for k, level in enumerate(problem.levels):
            if level.m == 0:
                continue
            if Z.shape[1]:
                z = self._level(problem, level, xp, Z, frozen)
                if z is None:
                    return self._failure(problem, x, k)
                x = xp + Z @ z[: Z.shape[1]]
            # freeze: inequality rows by their reached violation, equality rows by elimination
            v = np.abs(level.violation(x))
            ineq = ~level.eq
            if ineq.any():
                scale = margin * (1.0 + np.abs(np.where(np.isfinite(level.lo[ineq]),
                                                        level.lo[ineq], 0.0)))
                frozen.append((level.A[ineq], level.lo[ineq] - v[ineq] - scale,
                               level.hi[ineq] + v[ineq] + scale))
            if level.eq.any() and Z.shape[1]:
                N, _ = _null_space(level.A[level.eq] @ Z, self.rank_tol)
                Z = Z @ N
            xp = x
        if Z.shape[1]:
            z = self._final(problem, xp, Z, frozen)
            if z is None:
                return self._failure(problem, x, len(problem.levels))
            x = xp + Z @ z
        x = self._polish(problem, x)
        return BackendOutput(x, Status.OPTIMAL, "")

    def _level(self, problem: Problem, level: Any, xp: FloatArray, Z: FloatArray,
               frozen: list[tuple[FloatArray, FloatArray, FloatArray]]) -> FloatArray | None:
        p = Z.shape[1]
        eq, ineq = level.eq, ~level.eq
        q_t = int(ineq.sum())
        width = p + q_t
        P = np.zeros((width, width))
        q = np.zeros(width)
        if eq.any():
            AZ = level.A[eq] @ Z
            r0 = level.A[eq] @ xp - level.lo[eq]
            WA = level.w[eq][:, None] * AZ
            P[:p, :p] = AZ.T @ WA
            q[:p] = WA.T @ r0
        if q_t:
            P[p:, p:] = np.diag(level.w[ineq])
        rows, lb, ub = self._constraints(problem, xp, Z, width, frozen)
        if q_t:
            Ci = np.hstack((level.A[ineq] @ Z, np.eye(q_t)))
            base = level.A[ineq] @ xp
            rows.add(Ci, level.lo[ineq] - base, level.hi[ineq] - base)
        for attempt in range(2):
            Pr = P.copy()
            rho = self.reg * (100.0 ** attempt) * max(1.0, float(np.abs(np.diag(P)).max()))
            Pr[:p, :p] += rho * np.eye(p)
            z = self._qp(Pr, q, rows, lb, ub)
            if z is not None and self._feasible(problem, xp + Z @ z[:p]):
                return z
        return None

    def _final(self, problem: Problem, xp: FloatArray, Z: FloatArray,
               frozen: list[tuple[FloatArray, FloatArray, FloatArray]]) -> FloatArray | None:
        p = Z.shape[1]
        WZ = problem.W[:, None] * Z
        P = Z.T @ WZ
        P = 0.5 * (P + P.T)
        q = WZ.T @ xp
        rows, lb, ub = self._constraints(problem, xp, Z, p, frozen)
        z = self._qp(P, q, rows, lb, ub)
        if z is not None and self._feasible(problem, xp + Z @ z):
            return z
        return None

    def _feasible(self, problem: Problem, x: FloatArray) -> bool:
        """Loose check (1e-6 relative) that a QP answer respects the hard rows before polishing."""
        return hard_violation(problem, x) <= 1e-6 * hard_scale(problem)

    def _polish(self, problem: Problem, x: FloatArray) -> FloatArray:
        """Remove round-off outside the box (clip) and the hard rows (least-norm corrections)."""
        x = np.minimum(np.maximum(x, problem.lower), problem.upper)
        hard = problem.hard
        for _ in range(3):
            if not hard.m:
                break
            s = hard.violation(x)
            bad = np.abs(s) > 1e-12 * hard_scale(problem)
            if not bad.any():
                break
            x = x - np.linalg.lstsq(hard.A[bad], s[bad], rcond=None)[0]
            x = np.minimum(np.maximum(x, problem.lower), problem.upper)
        return x

    def _failure(self, problem: Problem, x: FloatArray, k: int) -> BackendOutput:
        where = f"level {k}" if k < len(problem.levels) else "the final regularisation"
        suspect = k == 0 or not np.all(np.isfinite(x)) or not self._feasible(problem, x)
        if suspect and not _hard_feasible(problem):
            return BackendOutput(x, Status.HARD_INFEASIBLE,
                                 "the hard box and hard rows admit no point")
        return BackendOutput(x, Status.BACKEND_ERROR,
                             f"{self.spec.name}: the QP of {where} failed; x solves levels < {k} "
                             "only")


def _hard_feasible(problem: Problem) -> bool:
    """Independent feasibility check of the hard box and rows (HiGHS LP through SciPy)."""
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
    res = linprog(np.zeros(problem.n), A_ub=np.vstack(A_ub) if A_ub else None,
                  b_ub=np.concatenate(b_ub) if b_ub else None, A_eq=A_eq, b_eq=b_eq,
                  bounds=bounds, method="highs")
    return res.status != 2
