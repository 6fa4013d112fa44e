"""DAQP's native hierarchical mode: all levels in one call, on the problem's own buffers.

DAQP solves ``min 0.5 x' H x`` subject to prioritised groups of rows separated by break points;
the first group is hard, each later group is softened and its violation minimised
lexicographically, and ``H`` regularises whatever freedom is left. We pass

* ``H = diag(W)``, ``f = 0``: the final regularisation is exactly ``min x' W x``;
* group 0: the box (DAQP's simple bounds) and the hard rows; hard equality rows start active and
  immutable;
* group k: the rows of level k-1; rows and sides are read in place from the problem's buffers
  (DAQP treats sides beyond ``1e30``, infinities included, as absent);
* per-row soft weights (below), so that every level minimises its weighted violation.

Weights: DAQP softens every row of a level after scaling it to unit norm in the metric of the
QP (the rows ``m_i = a_i W^(-1/2)`` of its least-distance form), so with one uniform soft weight
a level that cannot be met minimises ``sum_i (s_i / |m_i|)^2`` whatever the row weights. DAQP
(0.11) also takes one reciprocal quadratic weight ``rho_i`` per row, in the scale of the original
problem (the penalty of row ``i`` is ``s_i^2 / (2 rho_i)``). With

    rho_i = rho_soft * max_{j in level} (w_j |m_j|^2) / w_i

the penalties of a level are proportional to ``w_i s_i^2``, the weighted least-squares violation
every other back-end minimises, and the normalised weights DAQP works with are never below
``rho_soft`` (the most weighted row keeps the regularisation DAQP is tuned for). A level whose
rows are all zero keeps the default. A DAQP built without per-row weights keeps the normalised
compromise (see ``docs/solver.md``).

The set-up is kept per problem (its buffers, metric and hard equality pattern) and warm-started
from the previous solve's working set. Accepting an answer (:meth:`DaqpBackend.solve`): DAQP's
exit flag says solved, ``x`` is finite, the box and hard rows hold to
``max(hard_tol * max(1, |hard sides|), 1e-7)`` at ``x``; round-off outside the box is clipped
exactly, hard rows violated by more than 1e-12 are projected
(:func:`~uvms_qp.hqp.hard_set.polish_hard`). Anything else walks the ladder of other
``rho_soft`` values from a cold start (a very small ``rho_soft`` makes the soft subproblems badly
conditioned and DAQP can stop early or on a point that breaks a hard row); the value that worked
is reported in ``info["rho_soft"]``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from time import perf_counter
from typing import Any

import numpy as np

from ..._validation import FloatArray, as_scalar
from ...errors import InputError
from ..degenerate import Reduction, dependent_rows
from ..hard_set import hard_feasible, polish_hard
from ..linalg import one_blas_thread
from ..linalg import segment_max as _level_max
from ..linalg import square as _square
from ..measure import Measured, measure
from ..problem import Problem
from ..registry import SolverSpec
from ..result import Status
from . import Answer
from .daqp_binding import DaqpBinding, check_version, open_daqp

#: DAQP settings a caller may set (the keys of ``daqp.Model.settings``).
DAQP_SETTINGS = frozenset((
    "primal_tol", "dual_tol", "zero_tol", "pivot_tol", "progress_tol", "cycle_tol",
    "iter_limit", "fval_bound", "eps_prox", "eta_prox", "rho_soft", "w_soft", "rel_subopt",
    "abs_subopt", "sing_tol", "refactor_tol", "time_limit", "eq_reduction", "presolve",
))

_SOLVED = (1, 2)
_OPTIMAL = Status.OPTIMAL
_STOP = (-1, -7)  # empty hard set, time limit: another rho_soft cannot help
_ACCEPT = 1e-7  # box/hard violation accepted (then clipped / projected) whatever the scale
_POLISH = 1e-12  # hard rows violated by more than this are projected
_ROUND_OFF = 1e-13  # a clip into the box this small is not measured again (no hard rows)
_KEEP = 8  # set-ups kept (the problems a solver alternates between: full, relaxed)

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


def check_settings(options: dict[str, Any]) -> dict[str, Any]:
    """A copy of DAQP options after checking keys and values (``rho_ladder`` included).

    Raises:
        InputError: an unknown key (the message lists the known ones) or a value that is not a
            real number (``rho_ladder``: not a list of positive numbers).
    """
    out = dict(options)
    for key, value in options.items():
        if key == "rho_ladder":
            if isinstance(value, str | bytes) or not isinstance(value, list | tuple):
                raise InputError(f"options['rho_ladder']: expected a list of positive numbers, "
                                 f"got {value!r}")
            out[key] = tuple(as_scalar(r, f"options['rho_ladder'][{k}]", positive=True)
                             for k, r in enumerate(value))
        elif key not in DAQP_SETTINGS:
            known = ", ".join(sorted(DAQP_SETTINGS | {"rho_ladder", "level_tol", "hard_tol"}))
            raise InputError(f"options: unknown setting {key!r} (known: {known})")
        else:
            as_scalar(value, f"options[{key!r}]", allow_inf=True)
    return out


class _Setup:
    """DAQP set up on one problem: working sets, and the per-row soft weights' data."""

    __slots__ = (
        "W",
        "binding",
        "eq",
        "eq_key",
        "first",
        "flag",
        "head",
        "inv_W",
        "levels",
        "problem",
        "rho",
        "scatter",
        "sense0",
        "setup_time",
        "squares",
        "starts",
        "version",
        "views",
    )

    def __init__(self, problem: Problem, settings: dict[str, Any], binding: DaqpBinding) -> None:
        n, head, M = problem.n, problem.head, problem.M
        self.problem, self.head, self.W = problem, head, problem.W
        self.eq = problem.lo[n:head] == problem.hi[n:head]
        self.eq_key = self.eq.tobytes()
        self.sense0 = np.zeros(M, dtype=np.intc)  # the cold-start working set
        self.sense0[n:head][self.eq] = 5  # hard equality rows: active and immutable
        bp = np.unique(np.cumsum((head, *problem.sizes))).astype(np.intc)
        self.binding = binding
        # DAQP reads the rows and sides in place (it takes +-inf sides as its own infinity)
        self.flag, self.setup_time = binding.setup(
            np.diag(self.W), np.zeros(n), problem.A[n:], problem.hi, problem.lo,
            self.sense0.copy(), bp)
        sizes = problem.sizes
        ml = M - head
        self.squares = np.zeros((ml, n))
        self.inv_W = 1.0 / self.W
        filled = [k for k, m in enumerate(sizes) if m]  # reduceat needs non-empty segments
        self.starts = (np.cumsum((0, *sizes))[filled]).astype(np.intp)
        self.levels = problem.A[head:]
        self.rho = np.zeros(M)
        self.scatter: dict[float, FloatArray] = {}
        self.version = -1
        self.first = True
        self.views: tuple[FloatArray, FloatArray] | None = None
        if self.flag >= 0:
            binding.settings = settings
            views = binding.soft_weight_views()
            if views is not None and ml:
                self.views = (views[0][head:], views[1][head:])

    def level_weights(self, rho_soft: float, out: FloatArray) -> None:
        """The per-row ``rho_i`` of the module docstring, written into ``out`` (level rows).

        ``rho_i = S_ik top_k`` with ``top_k = max_{j in level k} w_j |a_j W^(-1/2)|^2`` and the
        scatter matrix ``S_ik = rho_soft / w_i`` for the rows of level k (0 elsewhere), one
        product for all rows.
        """
        problem = self.problem
        q = _square(self.levels, out=self.squares).dot(self.inv_W)  # |a_i W^(-1/2)|^2
        if not problem.unit_weights:
            q *= problem.w
        if problem.weights_version != self.version:
            self.scatter.clear()
            self.version = problem.weights_version
        scatter = self.scatter.get(rho_soft)
        if scatter is None:
            sizes = [m for m in problem.sizes if m]
            scatter = np.zeros((q.shape[0], len(sizes)))
            scatter[np.arange(q.shape[0]), np.repeat(np.arange(len(sizes)), sizes)] = (
                rho_soft / problem.w)
            self.scatter[rho_soft] = scatter
        scatter.dot(_level_max(q, self.starts), out=out)

    def load(self, rho_soft: float) -> None:
        """Hand this solve's rows, sides and soft weights to DAQP (warm start kept)."""
        views = self.views
        if self.first:  # set up on these values already: only the weights
            self.first = False
            if views is not None:
                self.level_weights(rho_soft, self.rho[self.head:])
                self.binding.soft_weights(self.rho)
        elif views is not None:
            lower, upper = views
            self.level_weights(rho_soft, lower)
            upper[...] = lower
            self.binding.refresh()
        else:
            self.binding.refresh()

    def cold(self, rho_soft: float) -> None:
        """Prepare a cold-started retry with another ``rho_soft`` (setting and weights)."""
        self.binding.settings = {"rho_soft": rho_soft}
        if self.views is not None:
            self.level_weights(rho_soft, self.rho[self.head:])
            self.binding.soft_weights(self.rho)
        self.binding.restart(self.sense0.copy())


class DaqpBackend:
    """One DAQP hierarchical call per solve (see the module docstring).

    Args:
        spec: Registry entry (settings such as ``rho_soft`` and the ``rho_ladder``).
        options: Overrides of DAQP settings (``rho_soft``, ``primal_tol``, ``time_limit``...) and
            ``rho_ladder`` (checked by :func:`check_settings`).

    Attributes:
        open_binding: Makes the DAQP binding of each set-up (default
            :func:`~uvms_qp.hqp.backends.daqp_binding.open_daqp`); replace it to observe or
            fault the C calls (:mod:`uvms_qp.testing.faults`).
    """

    factorises = False  # (DAQP's C calls no BLAS; the reduction's SVD enters the limit itself)

    def __init__(self, spec: SolverSpec, options: dict[str, Any] | None = None) -> None:
        import daqp  # noqa: F401 - fail here, at construction, if DAQP is missing

        self.spec = spec
        merged = {**spec.settings, **check_settings(options or {})}
        self.rho_ladder: tuple[float, ...] = tuple(merged.pop("rho_ladder", ()))
        self.settings = merged
        self.rho_soft = float(merged.get("rho_soft", 1e-8))
        self.open_binding: Callable[[], DaqpBinding] = open_daqp
        check_version()  # a DAQP the binding does not mirror is refused here, not in a solve
        self._ladder = (self.rho_soft, *[r for r in self.rho_ladder if r != self.rho_soft])
        self.end = math.inf  # the solve's end: DAQP's own ``time_limit`` is cut to it
        self.clock: Callable[[], float] = perf_counter
        self._setups: dict[Problem, _Setup] = {}
        self._last: tuple[Problem | None, _Setup | None] = (None, None)
        self._reductions: dict[Problem, Reduction] = {}

    def reset(self) -> None:
        """Forget every set-up: the next solve sets DAQP up afresh (a cold start).

        The rows left out by :meth:`reduce` stay out (they are a property of the problem's
        structure, and every answer is certified on the full problem anyway).
        """
        self._setups.clear()
        self._last = (None, None)

    def reduce(self, problem: Problem) -> bool:
        """Leave the level rows that are constant over the higher levels' optimum out of DAQP.

        DAQP 0.11's hierarchical mode can drop a level whose row lies in the span of the
        equality rows above it (a repeated or combined row, a level left without freedom) and
        still report success; without those rows (:func:`~uvms_qp.hqp.degenerate.dependent_rows`,
        constants of the level, measured on the full problem afterwards) it gives the exact
        optimum. The rows found are left out of every later solve of ``problem`` (a controller's
        problem keeps its structure from tick to tick) until a certificate fails again and the
        rows are found afresh.

        Returns:
            True when the rows left out changed.
        """
        with one_blas_thread:  # (SVDs: a small problem's solve runs without the limit)
            drop = dependent_rows(problem.A, problem.lo, problem.hi, problem.n, problem.mh,
                                  problem.sizes)
        old = self._reductions.get(problem)
        if not drop.any():
            return self._reductions.pop(problem, None) is not None
        if old is not None and np.array_equal(old.drop, drop):
            return False
        if len(self._reductions) >= _KEEP:
            self._reductions.pop(next(iter(self._reductions)))
        self._reductions[problem] = Reduction(problem, drop)
        return True

    def _setup(self, problem: Problem) -> _Setup:
        last, setup = self._last
        if problem is not last or setup is None:
            setup = self._setups.get(problem)
        if setup is not None and problem.W is setup.W:
            if not problem.mh:
                return setup
            eq = setup.eq
            np.equal(problem.lo[problem.n:problem.head], problem.hi[problem.n:problem.head],
                     out=eq)
            if eq.tobytes() == setup.eq_key:
                return setup
        setup = _Setup(problem, self.settings, self.open_binding())
        if setup.flag >= 0:
            if len(self._setups) >= _KEEP:
                self._setups.pop(next(iter(self._setups)))
            self._setups[problem] = setup
            self._last = (problem, setup)
        return setup

    def solve(self, problem: Problem) -> Answer:
        """Solve every level in one DAQP call; accept, or walk the ``rho_soft`` ladder.

        A problem with rows left out by :meth:`reduce` is solved without them (the answer is
        measured on the full problem by the caller); a failed solve is tried once more after
        :meth:`reduce`.
        """
        answer = self._solve_reduced(problem) if self._reductions else self._solve(problem)
        if answer.status is not _OPTIMAL and self.reduce(problem):
            # DAQP failed (a zero row with a nonzero target makes it call the hierarchy
            # infeasible): once more without the rows that are constants of their level
            answer = self._solve_reduced(problem)
        return answer

    def _solve_reduced(self, problem: Problem) -> Answer:
        reduction = self._reductions.get(problem)
        if reduction is None:
            return self._solve(problem)
        answer = self._solve(reduction.fill(problem))
        answer.measured = None  # measured on the reduced rows: the full problem measures again
        answer.info["reduced_rows"] = int(reduction.drop.sum())
        return answer

    def _solve(self, problem: Problem) -> Answer:
        setup = self._setup(problem)
        if setup.flag < 0:
            self.reset()
            # DAQP's "infeasible" covers the soft levels too (a zero row with a nonzero
            # target): the hard set is judged on its own
            if not hard_feasible(problem, self._time_left()):
                return Answer(None, Status.HARD_INFEASIBLE,
                              "the hard box and hard rows admit no point", {"exitflag": setup.flag})
            return Answer(None, Status.BACKEND_ERROR,
                          f"DAQP setup failed (exit flag {setup.flag})", {"exitflag": setup.flag})
        binding = setup.binding
        setup_time = setup.setup_time if setup.first else 0.0
        setup.load(self.rho_soft)
        c_time, iterations, flag = 0.0, 0, 0
        rho = self.rho_soft
        accepted: tuple[FloatArray, Measured] | None = None
        raw: Any = None
        for i, rho in enumerate(self._ladder):
            if i:
                if self.clock() > self.end:
                    flag = -7  # the solve's end passed: no further rho_soft
                    break
                setup.cold(rho)
            flag = binding.solve()
            raw = binding.x
            c_time += binding.solve_time
            iterations += binding.iterations
            if flag in _SOLVED:
                accepted = self._accept(problem, raw)
                if accepted is not None:
                    break
                flag = 3  # claimed success on a point that breaks the box or a hard row
            elif flag in _STOP:
                break
        if rho != self.rho_soft:
            binding.settings = {"rho_soft": self.rho_soft}  # the next load sets its weights
        info: dict[str, object] = {"exitflag": flag, "daqp_solve_time": c_time,
                                   "daqp_setup_time": setup_time, "iterations": iterations,
                                   "rho_soft": rho}
        if accepted is not None:
            return Answer(accepted[0], _OPTIMAL, "", info, accepted[1])
        self.reset()  # set up afresh after a failure
        reason = _FLAGS.get(flag, "unknown failure")
        status = Status.BACKEND_ERROR
        if not hard_feasible(problem, self._time_left()):
            status = Status.HARD_INFEASIBLE
            reason = "the hard box and hard rows admit no point"
        x = np.array(raw, dtype=np.float64) if raw is not None else None
        return Answer(x, status, f"DAQP exit flag {flag}: {reason}", info)

    def _time_left(self) -> float | None:
        """Time left until the solve's end [s], or None without one (for the hard-set LP)."""
        return None if self.end == math.inf else self.end - self.clock()

    def _accept(self, problem: Problem, raw: Any) -> tuple[FloatArray, Measured] | None:
        """``(x, measurement)`` when DAQP's answer holds the box and hard rows, else None.

        ``x`` is the answer clipped into the box; after a clip (round-off at an active bound,
        common) it is measured again, so the measurement is exactly that of ``x``.
        """
        if getattr(raw, "shape", None) != (problem.n,):
            return None
        measured = measure(problem, raw)
        squares = measured[2]
        total = sum(squares)
        if total != total or total == math.inf:  # NaN / inf in x (or an overflow)
            return None
        head_sq = squares[0]
        if not head_sq:  # nothing outside the box or a hard row
            return measured[1], measured
        n, head = problem.n, problem.head
        if head_sq <= _ROUND_OFF * _ROUND_OFF and not problem.mh:
            # round-off outside an active bound (common): x is the clipped answer; the other
            # rows move by at most |A| 1e-13, far below every tolerance, so the measurement
            # stands with the box rows' slacks made exactly zero
            measured[0][:n] = 0.0
            squares[0] = 0.0
            return measured[1], measured
        if problem.mh or head_sq > _ACCEPT * _ACCEPT:
            values = measured[0][:head].tolist()
            box = max(max(values[:n]), -min(values[:n]))
            hard = max(max(values[n:]), -min(values[n:])) if problem.mh else 0.0
            if max(box, hard) > _ACCEPT and max(box, hard) > (
                    self.spec.hard_tol * problem.hard_scale):
                return None
        else:
            box, hard = 1.0, 0.0  # the box alone, by at most 1e-7
        x = measured[1]
        if box:  # round-off outside the box: x is the clipped answer, measured again
            measured = measure(problem, x)
            hard = math.sqrt(measured[2][0])  # the box rows hold exactly now
        if hard > _POLISH:
            x = polish_hard(problem, x)
            measured = measure(problem, x)
        return x, measured
