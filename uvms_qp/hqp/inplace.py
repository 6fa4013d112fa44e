"""DAQP's hierarchy on a fixed structure whose rows and sides the caller writes in place.

A control loop solves the same structure every tick: the same number of variables, hard rows and
rows per level; only the values change. :class:`InPlaceDaqp` owns the stacked buffers of that
structure (a :class:`~uvms_qp.hqp.workspace.Workspace` plus the unclamped sides), the caller
writes each tick's rows and sides straight into views of them, and :meth:`InPlaceDaqp.solve`
hands them to DAQP and measures the answer without copying the problem anywhere:

1. DAQP's clamped sides ``max(lo, -1e30)``, ``min(hi, 1e30)`` (two array operations);
2. per-row soft weights (:mod:`uvms_qp.hqp.daqp_weights`: every level minimises its weighted
   violation, as on the other back-ends), one update and one solve (through
   :class:`~uvms_qp.hqp.daqp_native.NativeDaqp` when available, the weights written straight
   into DAQP's arrays), warm-started from the previous tick's working set;
3. acceptance, from one product of the stacked rows with DAQP's ``x``: exit flag 1 or 2,
   finite ``x``, ``x`` inside the box to ``1e-7`` (then clipped into it exactly and measured
   again), hard rows at the clipped ``x`` within the solver's bare hard tolerance
   (``1e-9``, never looser than the relative tolerance of
   :func:`~uvms_qp.safety.verify.verify_command`);
4. the level residuals and statuses of :func:`~uvms_qp.hqp.evaluate.evaluate_stacked` from the
   same slacks.

Anything not accepted returns None with the reason in :attr:`InPlaceDaqp.rejected`; the caller
then runs its general path (validation-free :class:`~uvms_qp.hqp.problem.Problem` over the same
buffers, the rho_soft retry ladder and the safety ladder of :mod:`uvms_qp.safety`). So this class
only ever shortens the happy path: every answer it returns would also have been accepted there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from time import perf_counter
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from .daqp_model import HierarchyModel
from .evaluate import evaluate_stacked
from .registry import get_spec
from .result import StackedResult, Status
from .workspace import DAQP_INF, Workspace

#: Largest box violation of DAQP's answer that is clipped away (as the back-end's lean path).
BOX_ACCEPT = 1e-7
_SOLVED = (1, 2)
_NO_RETRY = (-1, -7)  # empty hard set, time limit: another rho_soft cannot help


#: DAQP settings a caller may set (the keys of ``daqp.Model.settings``).
DAQP_SETTINGS = frozenset((
    "primal_tol", "dual_tol", "zero_tol", "pivot_tol", "progress_tol", "cycle_tol",
    "iter_limit", "fval_bound", "eps_prox", "eta_prox", "rho_soft", "w_soft", "rel_subopt",
    "abs_subopt", "sing_tol", "refactor_tol", "time_limit", "eq_reduction", "presolve",
))


def check_settings(settings: Any, name: str, extra: frozenset[str] = frozenset()) -> dict[str, Any]:
    """Return a copy of a DAQP settings dict after checking its keys and numeric values.

    Args:
        settings: Mapping of DAQP setting names (:data:`DAQP_SETTINGS`, plus ``extra``) to numbers.
        name: Argument name for error messages.
        extra: Further allowed keys; their values are not checked here.

    Raises:
        InputError: not a dict, an unknown key (the message lists the known ones), or a value
            that is not a real number.
    """
    if not isinstance(settings, dict):
        raise InputError(f"{name}: expected a dict of settings, got {type(settings).__name__}")
    for key, value in settings.items():
        if key in extra:
            continue
        if not isinstance(key, str) or key not in DAQP_SETTINGS:
            known = ", ".join(sorted(DAQP_SETTINGS | extra))
            raise InputError(f"{name}: unknown setting {key!r} (known: {known})")
        as_scalar(value, f"{name}[{key!r}]", allow_inf=True)
    return dict(settings)


def _tolerance(value: Any, name: str) -> float:
    """A finite positive tolerance (NaN would switch the check it drives off)."""
    return as_scalar(value, name, positive=True)


def _count(value: Any, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < least:
        raise InputError(f"{name}: expected an integer >= {least}, got {value!r}")
    return int(value)


class InPlaceDaqp:
    """DAQP hierarchical solves over caller-filled buffers (see the module docstring).

    Args:
        n: Number of variables.
        hard_rows: Number of hard general rows.
        sizes: Rows per level, highest priority first (each at least 1).
        W: Diagonal metric (n,) of the final regularisation ``min x' W x`` (positive).
        settings: DAQP settings (``rho_soft``, ``time_limit``, ...); default: the registry's
            settings of the ``"daqp"`` back-end.
        rho_ladder: Other ``rho_soft`` values tried in order, each from a cold start, when a
            solve stops early (DAQP's exit flag 3, a level it could not finish, or another
            failure that is not an empty hard set or a time limit); default: the registry's
            ladder, the one the back-end walks on its general path.
        level_tol: Relative tolerance deciding that a level is met.
        hard_tol: Relative tolerance on the hard rows (also the bare acceptance threshold).
        name: Solver name recorded in results.

    Raises:
        InputError: a non-positive size, a negative hard row count, or a bad metric.

    Example:
        >>> import numpy as np
        >>> from uvms_qp.hqp.inplace import InPlaceDaqp
        >>> solver = InPlaceDaqp(2, 0, [1, 1], np.ones(2))
        >>> rows, lo, hi = solver.ws.A[2:], solver.lo, solver.hi   # write these every tick
        >>> rows[:] = [[1.0, 1.0], [1.0, -1.0]]
        >>> lo[:2], hi[:2] = -1.0, 1.0                               # the box
        >>> lo[2:] = hi[2:] = [1.0, 0.0]                             # two equality levels
        >>> result = solver.solve()                                  # None: use a fallback
        >>> np.round(result.x, 6).tolist()
        [0.5, 0.5]

    Attributes:
        ws: The workspace: ``ws.A`` = ``[I; A_H; A_1; ...; A_p]`` (write rows ``ws.A[n:]``).
        lo: Stacked lower sides ``[lower; lo_H; lo_1; ...]`` (``-inf`` allowed), written by the
            caller.
        hi: Stacked upper sides.
        w: Row weights of the level rows (``sum(sizes)``,).
        rejected: Why the latest :meth:`solve` returned None ("" after an accepted solve).
        clipped: Amount the latest accepted ``x`` was clipped into the box.
    """

    def __init__(self, n: int, hard_rows: int, sizes: Sequence[int], W: Any = None,
                 settings: dict[str, Any] | None = None, *, level_tol: float | None = None,
                 hard_tol: float | None = None, rho_ladder: Sequence[float] | None = None,
                 name: str = "daqp") -> None:
        spec = get_spec("daqp")
        n = _count(n, "n", 1)
        hard_rows = _count(hard_rows, "hard_rows", 0)
        if not isinstance(sizes, list | tuple) or not sizes:
            raise InputError(f"sizes: expected a non-empty list of row counts, got {sizes!r}")
        sizes = [_count(m, f"sizes[{k}]", 1) for k, m in enumerate(sizes)]
        W = np.ones(n) if W is None else as_vector(W, "W", n, positive=True)
        if settings is None:
            settings = {k: v for k, v in spec.settings.items() if k != "rho_ladder"}
        else:
            settings = check_settings(settings, "settings")
        if rho_ladder is None:
            rho_ladder = spec.settings.get("rho_ladder", ())
        elif isinstance(rho_ladder, str | bytes) or not isinstance(rho_ladder, Sequence):
            raise InputError(f"rho_ladder: expected a list of positive numbers, got {rho_ladder!r}")
        else:
            rho_ladder = [_tolerance(r, f"rho_ladder[{k}]") for k, r in enumerate(rho_ladder)]
        level_tol = spec.level_tol if level_tol is None else _tolerance(level_tol, "level_tol")
        hard_tol = spec.hard_tol if hard_tol is None else _tolerance(hard_tol, "hard_tol")
        self.ws = ws = Workspace(n, hard_rows, sizes)
        self.lo = np.zeros(ws.M)
        self.hi = np.zeros(ws.M)
        self.w = np.ones(ws.ml)
        self.W = np.array(W, dtype=np.float64)
        self.settings = dict(settings)
        self.level_tol = float(level_tol)
        self.hard_tol = float(hard_tol)
        self.name = name
        self.rejected = ""
        self.clipped = 0.0
        self._model: HierarchyModel | None = None
        self._hard_eq = np.zeros(ws.mh, dtype=bool)
        self._hard_key: bytes | None = None
        self._rho_soft = float(self.settings.get("rho_soft", 1e-8))
        self.rho_ladder = tuple(float(r) for r in rho_ladder if float(r) != self._rho_soft)
        # persistent views (basic slicing once, not every tick)
        self._lo_box, self._hi_box = self.lo[:n], self.hi[:n]
        self._lo_hard, self._hi_hard = self.lo[n:ws.head], self.hi[n:ws.head]

    def reset(self) -> None:
        """Forget the DAQP model: the next solve sets it up afresh (a cold start)."""
        self._hard_key = None

    def _retry(self, model: HierarchyModel, c_time: float,
               iterations: int) -> tuple[FloatArray, int, float, int, float]:
        """Walk :attr:`rho_ladder` from cold starts (as the back-end's general path does).

        Returns the last attempt's ``(x, flag)``, the summed C time and iterations, and the
        ``rho_soft`` of the last attempt; ``rho_soft`` is restored for the next tick.
        """
        raw: FloatArray = np.zeros(self.ws.n)  # the ladder is never empty here
        flag, rho = 0, self._rho_soft
        try:
            for rho in self.rho_ladder:
                model.cold(self.w, rho)
                raw, flag, t, it = model.solve()
                c_time += t
                iterations += it
                if flag in _SOLVED or flag in _NO_RETRY:
                    break
        finally:
            model.restore()
        return raw, flag, c_time, iterations, rho

    def solve(self) -> StackedResult | None:
        """Solve the problem in the buffers; the accepted result, or None (see :attr:`rejected`).

        The result owns copies of the sides and its slacks; ``x`` is inside the box.
        """
        start = perf_counter()
        ws = self.ws
        lo, hi = self.lo, self.hi
        if ws.mh:
            np.equal(self._lo_hard, self._hi_hard, out=self._hard_eq)
            key = self._hard_eq.tobytes()
        else:
            key = b""
        np.maximum(lo, -DAQP_INF, out=ws.bl)
        np.minimum(hi, DAQP_INF, out=ws.bu)
        model = self._model
        if key != self._hard_key or model is None:
            model = HierarchyModel(ws, self.W, self._hard_eq, self.settings)
            if model.flag < 0:
                self._model, self._hard_key = None, None
                self.rejected = f"DAQP setup failed (exit flag {model.flag})"
                return None
            self._model, self._hard_key = model, key
            model.load(self.w, first=True)
        else:
            model.load(self.w)
        raw, flag, c_time, iterations = model.solve()
        rho = self._rho_soft
        if flag not in _SOLVED and flag not in _NO_RETRY and self.rho_ladder:
            raw, flag, c_time, iterations, rho = self._retry(model, c_time, iterations)
        if flag not in _SOLVED:
            self._hard_key = None  # set up afresh next time
            self.rejected = f"DAQP exit flag {flag}"
            return None
        # one product measures everything: the box rows' slacks are raw - clip(raw, box), so
        # they give the clip amount, and any NaN/inf in raw makes the sum of slacks non-finite
        n = ws.n
        s = ws.slacks(raw, lo, hi)
        values = s.tolist()
        if not math.isfinite(sum(values)):  # NaN/inf in x, in a row or in a side
            self._hard_key = None  # do not warm-start from this solve
            self.rejected = "non-finite x, rows or sides"
            return None
        box = values[:n]
        clipped = max(max(box), -min(box))
        if clipped > BOX_ACCEPT:
            self.rejected = f"box violated by {clipped:.2e}"
            return None
        if clipped:  # round-off outside the box: clip (raw - s would round) and measure again
            x = np.minimum(np.maximum(raw, self._lo_box), self._hi_box)
            s = ws.slacks(x, lo, hi)
            values = s.tolist()
        else:
            x = raw.copy()
        if ws.mh:
            top = values[n:ws.head]
            hv = max(max(top), -min(top), 0.0)
            if hv > self.hard_tol:
                self.rejected = f"hard rows violated by {hv:.2e}"
                return None
        else:
            hv = 0.0
        self.clipped = clipped
        self.rejected = ""
        info: dict[str, object] = {"exitflag": flag, "daqp_solve_time": c_time,
                                   "iterations": iterations, "rho_soft": rho}
        result = evaluate_stacked(ws, x, s, lo.copy(), hi.copy(), self.w, hv, self.name,
                                  Status.OPTIMAL, "", level_tol=self.level_tol,
                                  hard_tol=self.hard_tol, solve_time=perf_counter() - start,
                                  info=info)
        if not isinstance(result, StackedResult) or not result.ok:  # pragma: no cover
            self.rejected = result.message or "not a stacked result"
            return None
        return result
