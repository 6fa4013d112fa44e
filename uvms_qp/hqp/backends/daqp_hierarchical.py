"""DAQP's native hierarchical mode: all levels in one call.

DAQP solves ``min 0.5 x' H x`` subject to prioritised groups of rows separated by
``break_points``; the first group is hard, each later group is softened and its violation is
minimised lexicographically, and ``H`` regularises whatever freedom is left. We pass

* group 0: the hard box (as DAQP's simple bounds) and the hard rows;
* group k: the rows of level k-1;
* ``H = W`` (the diagonal metric), so the final regularisation is exactly ``min x' W x``: no extra
  level ``W^(1/2) x = 0`` is needed and no soft-row approximation is added at the end.

Weights: DAQP normalises every row to unit norm before softening it, so with its one uniform
soft weight a level that cannot be met would minimise ``sum_i (s_i / |a_i|)^2`` whatever the row
weights. Every solve therefore sets DAQP's per-row soft weights
(:mod:`uvms_qp.hqp.daqp_weights`), so each level minimises ``sum_i w_i s_i^2`` like every other
back-end (a daqp without per-row weights keeps the normalised compromise; see
``docs/solver.md``). The soft-row regularisation ``rho_soft`` (1e-8 here, with a ladder of
retries) leaves errors of 1e-9..1e-7.

Hot path: the rows are copied into the preallocated buffers of a
:class:`~uvms_qp.hqp.workspace.Workspace` (reused while ``n``, the hard rows, the level sizes,
the hard equality pattern and ``W`` repeat), the DAQP model (direct C calls of
:class:`~uvms_qp.hqp.daqp_native.NativeDaqp` where available, else ``daqp.Model``) is updated in
place (warm start from the previous working set), and ``x`` is measured once on the stacked
rows. The first answer
is accepted when DAQP claims success and the box and hard rows hold to ``1e-7`` (the retry
threshold is never below that); round-off outside the box is clipped exactly as
:func:`~uvms_qp.hqp.evaluate.polish_hard` does. Anything else (a stall, a broken hard row, a
failure, hard rows off by more than ``1e-12``) continues on the reference path with the
normalised :class:`~uvms_qp.hqp.problem.Problem`, from the same model state.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, cast

import numpy as np

from ..daqp_model import HierarchyModel
from ..evaluate import hard_feasible, hard_scale, polish_hard
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status
from ..workspace import DAQP_INF, Workspace, box_and_hard_violation
from . import BackendOutput

_INF = DAQP_INF  # DAQP's infinity

#: a first answer whose box/hard violation is at most this is accepted without a retry (the
#: retry threshold is ``max(hard_tol * hard_scale, 1e-7)``, never below it)
_ACCEPT = 1e-7
#: hard rows violated by at most this need no projection (polish_hard's 1e-12 relative tolerance
#: is never below it)
_POLISH = 1e-12

_FLAGS = {
    -1: "infeasible hard constraints",
    -2: "cycling detected",
    -3: "unbounded problem",
    -4: "iteration limit reached",
    -5: "non-convex problem",
    -6: "initial working set overdetermined",
    -7: "time limit reached",
    -8: "setup failed",
    3: ("stopped early at a level it could not finish, or on a point that violates a hard "
        "row (after every rho_soft retry)"),
}


class DaqpHierarchicalBackend:
    """One DAQP hierarchical call per solve; the ``daqp.Model`` is reused when the shape repeats.

    Args:
        spec: Registry entry (settings such as ``rho_soft``).
        options: Overrides of DAQP settings (``rho_soft``, ``primal_tol``, ``iter_limit``...).
        lean: Use the measured hot path (see the module docstring); False runs the reference
            path only (stacking, verification and polish on the normalised problem), which gives
            the same answers and is kept for tests and debugging.
    """

    def __init__(self, spec: SolverSpec, options: dict[str, Any] | None = None,
                 lean: bool = True) -> None:
        import daqp  # noqa: F401 - fail here, at construction, if DAQP is missing

        self.spec = spec
        self.lean = lean
        self.settings = {**spec.settings, **(options or {})}
        self._daqp_settings = {k: v for k, v in self.settings.items() if k != "rho_ladder"}
        first = float(self.settings.get("rho_soft", 1e-8))
        self._ladder = (first, [first] + [float(r) for r in self.settings.get("rho_ladder", ())
                                          if r != first])
        self._model: HierarchyModel | None = None
        self._key: tuple[object, ...] | None = None
        self._ws: Workspace | None = None
        self._levels_ref: object = None
        self._sizes: tuple[int, ...] = ()
        self._w: np.ndarray = np.zeros(0)  # level row weights of the loaded problem

    def reset(self) -> None:
        """Forget the DAQP model (the next call sets it up afresh: a cold start)."""
        self._key = None

    @property
    def rho_ladder(self) -> tuple[float, ...]:
        """The ``rho_soft`` values tried after the first one when a solve fails, in order."""
        return tuple(self._ladder[1][1:])

    @property
    def daqp_settings(self) -> dict[str, Any]:
        """The DAQP settings every set-up applies (registry values merged with the options)."""
        return dict(self._daqp_settings)

    # ---------------------------------------------------------------------------- workspace
    def workspace(self, n: int, hard_rows: int, sizes: tuple[int, ...]) -> Workspace:
        """The buffers of structure ``(n, hard_rows, sizes)`` (kept while it repeats)."""
        ws = self._ws
        if ws is None or ws.key != (n, hard_rows, sizes):
            ws = self._ws = Workspace(n, hard_rows, sizes)
        return ws

    def _problem_workspace(self, problem: Problem) -> Workspace:
        levels = problem.levels
        if levels is not self._levels_ref:  # the same tuple of blocks has the same sizes
            self._sizes = tuple(b.A.shape[0] for b in levels)
            self._levels_ref = levels
        return self.workspace(problem.n, problem.hard.A.shape[0], self._sizes)

    def solve(self, problem: Problem) -> BackendOutput:
        """Solve all levels in one DAQP call, then clip/project round-off into the hard set."""
        ws = self._problem_workspace(problem)
        lo, hi, w = ws.load_problem(problem)
        return self.solve_loaded(ws, lo, hi, w, problem.W, lambda: problem)

    def solve_loaded(self, ws: Workspace, lo: np.ndarray, hi: np.ndarray, w: np.ndarray,
                     W: np.ndarray, get_problem: Callable[[], Problem]) -> BackendOutput:
        """Solve the problem already loaded in ``ws`` (rows in ``ws.A``, sides ``lo``/``hi``).

        Args:
            ws: Workspace holding the rows (from :meth:`workspace`).
            lo: Stacked lower sides ``[lower; lo_H; lo_1; ...]``.
            hi: Stacked upper sides.
            w: Level row weights.
            W: Diagonal of the metric (validated), shape (n,).
            get_problem: Returns the normalised problem; called only off the hot path.
        """
        n, head = ws.n, ws.head
        hard_eq = (lo[n:head] == hi[n:head]).tobytes() if ws.mh else b""
        # the workspace itself, not its shape: DAQP reads this workspace's arrays, and a call
        # that failed after a new workspace of the same shape was made must not leave the model
        # reading the old one
        key = (ws, hard_eq, W.tobytes())
        self._w = w
        if key != self._key:
            model = HierarchyModel(ws, W, lo[n:head] == hi[n:head], self._daqp_settings)
            if model.flag < 0:
                self._model, self._key = None, None
                return BackendOutput(None, Status.BACKEND_ERROR,
                                     f"DAQP setup failed (exit flag {model.flag})",
                                     {"exitflag": model.flag})
            self._model, self._key = model, key
            model.load(w, first=True)
            setup_time = model.setup_time
        else:
            model = cast(HierarchyModel, self._model)  # kept with the key
            model.load(w)
            setup_time = 0.0
        if not self.lean:
            problem = get_problem()
            x, flag, info, rho = self._solve_with_retries(problem)
        else:
            raw, flag, c_time, iterations = model.solve()
            x = raw.copy()  # the result keeps x; the model's buffer is reused
            info = {"solve_time": c_time, "setup_time": setup_time, "iterations": iterations}
            if flag in (1, 2):
                fast = self._measure(ws, x, lo, hi, get_problem)
                if fast is not None:
                    x, s, hv = fast
                    extra = self._extra(flag, info, self._ladder[0])
                    return BackendOutput(x, Status.OPTIMAL, "", extra, (ws, s, lo, hi, w, hv))
            problem = get_problem()
            x, flag, info, rho = self._solve_with_retries(problem, (x, flag, info))
        extra = self._extra(flag, info, rho)
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

    @staticmethod
    def _extra(flag: int, info: dict[str, Any], rho: float) -> dict[str, object]:
        return {"exitflag": int(flag), "daqp_solve_time": info["solve_time"],
                "daqp_setup_time": info["setup_time"], "iterations": info["iterations"],
                "rho_soft": rho}

    @staticmethod
    def _measure(ws: Workspace, x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                 get_problem: Callable[[], Problem]) -> tuple[np.ndarray, np.ndarray, float] | None:
        """Accept DAQP's first answer if the box and hard rows hold; polish it like the reference.

        Returns ``(x, slacks at x, box/hard violation at x)``, or None to continue on the
        reference path (non-finite values, or a box/hard violation above the acceptance
        threshold).
        """
        if not math.isfinite(sum(x.tolist())):  # NaN/inf (or an overflow: reference path)
            return None
        n = ws.n
        if not ws.mh:  # box only: check and clip before the one product with the rows
            clipped = np.minimum(np.maximum(x, lo[:n]), hi[:n])
            off = (x - clipped).tolist()
            if max(max(off), -min(off)) > _ACCEPT:
                return None
            s = ws.slacks(clipped, lo, hi)
            if not math.isfinite(sum(s.tolist())):
                return None
            return clipped, s, 0.0
        s = ws.slacks(x, lo, hi)
        values = s.tolist()
        if not math.isfinite(sum(values)):
            return None
        head = ws.head
        top = values[:head]
        hv = max(max(top), -min(top), 0.0)
        if hv > _ACCEPT:
            return None
        box = values[:n]
        if max(box) > 0.0 or min(box) < 0.0:  # round-off outside the box: clip (exact)
            x = np.minimum(np.maximum(x, lo[:n]), hi[:n])
            s = ws.slacks(x, lo, hi)
        if box_and_hard_violation(s[n:], ws.mh) > _POLISH:
            x = polish_hard(get_problem(), x)
            s = ws.slacks(x, lo, hi)
        return x, s, box_and_hard_violation(s, head)

    def _solve_with_retries(
        self, problem: Problem, first: tuple[np.ndarray, int, dict[str, Any]] | None = None
    ) -> tuple[np.ndarray, int, dict[str, Any], float]:
        """Solve; if DAQP stalls (exit flag 3 or a violated hard row), retry with other rho_soft.

        A very small ``rho_soft`` makes the soft-row subproblems badly conditioned and DAQP can
        stop on a point that breaks hard rows. The retries walk the ladder ``rho_ladder``
        (registry data) from a cold start; the value that worked is reported in ``info``.
        ``first`` is the answer of a solve already made with the first ``rho_soft``.
        """
        first_rho, ladder = self._ladder
        model = cast(HierarchyModel, self._model)  # set up by solve_loaded
        tol = max(self.spec.hard_tol * hard_scale(problem), 1e-7)
        for i, rho in enumerate(ladder):
            if i:
                model.cold(self._w, rho)
            if i == 0 and first is not None:
                x, flag, info = first
            else:
                raw, flag, c_time, iterations = model.solve()
                x = raw.copy()
                info = {"solve_time": c_time, "setup_time": 0.0, "iterations": iterations}
            if flag == -1:
                break
            if flag in (1, 2) and _box_rows_violation(problem, x) <= tol:
                break
            if flag in (1, 2):
                flag = 3  # claimed success but a hard row is broken: not acceptable
        if len(ladder) > 1 and rho != first_rho:
            model.restore()
        return x, int(flag), info, rho


def _box_rows_violation(problem: Problem, x: np.ndarray) -> float:
    """Violation of the hard rows (the box is clipped afterwards: only gross box errors count)."""
    v = 0.0
    if problem.hard.m:
        v = float(np.abs(problem.hard.violation(x)).max())
    return max(v, float((problem.lower - x).max()), float((x - problem.upper).max()))
