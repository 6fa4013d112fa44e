"""DAQP's native hierarchical mode: all levels in one call.

DAQP solves ``min 0.5 x' H x`` subject to prioritised groups of rows separated by
``break_points``; the first group is hard, each later group is softened and its violation is
minimised lexicographically, and ``H`` regularises whatever freedom is left. We pass

* group 0: the hard box (as DAQP's simple bounds) and the hard rows;
* group k: the rows of level k-1;
* ``H = W`` (the diagonal metric), so the final regularisation is exactly ``min x' W x``: no extra
  level ``W^(1/2) x = 0`` is needed and no soft-row approximation is added at the end.

Semantics that differ from the other back-ends (see ``docs/solver.md``): DAQP normalises every row
to unit norm before softening it, so for a level that cannot be met it minimises
``sum_i (s_i / |a_i|)^2`` (``a_i`` the row, ``s_i`` its violation); the per-row weights and row
scalings of that level do not change the compromise. Levels that can be met, and levels whose rows
share one value of ``w_i |a_i|^2``, give the same answer as every other back-end. The soft-row
regularisation ``rho_soft`` (1e-8 here, with a ladder of retries) leaves errors of 1e-9..1e-7.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..evaluate import hard_feasible, hard_scale, polish_hard
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status
from . import BackendOutput

_INF = 1e30  # DAQP's infinity

_FLAGS = {
    -1: "infeasible hard constraints",
    -2: "cycling detected",
    -3: "unbounded problem",
    -4: "iteration limit reached",
    -5: "non-convex problem",
    -6: "initial working set overdetermined",
    -7: "time limit reached",
    -8: "setup failed",
    3: "stalled on a point that violates a hard row (after every rho_soft retry)",
}


class DaqpHierarchicalBackend:
    """One DAQP hierarchical call per solve; the ``daqp.Model`` is reused when the shape repeats.

    Args:
        spec: Registry entry (settings such as ``rho_soft``).
        options: Overrides of DAQP settings (``rho_soft``, ``primal_tol``, ``iter_limit``...).
    """

    def __init__(self, spec: SolverSpec, options: dict[str, Any] | None = None) -> None:
        import daqp

        self._daqp = daqp
        self.spec = spec
        self.settings = {**spec.settings, **(options or {})}
        self._daqp_settings = {k: v for k, v in self.settings.items() if k != "rho_ladder"}
        first = float(self.settings.get("rho_soft", 1e-8))
        self._ladder = (first, [first] + [float(r) for r in self.settings.get("rho_ladder", ())
                                          if r != first])
        self._model: Any = None
        self._key: tuple[object, ...] | None = None
        self._H: np.ndarray | None = None
        self._f: np.ndarray | None = None
        self._W: np.ndarray | None = None
        self._sense = np.zeros(0, dtype=np.intc)

    def _arrays(self, problem: Problem) -> tuple[np.ndarray, ...]:
        stacked = problem.stacked
        hard = problem.hard
        A = stacked.A if not hard.m else np.vstack((hard.A, stacked.A))
        bu = np.concatenate((problem.upper, hard.hi, stacked.hi))
        bl = np.concatenate((problem.lower, hard.lo, stacked.lo))
        np.minimum(bu, _INF, out=bu)
        np.maximum(bl, -_INF, out=bl)
        return A, bu, bl

    def _structure(self, problem: Problem) -> tuple[np.ndarray, np.ndarray]:
        n, hard = problem.n, problem.hard
        sense = np.zeros(n + hard.m + problem.stacked.m, dtype=np.intc)
        if hard.m:
            sense[n : n + hard.m][hard.eq] = 5
        sizes = np.array([n + hard.m] + [b.m for b in problem.levels])
        bp = np.unique(np.cumsum(sizes)).astype(np.intc)
        return sense, bp

    def solve(self, problem: Problem) -> BackendOutput:
        """Solve all levels in one DAQP call, then clip/project round-off into the hard set."""
        A, bu, bl = self._arrays(problem)
        hard = problem.hard
        key = (problem.n, hard.m, tuple(b.m for b in problem.levels),
               hard.eq.tobytes() if hard.m else b"")
        W_same = self._W is not None and np.array_equal(problem.W, self._W)
        if key != self._key or not W_same:
            sense, bp = self._structure(problem)
            self._sense = sense
            self._W = problem.W.copy()
            self._H = np.diag(problem.W)
            self._f = np.zeros(problem.n)
            self._model = self._daqp.Model()
            flag = self._model.setup(self._H, self._f, A, bu, bl, sense, break_points=bp)[0]
            if flag < 0:
                self._key = None
                return BackendOutput(None, Status.BACKEND_ERROR,
                                     f"DAQP setup failed (exit flag {flag})", {"exitflag": flag})
            settings = self._model.settings
            settings.update(self._daqp_settings)
            self._model.settings = settings
            self._key = key
        else:
            self._model.update(A=A, bupper=bu, blower=bl)
        x, flag, info, rho = self._solve_with_retries(problem)
        extra = {"exitflag": int(flag), "daqp_solve_time": info["solve_time"],
                 "daqp_setup_time": info["setup_time"], "iterations": info["iterations"],
                 "rho_soft": rho}
        if flag in (1, 2):
            x = polish_hard(problem, x)
            return BackendOutput(x, Status.OPTIMAL, "", extra)
        self._key = None  # rebuild the workspace after a failure
        reason = _FLAGS.get(int(flag), "unknown failure")
        status = Status.BACKEND_ERROR
        if flag == -1 or not hard_feasible(problem):
            status = Status.HARD_INFEASIBLE
            reason = "the hard box and hard rows admit no point"
        return BackendOutput(x, status, f"DAQP exit flag {flag}: {reason}", extra)

    def _solve_with_retries(
        self, problem: Problem
    ) -> tuple[np.ndarray, int, dict[str, Any], float]:
        """Solve; if DAQP stalls (exit flag 3 or a violated hard row), retry with other rho_soft.

        A very small ``rho_soft`` makes the soft-row subproblems badly conditioned and DAQP can
        stop on a point that breaks hard rows. The retries walk the ladder ``rho_ladder``
        (registry data) from a cold start; the value that worked is reported in ``info``.
        """
        first, ladder = self._ladder
        tol = max(self.spec.hard_tol * hard_scale(problem), 1e-7)
        for i, rho in enumerate(ladder):
            if i:
                settings = self._model.settings
                settings["rho_soft"] = rho
                self._model.settings = settings
                self._model.update(sense=self._sense.copy())  # cold start for the retry
            x, _, flag, info = self._model.solve()
            if flag == -1:
                break
            if flag in (1, 2) and _box_rows_violation(problem, x) <= tol:
                break
            if flag in (1, 2):
                flag = 3  # claimed success but a hard row is broken: not acceptable
        if len(ladder) > 1 and rho != first:
            settings = self._model.settings
            settings["rho_soft"] = first
            self._model.settings = settings
        return x, int(flag), info, rho


def _box_rows_violation(problem: Problem, x: np.ndarray) -> float:
    """Violation of the hard rows (the box is clipped afterwards: only gross box errors count)."""
    v = 0.0
    if problem.hard.m:
        v = float(np.abs(problem.hard.violation(x)).max())
    return max(v, float((problem.lower - x).max()), float((x - problem.upper).max()))
