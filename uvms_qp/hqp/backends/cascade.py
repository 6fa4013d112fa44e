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
wrappers that mishandle equality rows. ``rho`` keeps small dense solvers strictly convex; its bias
is removed by proximal steps (``rho |y - y_j|^2`` around the previous answer) while they converge,
then the answer's active set is solved exactly on the QP without ``rho`` (a level of condition
2e4 leaves the proximal steps a factor 0.98 per step along its weak direction; the exact solve
removes the bias at once); inexact back-ends' answers are sharpened and certified per QP
(:mod:`uvms_qp.hqp.kkt`), and results are measured and certified, never trusted, in
:mod:`uvms_qp.hqp.measure`.

Degenerate data, by design:

* each level's objective is divided by its Hessian's largest diagonal entry (the same minimiser),
  so that a level whose rows and targets are 1e5 (or 1e-5) reaches the back-end, its
  regularisation and the KKT check of :mod:`uvms_qp.hqp.kkt` at the scale 1;
* every inequality row handed to a back-end (box and hard rows in the reduced space, frozen rows,
  the level's rows with their slacks) is scaled to unit norm in x (a slack ``t_i`` of a scaled
  row carries the weight ``w_i |a_i|^2``): row norms spread over 1e-3..1e3 reach the back-end as
  rows of norm 1;
* an equality row whose projection on the freedom left is below ``rank_tol |a_i|`` is a constant
  of the level (its value is fixed by the levels above) and is left out of its QP, and so is a
  row whose norm is below ``ZERO_ROW_TOL`` of the problem's largest (a zero or tiny row: it pins no
  direction for the levels below either); the rank of
  the rows frozen into ``Z`` is decided against their unprojected norms, so round-off left by a
  projection never becomes a direction;
* the end of the solve (``end``, a reading of ``clock``: the solver's, which a safe solver sets
  to its own; back-ends with a time limit of their own get the time left): a QP is not started
  after it, the exact rescue and the sharpening stop there, and the solve reports
  ``backend_error`` ("stopped at the deadline") for the ladder to fall back.
"""

from __future__ import annotations

import ctypes
import difflib
import inspect
import math
import os
import re
import sys
import warnings
from collections.abc import Callable
from functools import cache
from time import perf_counter
from typing import Any

import numpy as np

from ..._validation import FloatArray, as_scalar
from ...errors import InputError
from ..hard_set import hard_feasible, hard_point, polish_hard
from ..kkt import active_set_from, certified_point
from ..measure import hard_violation
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status
from ..tolerances import PIN_TOL, ZERO_ROW_TOL
from . import Answer
from .daqp import DAQP_SETTINGS


@cache
def _mute_highs_banner() -> None:
    """Construct one ``highspy.Highs`` with the process's C-level stdout sent to /dev/null.

    HiGHS prints a copyright banner on the first construction in a process, before any option
    can turn its output off; after that first construction it stays quiet (``output_flag``
    false, as qpsolvers sets it). Called once, when a ``cascade:highs`` back-end is built.
    """
    try:
        import highspy
    except ImportError:  # pragma: no cover - the registry only offers installed back-ends
        return
    try:
        libc_fflush = ctypes.CDLL(None).fflush
    except (OSError, TypeError, AttributeError):  # pragma: no cover - no C runtime handle
        return  # the banner is printed, nothing else changes
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            try:
                highspy.Highs()
            finally:
                libc_fflush(None)  # the banner may sit in C's stdio buffer
                os.dup2(saved, 1)
    finally:
        os.close(saved)


def _null_space(M: FloatArray, rtol: float, ref: float = 1.0) -> tuple[FloatArray, int]:
    """Orthonormal basis of the null space of ``M`` and its rank.

    Singular values at or below ``rtol * max(ref, s_max)`` are zero: ``ref`` is the norm of the
    rows before a projection, so that what a projection leaves of a row in the span of the
    levels above (round-off, ``1e-16 |a|``) is never taken for a direction.
    """
    if M.shape[0] == 0:
        return np.eye(M.shape[1]), 0
    _, s, Vt = np.linalg.svd(M, full_matrices=True)
    rank = int(np.sum(s > rtol * max(ref, s[0]))) if s.size else 0
    return Vt[rank:].T.copy(), rank


def _row_norms(A: FloatArray) -> FloatArray:
    return np.sqrt(np.einsum("ij,ij->i", A, A))


class _Rows:
    """Accumulates inequality rows ``lo <= C z <= hi`` as qpsolvers' one-sided ``G z <= h``."""

    def __init__(self, width: int, n: int) -> None:
        self.width = width
        self.n = n
        self.G: list[FloatArray] = []
        self.h: list[FloatArray] = []
        self.X: list[FloatArray] = []  # x-space row of each G row (zeros: not freezable)

    def add(self, C: FloatArray, lo: FloatArray, hi: FloatArray, margin: float = 0.0,
            X: FloatArray | None = None, norms: FloatArray | None = None) -> None:
        """Add rows scaled to unit x-space norm; rows that vanish in the reduced space are dropped.

        A row whose reduced coefficients are ~0 (below 1e-12 of its x-space norm) only restates
        that ``x_p`` satisfies it (true up to round-off, since ``x_p`` is the previous answer);
        keeping it could turn a 1e-13 round-off into an infeasible ``0 <= -1e-13``. ``margin``
        loosens both sides (in the units of the rows). ``norms``: the x-space norm of each row
        (default: that of ``X``, else of ``C``); the rows and sides are divided by it.
        """
        if norms is None:
            norms = _row_norms(X if X is not None else C)
        ref = np.where(norms > 0.0, norms, 1.0)
        live = np.abs(C).max(axis=1, initial=0.0) > 1e-12 * ref if C.shape[1] else np.zeros(
            C.shape[0], dtype=bool)
        ref = ref[live]
        C = C[live] / ref[:, None]
        lo, hi = (lo[live] - margin) / ref, (hi[live] + margin) / ref
        X = np.zeros((C.shape[0], self.n)) if X is None else X[live]
        up = np.isfinite(hi)
        dn = np.isfinite(lo)
        if up.any():
            self.G.append(C[up])
            self.h.append(hi[up])
            self.X.append(X[up])
        if dn.any():
            self.G.append(-C[dn])
            self.h.append(-lo[dn])
            self.X.append(X[dn])

    def xrows(self) -> FloatArray:
        """x-space rows of the G rows (zero rows for the level's own slack rows)."""
        return np.vstack(self.X) if self.X else np.zeros((0, self.n))

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

    factorises = True  # (null spaces by SVD, least squares, QP libraries on BLAS)

    def __init__(self, spec: SolverSpec, options: dict[str, Any] | None = None) -> None:
        import qpsolvers

        opts = dict(options or {})
        self._qpsolvers = qpsolvers
        self.spec = spec
        self.rank_tol = as_scalar(opts.pop("rank_tol", 1e-10), "options['rank_tol']",
                                  nonnegative=True)
        self.reg = as_scalar(opts.pop("reg", spec.reg), "options['reg']", nonnegative=True)
        steps = opts.pop("prox_steps", spec.prox_steps)
        if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 0:
            raise InputError(f"options['prox_steps']: expected a non-negative integer, "
                             f"got {steps!r}")
        self.prox_steps = int(steps)
        self.mult_tol = as_scalar(opts.pop("mult_tol", 1e-7), "options['mult_tol']",
                                  positive=True)
        _check_settings(spec, opts)
        #: reading of ``clock`` [s] by which the current solve ends (set by the solver)
        self.end = math.inf
        #: the clock of the cap [s] (the solver's; a safe solver's may be a test's)
        self.clock: Callable[[], float] = perf_counter
        #: QPs answered by the exact active-set rescue since construction (diagnostics)
        self.rescued = 0
        self._stopped = False  # this solve passed its end: no QP and no rescue after it
        self._capped = False  # the last QP stopped at its iteration cap
        self._end = math.inf  # reading of ``clock`` at which this solve ends
        self._timed_out = False  # this solve reached its end
        self._big = 0.0  # the largest level row norm of this solve's problem
        self.settings = {**spec.settings, **opts}
        if spec.qp_name == "highs":
            _mute_highs_banner()

    # -- one QP -------------------------------------------------------------------------------
    def _qp(self, P: FloatArray, q: FloatArray, rows: _Rows, lb: FloatArray | None,
            ub: FloatArray | None, extra: Any = None, floor: float = 1.0
            ) -> tuple[FloatArray | None, FloatArray]:
        """Solve one QP; return ``z`` and the x-space rows of its strongly active constraints.

        ``floor``: the scale of the Hessian before any projection (rank decisions of an
        unconstrained QP are taken against it).

        A constraint with a positive multiplier is active at *every* optimum of this QP
        (complementary slackness holds between any primal and any dual optimum), so it can be
        frozen as an equality for the lower levels without loss.
        """
        none = np.zeros((0, rows.n))
        left = self._end - self.clock()
        if left <= 0.0:  # the end of the solve: no QP is started after it
            self._stopped = self._timed_out = True
            return None, none
        G, h = rows.arrays()
        if G is None and lb is None and ub is None:
            # unconstrained: least squares with singular values cut against the level's rows
            # before projection (``floor``), not against P's own (possibly round-off) size
            top = float(np.abs(np.diag(P)).max(initial=0.0))
            rcond = min(1.0, self.rank_tol * max(floor, 1e-300) / top) if top > 0.0 else 1.0
            return np.asarray(np.linalg.lstsq(P, -q, rcond=rcond)[0], dtype=np.float64), none
        if self.spec.time_setting:
            extra = {**(extra or {}), self.spec.time_setting: min(
                left, float(self.settings.get(self.spec.time_setting, math.inf)))}
        Gs, Ps = G, P
        if self.spec.sparse:
            from scipy import sparse

            Ps = sparse.csc_matrix(P)
            Gs = sparse.csc_matrix(G) if G is not None else None
        try:
            problem = self._qpsolvers.Problem(Ps, q, Gs, h, None, None, lb, ub)
            # Every answer is measured (and certified where the back-end is inexact) below, so the
            # back-ends' own status warnings would only repeat what the result reports.
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sol = self._qpsolvers.solve_problem(problem, solver=self.spec.qp_name,
                                                    **{**self.settings, **(extra or {})})
        except Exception:  # a back-end crash is a failed level, reported truthfully
            return None, none
        self._capped = not sol.found and _hit_iteration_cap(sol)
        z = sol.x
        if z is None:
            return None, none
        z = np.asarray(z, dtype=np.float64)
        if z.shape != q.shape or not np.all(np.isfinite(z)):  # HiGHS may return an empty x
            return None, none
        rescue = not sol.found and not _closest_feasible_is_optimal(sol, G, h, z)
        if rescue and self.spec.exact:
            return None, none
        lam = None if sol.z is None else np.asarray(sol.z, dtype=np.float64)
        lam_b = None if sol.z_box is None else np.asarray(sol.z_box, dtype=np.float64)
        mult_tol = self.mult_tol if self.spec.exact else max(self.mult_tol, 1e-5)
        if self.spec.certify or rescue:
            # never trust the back-end (or rescue an answer it gave up on, e.g. a thin feasible
            # set called infeasible): sharpen on its active set and prove the KKT conditions
            cert = certified_point(P, q, G, h, lb, ub, z, deadline=self._end, clock=self.clock)
            if cert is None:
                return None, none
            z, lam, lam_b, mult_tol = cert.z, cert.lam, cert.lam_box, self.mult_tol
        return z, self._strong(rows, G, h, lb, ub, z, lam, lam_b, mult_tol)

    @staticmethod
    def _strong(rows: _Rows, G: FloatArray | None, h: FloatArray | None, lb: FloatArray | None,
                ub: FloatArray | None, z: FloatArray, lam: FloatArray | None,
                lam_b: FloatArray | None, mult_tol: float) -> FloatArray:
        """x-space rows of the constraints that are strongly active at ``z``.

        Strongly active: positive multiplier AND tight at ``z`` (an interior-point method gives
        inactive constraints small positive multipliers; those must not be frozen).
        """
        active = [np.zeros((0, rows.n))]
        if G is not None and h is not None and lam is not None:
            thr = mult_tol * max(1.0, float(np.abs(lam).max(initial=0.0)))
            X = rows.xrows()
            tight = h - G @ z <= PIN_TOL * (1.0 + np.abs(h))
            strong = (lam > thr) & tight & (np.abs(X).max(axis=1, initial=0.0) > 0.0)
            active.append(X[strong])
        if lb is not None and ub is not None and lam_b is not None:
            zb = z[: rows.n]
            lam_b = np.abs(lam_b)[: rows.n]
            thr = mult_tol * max(1.0, float(lam_b.max(initial=0.0)))
            tight = (zb - lb[: rows.n] <= PIN_TOL * (1.0 + _finite_abs(lb[: rows.n]))) | (
                ub[: rows.n] - zb <= PIN_TOL * (1.0 + _finite_abs(ub[: rows.n])))
            active.append(np.eye(rows.n)[(lam_b > thr) & tight])
        return np.vstack(active)

    def _rescue(self, P: FloatArray, q: FloatArray, rows: _Rows, lb: FloatArray | None,
                ub: FloatArray | None, z0: FloatArray) -> tuple[FloatArray | None, FloatArray]:
        """Exact active-set solve from the feasible point ``z0`` when every attempt failed.

        ``z0`` keeps the previous level's answer (``y = 0``, feasible by construction); the
        answer counts only with a KKT certificate (:mod:`~uvms_qp.hqp.kkt`). A solve past its
        end does not rescue.
        """
        if self._stopped or self.clock() > self._end:
            self._stopped = self._timed_out = True
            return None, np.zeros((0, rows.n))
        G, h = rows.arrays()
        cert = active_set_from(P, q, G, h, lb, ub, z0, deadline=self._end, clock=self.clock)
        if cert is None:
            return None, np.zeros((0, rows.n))
        self.rescued += 1
        return cert.z, self._strong(rows, G, h, lb, ub, cert.z, cert.lam, cert.lam_box,
                                    self.mult_tol)

    def _constraints(self, problem: Problem, xp: FloatArray, Z: FloatArray, width: int,
                     frozen: list[tuple[FloatArray, FloatArray, FloatArray]]
                     ) -> tuple[_Rows, FloatArray | None, FloatArray | None]:
        """Hard box, hard inequality rows and frozen rows over ``z = [y, t]``."""
        p = Z.shape[1]
        rows = _Rows(width, problem.n)
        lb = ub = None
        margin = self.spec.freeze_margin * problem.hard_scale if frozen or p < problem.n else 0.0

        def over_y(C: FloatArray) -> FloatArray:
            CZ = C @ Z
            return np.hstack((CZ, np.zeros((CZ.shape[0], width - p)))) if width > p else CZ

        if np.isfinite(problem.lower).any() or np.isfinite(problem.upper).any():
            if Z.shape[1] == problem.n and not xp.any() and np.array_equal(Z, np.eye(problem.n)):
                lb = np.concatenate((problem.lower, np.full(width - p, -np.inf)))
                ub = np.concatenate((problem.upper, np.full(width - p, np.inf)))
            else:
                eye = np.eye(problem.n)
                rows.add(over_y(eye), problem.lower - xp, problem.upper - xp, margin, eye)
        hard = problem.hard
        ineq = hard.lower != hard.upper
        if ineq.any():
            base = hard.A[ineq] @ xp
            rows.add(over_y(hard.A[ineq]), hard.lower[ineq] - base, hard.upper[ineq] - base,
                     margin, hard.A[ineq])
        for A, lo, hi in frozen:
            base = A @ xp
            rows.add(over_y(A), lo - base, hi - base, 0.0, A)
        return rows, lb, ub

    # -- the cascade --------------------------------------------------------------------------
    def reset(self) -> None:
        """Nothing to forget (every solve starts from scratch)."""

    def reduce(self, problem: Problem) -> bool:
        """Nothing to reduce: rows the levels above fix are left out of each level's QP."""
        return False

    def solve(self, problem: Problem) -> Answer:
        """Solve level by level; on a failed QP return the last verified point and say so.

        ``info["rescued_qps"]`` counts the QPs of this solve that the back-end failed and the
        exact active-set rescue answered (each with a KKT certificate).
        """
        n = problem.n
        rescued = self.rescued
        self._stopped = self._timed_out = False
        self._end = self.end
        self._big = float(_row_norms(problem.A[problem.head:]).max(initial=0.0))
        xp = np.zeros(n)
        Z = np.eye(n)
        hard = problem.hard
        hard_eq = hard.lower == hard.upper
        if hard_eq.any():
            E, e = hard.A[hard_eq], hard.lower[hard_eq]
            xp = np.linalg.lstsq(E, e, rcond=None)[0]
            gap = float(np.max(np.abs(E @ xp - e)))
            if gap > self.spec.hard_tol * problem.hard_scale:
                return Answer(xp, Status.HARD_INFEASIBLE,
                              f"hard equality rows are inconsistent (gap {gap:.2e})")
            Z, _ = _null_space(E, self.rank_tol, float(_row_norms(E).max(initial=0.0)))
        frozen: list[tuple[FloatArray, FloatArray, FloatArray]] = []
        margin = self.spec.freeze_margin
        x = xp.copy()
        for k, level in enumerate(problem.levels):
            if level.m == 0:
                continue
            active = np.zeros((0, n))
            if Z.shape[1]:
                z, active = self._level(problem, level, xp, Z, frozen)
                if z is None:
                    return self._failure(problem, x, k)
                x = xp + Z @ z[: Z.shape[1]]
            # freeze: inequality rows by their reached violation, equality rows by elimination
            v = level.violation(x)
            eq = level.lower == level.upper
            ineq = ~eq
            if ineq.any():
                scale = margin * (1.0 + np.abs(np.where(np.isfinite(level.lower[ineq]),
                                                        level.lower[ineq], 0.0)))
                frozen.append((level.A[ineq], level.lower[ineq] - v[ineq] - scale,
                               level.upper[ineq] + v[ineq] + scale))
            # (a row the level's QP left out as a constant pins no direction either)
            live = _row_norms(level.A) > ZERO_ROW_TOL * self._big
            pinned = np.vstack((level.A[eq & live], active))
            if pinned.shape[0] and Z.shape[1]:
                ref = float(_row_norms(pinned).max(initial=0.0))
                N, _ = _null_space(pinned @ Z, self.rank_tol, ref)
                Z = Z @ N
            xp = x
        if Z.shape[1]:
            z = self._final(problem, xp, Z, frozen)
            if z is None:
                return self._failure(problem, x, len(problem.sizes))
            x = xp + Z @ z
        x = polish_hard(problem, x)
        return Answer(x, Status.OPTIMAL, "", {"rescued_qps": self.rescued - rescued})

    def _level(self, problem: Problem, level: Any, xp: FloatArray, Z: FloatArray,
               frozen: list[tuple[FloatArray, FloatArray, FloatArray]]
               ) -> tuple[FloatArray | None, FloatArray]:
        p = Z.shape[1]
        w = level.weights if level.weights is not None else np.ones(level.m)
        norms = _row_norms(level.A)
        # a row of norm below ZERO_ROW_TOL of the problem's largest is a constant of the level (its
        # value moves by |a| |x| at most): left out of the QP, like a zero row
        live = norms > ZERO_ROW_TOL * self._big
        eq = (level.lower == level.upper) & live
        ineq = (level.lower != level.upper) & live
        if eq.any():
            AZ = level.A[eq] @ Z
            # a row the levels above fix (its projection is round-off) is a constant here
            eq_live = _row_norms(AZ) > self.rank_tol * norms[eq]
            AZ, we = AZ[eq_live], w[eq][eq_live]
            r0 = (level.A[eq] @ xp - level.lower[eq])[eq_live]
        q_t = int(ineq.sum())
        width = p + q_t
        P = np.zeros((width, width))
        q = np.zeros(width)
        floor = 0.0
        if eq.any() and AZ.shape[0]:
            WA = we[:, None] * AZ
            P[:p, :p] = AZ.T @ WA
            q[:p] = WA.T @ r0
            floor = float((we * norms[eq][eq_live] ** 2).max())
        # the level's inequality rows scaled to unit norm: slack t_i of the scaled row, weight
        # w_i |a_i|^2 (the same objective w_i (|a_i| t_i)^2)
        ni = np.where(norms[ineq] > 0.0, norms[ineq], 1.0)
        if q_t:
            P[p:, p:] = np.diag(w[ineq] * ni * ni)
        # the level's objective in its own units: divided by its Hessian's largest diagonal
        # entry (the same minimiser; a level of rows 1e5 or 1e-5 reaches the QP at the scale 1)
        unit = float(np.abs(np.diag(P)).max(initial=0.0))
        if unit > 0.0:
            P /= unit
            q /= unit
            floor /= unit
        rows, lb, ub = self._constraints(problem, xp, Z, width, frozen)
        if q_t:
            Ci = np.hstack((level.A[ineq] @ Z, np.diag(ni)))
            base = level.A[ineq] @ xp
            rows.add(Ci, level.lower[ineq] - base, level.upper[ineq] - base, norms=ni)
        scale = max(1.0, float(np.abs(np.diag(P)).max()))
        attempts: list[tuple[float, int, Any]] = [(self.reg, self.prox_steps, None)]
        attempts += [(self.reg, self.prox_steps, extra) for extra in self.spec.retries]
        attempts.append((max(self.reg * 100.0, 1e-8), self.prox_steps, None))
        for rel, steps, extra in attempts:
            rho = rel * scale
            Pr = P.copy()
            Pr[:p, :p] += rho * np.eye(p)
            z, active = self._qp(Pr, q, rows, lb, ub, extra, floor)
            # proximal steps while they converge: each shrinks the bias of rho along a
            # direction of curvature sigma^2 by rho / (rho + sigma^2); once a step moves less
            # than half the one before (slow directions, or round-off) the answer is sharpened
            # on the exact QP instead
            moved_before = math.inf
            for _ in range(steps if rho > 0.0 else 0):
                if z is None:
                    break
                qr = q.copy()
                qr[:p] -= rho * z[:p]  # proximal centre at the previous answer
                z_new, active = self._qp(Pr, qr, rows, lb, ub, extra, floor)
                if z_new is None:
                    z = None
                    break
                moved = float(np.abs(z_new[:p] - z[:p]).max(initial=0.0))
                z = z_new
                if moved <= 1e-12 * max(1.0, float(np.abs(z[:p]).max(initial=0.0))) or (
                        moved > 0.5 * moved_before):
                    break
                moved_before = moved
            if z is not None and rho > 0.0:
                # the regularised answer's active set, solved exactly on the QP itself
                G, h = rows.arrays()
                cert = certified_point(P, q, G, h, lb, ub, z, deadline=self._end,
                                       clock=self.clock)
                if cert is not None:
                    z = cert.z
                    active = self._strong(rows, G, h, lb, ub, z, cert.lam, cert.lam_box,
                                          self.mult_tol)
            if z is not None and self._feasible(problem, xp + Z @ z[:p]):
                return z, active
            if z is None and self._capped:
                break  # other settings would spend the same capped effort: go to the rescue
        # rescue from y = 0 (the previous answer), else from a vertex of the hard set, with the
        # smallest slacks that satisfy the level's own rows
        for y0 in (np.zeros(p), None):
            if self._stopped:
                break
            if y0 is None:
                xh = hard_point(problem) if not frozen else None
                if xh is None:
                    break
                y0 = Z.T @ (xh - xp)
            z0 = np.concatenate((y0, np.zeros(q_t)))
            if q_t:
                yi = level.A[ineq] @ (xp + Z @ y0)
                z0[p:] = np.clip(0.0, level.lower[ineq] - yi, level.upper[ineq] - yi) / ni
            z, active = self._rescue(P, q, rows, lb, ub, z0)
            if z is not None and self._feasible(problem, xp + Z @ z[:p]):
                return z, active
        return None, np.zeros((0, problem.n))

    def _final(self, problem: Problem, xp: FloatArray, Z: FloatArray,
               frozen: list[tuple[FloatArray, FloatArray, FloatArray]]) -> FloatArray | None:
        p = Z.shape[1]
        WZ = problem.W[:, None] * Z
        P = Z.T @ WZ
        P = 0.5 * (P + P.T)
        q = WZ.T @ xp
        rows, lb, ub = self._constraints(problem, xp, Z, p, frozen)
        for extra in (None, *self.spec.retries):
            z, _ = self._qp(P, q, rows, lb, ub, extra)
            if z is not None and self._feasible(problem, xp + Z @ z):
                return z
            if z is None and self._capped:
                break  # other settings would spend the same capped effort: go to the rescue
        z, _ = self._rescue(P, q, rows, lb, ub, np.zeros(p))
        if z is not None and self._feasible(problem, xp + Z @ z):
            return z
        return None

    @staticmethod
    def _feasible(problem: Problem, x: FloatArray) -> bool:
        """Loose check (1e-6 relative) that a QP answer respects the hard rows before polishing."""
        hard = problem.hard
        return hard_violation(x, problem.lower, problem.upper, hard.A, hard.lower,
                              hard.upper) <= 1e-6 * problem.hard_scale

    def _failure(self, problem: Problem, x: FloatArray, k: int) -> Answer:
        where = f"level {k}" if k < len(problem.sizes) else "the final regularisation"
        if self._timed_out:
            return Answer(x, Status.BACKEND_ERROR,
                          f"{self.spec.name}: stopped at the deadline in {where}; x solves "
                          f"levels < {k} only", {"deadline_passed": True})
        suspect = k == 0 or not np.all(np.isfinite(x)) or not self._feasible(problem, x)
        if suspect and not hard_feasible(problem):
            return Answer(x, Status.HARD_INFEASIBLE, "the hard box and hard rows admit no point")
        return Answer(x, Status.BACKEND_ERROR,
                      f"{self.spec.name}: the QP of {where} failed; x solves levels < {k} only")


def _finite_abs(v: FloatArray) -> FloatArray:
    """``|v|`` with infinite entries replaced by 0.

    Used in tolerances ``tol * (1 + |bound|)``: at an infinite bound every comparison has the
    same outcome whether the bound's magnitude counts as 0 or as the largest float (the
    distance to it is infinite), and this costs two array operations instead of
    ``np.nan_to_num``'s dozen.
    """
    return np.abs(np.where(np.isfinite(v), v, 0.0))


_OWN_OPTIONS = ("rank_tol", "reg", "prox_steps", "mult_tol", "level_tol", "hard_tol")


@cache
def backend_settings(qp_name: str) -> frozenset[str] | None:
    """Names of the settings qpsolvers passes on to the back-end ``qp_name``.

    Read from the installed back-end itself (its settings object or its solve function's
    signature), so a setting it does not know is refused here instead of being ignored or
    making every QP fail. None when the back-end offers no way to list them (not checked).
    """
    names: set[str] = {"verbose"}
    try:
        if qp_name == "quadprog":
            import quadprog

            names |= set(inspect.signature(quadprog.solve_qp).parameters) - {
                "G", "a", "C", "b", "meq"}
        elif qp_name == "daqp":
            names |= DAQP_SETTINGS
        elif qp_name == "proxqp":
            import proxsuite

            doc = (proxsuite.proxqp.dense.solve.__doc__ or "").splitlines()
            found = set(re.findall(r"(\w+):", doc[0])) if doc else set()
            if not found:
                return None
            names |= found - {"H", "g", "A", "b", "C", "l", "u", "x", "y", "z"}
            names.add("backend")
        elif qp_name == "piqp":
            import piqp

            names |= _public(piqp.DenseSolver().settings) | {"backend"}
        elif qp_name == "clarabel":
            import clarabel

            names |= _public(clarabel.DefaultSettings())
        elif qp_name == "highs":
            import highspy

            names |= _public(highspy.HighsOptions())
        elif qp_name == "osqp":
            import osqp

            names |= _public(osqp.ext_builtin.OSQPSettings()) | {"raise_error"}
        else:
            return None
    except Exception:  # an unexpected version of the back-end: leave its settings unchecked
        return None
    return frozenset(names)


def _public(obj: Any) -> set[str]:
    """Public attribute names of a settings object."""
    return {a for a in dir(obj) if not a.startswith("_") and not callable(getattr(obj, a))}


def _check_settings(spec: SolverSpec, settings: dict[str, Any]) -> None:
    """Refuse a back-end setting the back-end does not know (it would be ignored, or fail).

    Raises:
        InputError: naming the setting, the closest known names and where the rest are listed.
    """
    known = backend_settings(spec.qp_name) if settings else None
    if known is None:
        return
    for key in settings:
        if key not in known:
            close = difflib.get_close_matches(key, [*known, *_OWN_OPTIONS], n=3)
            hint = f" (did you mean {', '.join(map(repr, close))}?)" if close else ""
            raise InputError(
                f"options: unknown setting {key!r} for solver {spec.name!r}{hint}; known: "
                f"{', '.join(_OWN_OPTIONS)} and the settings of the {spec.qp_name} back-end")


def _hit_iteration_cap(sol: Any) -> bool:
    """True when the back-end reports that it stopped at its iteration cap.

    ProxQP (``PROXQP_MAX_ITER_REACHED``) and PIQP (``PIQP_MAX_ITER_REACHED``) say so in their
    status; such a QP is badly scaled for the back-end (e.g. a target 1e300 m away), and each
    retry with other tolerances would spend the same capped effort again.
    """
    info = (sol.extras or {}).get("info")
    return "MAX_ITER" in str(getattr(info, "status", "")).upper()


def _closest_feasible_is_optimal(sol: Any, G: FloatArray | None, h: FloatArray | None,
                                 z: FloatArray) -> bool:
    """Accept ProxQP's "closest primal feasible" answer when it is in fact feasible.

    With ``primal_infeasibility_solving`` ProxQP solves the QP over the closest feasible
    constraint set; qpsolvers reports that as not found. When the constraints hold at ``z`` (to
    1e-9 relative) that set is the original one, so ``z`` is the QP's optimum.
    """
    info = (sol.extras or {}).get("info")
    status = str(getattr(info, "status", ""))
    if "CLOSEST_PRIMAL_FEASIBLE" not in status:
        return False
    if G is None or h is None:
        return True
    return bool(np.all(G @ z - h <= 1e-9 * (1.0 + np.abs(h))))
