"""The fallback ladder: a finite command inside the hard box on every step, and the truth about it.

:class:`SafeSolver` wraps a :class:`~uvms_qp.hqp.HierarchySolver`. Each call of
:meth:`SafeSolver.solve` climbs down the ladder until a stage produces a command that passes
verification (:mod:`uvms_qp.safety.verify`: finite, hard box and hard rows hold, a solution
status); the stage that ran is named in :attr:`SafeSolve.stage`:

=====================  =====================================================================
stage                  what it does
=====================  =====================================================================
``primary``            the configured back-end, warm-started as usual (the happy path)
``cold_retry``         the same back-end after its warm start / workspace has been reset
``alternate``          a back-end of another family (DAQP hierarchical <-> a qpsolvers cascade)
``relaxed``            the lowest levels dropped one by one (``relaxed_levels`` says how many)
``decayed_previous``   ``decay`` times the previous command, if it satisfies the hard set now
``zero``               zero clipped into the box (zero rates: the vehicle and arm hold still)
``hold_zero``          after ``max_fallbacks`` consecutive steps ended on one of the two stages
                       above, only the primary back-end is tried, and zero is held until it
                       returns a verified solve
=====================  =====================================================================

Stages after ``alternate`` degrade the command; in strict mode they are not taken and
:class:`~uvms_qp.errors.NoSolutionFound` is raised instead (carrying the failed result). A hard set
that is empty (confirmed by an independent LP) skips every solver stage. Once the step's deadline
has passed (:mod:`uvms_qp.safety.deadline`) the remaining solver stages are skipped as well.
Whatever the stage, the returned command goes through the final saturation
(:mod:`uvms_qp.safety.saturation`), and :attr:`SafeSolve.result` is the evaluation of that
command against the *full* problem, so per-level residuals and the status are truthful:
``optimal``/``level_infeasible`` only for solver stages, ``backend_error`` (or
``hard_infeasible``) for the decayed, zero and hold stages.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError, NoSolutionFound
from ..hqp import HierarchyResult, HierarchySolver, Status
from ..hqp.evaluate import evaluate, hard_feasible
from ..hqp.problem import Problem
from ..hqp.registry import available_solvers, get_spec
from .deadline import CascadeGuard, Deadline, backend_limits, guard_cascade
from .saturation import CLIP_FLAG_TOL, Saturation, saturate
from .verify import verify_point, verify_result

PRIMARY = "primary"
COLD_RETRY = "cold_retry"
ALTERNATE = "alternate"
RELAXED = "relaxed"
DECAYED = "decayed_previous"
ZERO = "zero"
HOLD_ZERO = "hold_zero"

#: Every stage name, in ladder order.
STAGES: tuple[str, ...] = (PRIMARY, COLD_RETRY, ALTERNATE, RELAXED, DECAYED, ZERO, HOLD_ZERO)
#: Stages whose command is a verified solve of the problem (all levels, or the kept levels).
SOLVED_STAGES: frozenset[str] = frozenset((PRIMARY, COLD_RETRY, ALTERNATE, RELAXED))
#: Stages that did not solve the problem.
DEGRADED_STAGES: frozenset[str] = frozenset((DECAYED, ZERO, HOLD_ZERO))

_CASCADE_PREFERENCE = ("cascade:quadprog", "cascade:proxqp", "cascade:piqp", "cascade:clarabel",
                       "cascade:daqp", "cascade:osqp", "cascade:highs")


def default_alternate(solver: str, *, cascade_only: bool = False) -> str | None:
    """A back-end of another family for the fallback ladder, or None if none is installed.

    DAQP's hierarchical mode falls back to a qpsolvers cascade (quadprog first), a cascade to
    DAQP's hierarchical mode; with ``cascade_only`` (problems whose weights DAQP's row
    normalisation would change, e.g. the weighted scheme) a cascade on another library is chosen.

    Args:
        solver: The primary solver name.
        cascade_only: Only cascades qualify.
    """
    installed = set(available_solvers())
    if solver.startswith("cascade:") and not cascade_only and "daqp" in installed:
        return "daqp"
    library = solver.split(":", 1)[-1]
    for name in _CASCADE_PREFERENCE:
        if name in installed and name != solver and name.split(":", 1)[1] != library:
            return name
    return None


def reset_warm_start(solver: HierarchySolver) -> None:
    """Drop the warm start / workspace of a solver so that its next call starts cold.

    Uses ``solver.reset()`` when the solver has one, else the back-end's ``reset()``; DAQP's
    hierarchical back-end keeps its workspace under a structure key, which is cleared.
    """
    hook = getattr(solver, "reset", None)
    if callable(hook):
        hook()
        return
    reset_backend(getattr(solver, "_backend", None))


def reset_backend(backend: Any) -> None:
    """Cold-start one back-end object (see :func:`reset_warm_start`)."""
    hook = getattr(backend, "reset", None)
    if callable(hook):
        hook()
    elif hasattr(backend, "_key"):
        backend._key = None  # DAQP hierarchical: the next call sets the model up afresh


@dataclass(eq=False)
class SafeSolve:
    """One step of the safe solver.

    Attributes:
        x: The command, finite and inside the hard box (saturated), shape (n,) [m/s, rad/s].
        result: Evaluation of ``x`` against the full problem (truthful status and residuals);
            for the primary stage, the back-end's own result.
        stage: The ladder stage that produced ``x`` (one of :data:`STAGES`).
        attempts: One line per failed stage: ``"<stage>: <reason>"``.
        clipped: Amount removed by the final saturation [m/s, rad/s].
        clip_flagged: ``clipped`` exceeded the flag threshold (something upstream went wrong).
        deadline_missed: The step took longer than its deadline.
        relaxed_levels: Number of lowest levels dropped (``relaxed`` stage), else 0.
        elapsed: Wall time of the whole ladder [s].
    """

    x: FloatArray
    result: HierarchyResult
    stage: str
    attempts: tuple[str, ...] = ()
    clipped: float = 0.0
    clip_flagged: bool = False
    deadline_missed: bool = False
    relaxed_levels: int = 0
    elapsed: float = 0.0

    @property
    def solved(self) -> bool:
        """True when ``x`` comes from a verified solve (full or relaxed problem)."""
        return self.stage in SOLVED_STAGES

    @property
    def degraded(self) -> bool:
        """True when the ladder fell back beyond the primary back-end."""
        return self.stage != PRIMARY


class SafeSolver:
    """A hierarchy solver that verifies every answer and falls back safely.

    Args:
        solver: Primary solver name (see :func:`uvms_qp.hqp.available_solvers`).
        weights: Diagonal metric W (n,) of the final regularisation, or None.
        options: Options of the primary back-end (merged over the deadline's limits).
        alternate: Back-end of another family for the ``alternate`` stage: ``"auto"``
            (:func:`default_alternate`), a solver name, or None to skip the stage.
        deadline: Budget of one step's solver stages [s], or None for no deadline.
        max_fallbacks: Consecutive degraded steps after which zero is held until a verified solve.
        decay: Factor on the previous command in the ``decayed_previous`` stage, ``0 <= decay < 1``.
        relax: Take the ``relaxed`` stage.
        strict: Raise :class:`~uvms_qp.errors.NoSolutionFound` instead of degrading.
        clip_flag_tol: Clip amount above which a saturation is flagged [m/s, rad/s].

    Raises:
        UnknownSolverError: unknown or uninstalled primary or alternate solver.
        InputError: a bad deadline, decay or max_fallbacks.
    """

    def __init__(self, solver: str = "daqp", weights: Any = None,
                 options: dict[str, Any] | None = None, *, alternate: str | None = "auto",
                 deadline: float | None = None, max_fallbacks: int = 3, decay: float = 0.5,
                 relax: bool = True, strict: bool = False,
                 clip_flag_tol: float = CLIP_FLAG_TOL) -> None:
        self.deadline = None if deadline is None else as_scalar(
            deadline, "deadline", positive=True, allow_inf=True)
        self.decay = as_scalar(decay, "decay", nonnegative=True)
        if self.decay >= 1.0:
            raise InputError(f"decay: expected 0 <= decay < 1, got {self.decay}")
        if isinstance(max_fallbacks, bool) or not isinstance(max_fallbacks, int) or (
                max_fallbacks < 1):
            raise InputError(f"max_fallbacks: expected a positive integer, got {max_fallbacks!r}")
        self.max_fallbacks = max_fallbacks
        self.clip_flag_tol = as_scalar(clip_flag_tol, "clip_flag_tol", positive=True)
        self.relax = bool(relax)
        self.strict = bool(strict)
        self._options = dict(options or {})
        self.primary = HierarchySolver(
            solver, weights, {**backend_limits(get_spec(solver).name, self.deadline),
                              **self._options})
        self.name = self.primary.name
        if alternate == "auto":
            alternate = default_alternate(self.name)
        if alternate is not None:
            get_spec(alternate)  # raises UnknownSolverError early
            if alternate == self.name:
                alternate = None
        self.alternate_name: str | None = alternate
        # built now: importing a back-end (or SciPy's LP used to confirm an empty hard set) on
        # first use would be a solve-time spike at run time
        import scipy.optimize  # noqa: F401

        self._alternate: HierarchySolver | None = None if alternate is None else HierarchySolver(
            alternate, weights, backend_limits(alternate, self.deadline))
        self._guards: list[CascadeGuard] = []
        if self.deadline is not None and math.isfinite(self.deadline):
            for hs in (self.primary, self._alternate):
                guard = None if hs is None else guard_cascade(getattr(hs, "_backend", None))
                if guard is not None:
                    self._guards.append(guard)
        self.previous: FloatArray | None = None
        self.consecutive = 0
        #: How many steps ended on each stage since construction (for reports and soaks).
        self.stage_counts: Counter[str] = Counter()
        self._last: HierarchyResult | None = None
        self._sat: Saturation | None = None

    # ------------------------------------------------------------------------------ plumbing
    @property
    def alternate(self) -> HierarchySolver | None:
        """The alternate solver, or None."""
        return self._alternate

    @property
    def level_tol(self) -> float:
        """Relative level tolerance of the primary solver."""
        return self.primary.level_tol

    @property
    def hard_tol(self) -> float:
        """Relative hard tolerance of the primary solver."""
        return self.primary.hard_tol

    def reset(self) -> None:
        """Forget the previous command and the fallback count; cold-start the back-ends."""
        self.previous = None
        self.consecutive = 0
        reset_warm_start(self.primary)
        if self._alternate is not None:
            reset_warm_start(self._alternate)

    def _attempt(self, solver: HierarchySolver, problem: Problem, stage: str, tol: float,
                 attempts: list[str]) -> HierarchyResult | None:
        """Run one back-end call; return its result if verified, else record why and None.

        The saturation of a verified ``x`` is kept in ``self._sat`` for :meth:`_solved`.
        """
        try:
            result = solver.solve_problem(problem)
        except Exception as exc:  # any back-end exception, ours or foreign, is a failed stage
            attempts.append(f"{stage}: raised {type(exc).__name__}: {exc}")
            self._last = None
            return None
        self._last = result
        verdict, sat = verify_result(problem, result, tol)
        if verdict.ok:
            self._sat = sat
            return result
        if verdict.reason == "not_a_solution":
            detail = result.status.value + (f" ({result.message})" if result.message else "")
        else:
            detail = f"{verdict.reason} ({verdict.violation:.2e})"
        attempts.append(f"{stage}: {detail}")
        return None

    def record_primary(self, x: FloatArray) -> None:
        """Book a command verified outside :meth:`solve` as a primary-stage success.

        For a caller that solved and verified the primary stage itself (the controller's
        in-place DAQP path, :mod:`uvms_qp.hqp.inplace`): the next degraded step decays from
        ``x`` and the fallback count restarts, exactly as after a primary success here.
        """
        self.previous = x
        self.consecutive = 0
        self.stage_counts[PRIMARY] += 1

    # ---------------------------------------------------------------------------------- solve
    def solve(self, problem: Problem, start: float | None = None) -> SafeSolve:
        """Solve ``problem`` through the ladder (see the module docstring).

        Args:
            problem: A normalised problem (validated upstream: no bad input reaches a back-end).
            start: ``time.perf_counter()`` at which the step began (for the deadline); now if None.

        Returns:
            The command and how it was obtained (never None, ``x`` always finite and in the box).

        Raises:
            NoSolutionFound: strict mode, and no solver stage produced a verified solve.
        """
        clock = Deadline(self.deadline, start)
        for guard in self._guards:
            guard.end = clock.end
        tol = self.primary.hard_tol * problem.hard_scale
        attempts: list[str] = []
        self._last = None
        result = self._attempt(self.primary, problem, PRIMARY, tol, attempts)
        if result is not None:
            return self._solved(problem, result, PRIMARY, attempts, clock, 0)
        primary_result = self._last
        infeasible = (primary_result is not None
                      and primary_result.status == Status.HARD_INFEASIBLE
                      and not hard_feasible(problem))
        hold = self.consecutive >= self.max_fallbacks
        if not infeasible and not hold:
            stage_result = self._solver_stages(problem, tol, attempts, clock)
            if stage_result is not None:
                return stage_result
        elif infeasible:
            attempts.append("the hard box and hard rows admit no point (confirmed by an LP)")
        if self.strict:
            failed = self._last or primary_result
            raise NoSolutionFound(
                f"{self.name}: no verified solution ({'; '.join(attempts)})", result=failed)
        status = Status.HARD_INFEASIBLE if infeasible else Status.BACKEND_ERROR
        return self._degraded(problem, status, attempts, clock, hold, tol)

    def _solver_stages(self, problem: Problem, tol: float, attempts: list[str],
                       clock: Deadline) -> SafeSolve | None:
        if clock.expired():
            attempts.append("deadline passed: solver stages skipped")
            return None
        reset_warm_start(self.primary)
        result = self._attempt(self.primary, problem, COLD_RETRY, tol, attempts)
        if result is not None:
            return self._solved(problem, result, COLD_RETRY, attempts, clock, 0)
        alternate = self.alternate
        if alternate is not None:
            if clock.expired():
                attempts.append("deadline passed: solver stages skipped")
                return None
            result = self._attempt(alternate, problem, f"{ALTERNATE} {alternate.name}", tol,
                                   attempts)
            if result is not None:
                return self._solved(problem, result, ALTERNATE, attempts, clock, 0)
        if not self.relax or self.strict:
            return None
        p = len(problem.levels)
        for keep in range(p - 1, -1, -1):
            if clock.expired():
                attempts.append("deadline passed: solver stages skipped")
                return None
            sub = Problem(problem.n, problem.levels[:keep], problem.hard, problem.lower,
                          problem.upper, problem.W)
            result = self._attempt(self.primary, sub, f"{RELAXED} to {keep} levels", tol,
                                   attempts)
            if result is not None:
                full = evaluate(problem, result.x, f"{result.solver} ({keep} of {p} levels)",
                                Status.OPTIMAL, f"relaxed: lowest {p - keep} level(s) dropped",
                                level_tol=self.primary.level_tol, hard_tol=self.primary.hard_tol,
                                solve_time=result.solve_time, info=result.info)
                return self._solved(problem, full, RELAXED, attempts, clock, p - keep)
        return None

    def _solved(self, problem: Problem, result: HierarchyResult, stage: str,
                attempts: list[str], clock: Deadline, dropped: int) -> SafeSolve:
        sat = self._sat
        if sat is None or sat.x.shape != result.x.shape:  # pragma: no cover - set by _attempt
            sat = saturate(result.x, problem.lower, problem.upper)
        self.previous = sat.x
        self.consecutive = 0
        self.stage_counts[stage] += 1
        elapsed = clock.elapsed()
        return SafeSolve(sat.x, result, stage, tuple(attempts), sat.clipped,
                         sat.clipped > self.clip_flag_tol, elapsed > clock.budget, dropped,
                         elapsed)

    def _degraded(self, problem: Problem, status: Status, attempts: list[str], clock: Deadline,
                  hold: bool, tol: float) -> SafeSolve:
        stage = HOLD_ZERO if hold else ZERO
        x: FloatArray | None = None
        if not hold and self.previous is not None and self.previous.shape == (problem.n,):
            cand = saturate(self.decay * self.previous, problem.lower, problem.upper).x
            if verify_point(problem, cand, tol).ok:
                x, stage = cand, DECAYED
            else:
                attempts.append(f"{DECAYED}: violates the hard set now")
        if x is None:
            x = np.minimum(np.maximum(np.zeros(problem.n), problem.lower), problem.upper)
        sat = saturate(x, problem.lower, problem.upper, self.clip_flag_tol)
        message = f"{stage}: " + "; ".join(attempts)
        result = evaluate(problem, sat.x, self.name, status, message,
                          level_tol=self.primary.level_tol, hard_tol=self.primary.hard_tol,
                          solve_time=clock.elapsed())
        self.previous = sat.x
        self.consecutive += 1
        self.stage_counts[stage] += 1
        elapsed = clock.elapsed()
        return SafeSolve(sat.x, result, stage, tuple(attempts), sat.clipped, sat.flagged,
                         elapsed > clock.budget, 0, elapsed)


def fallback_summary(counts: Counter[str]) -> str:
    """One line ``stage: count`` per stage that occurred, in ladder order."""
    total = sum(counts.values()) or 1
    return ", ".join(f"{s}: {counts[s]} ({100.0 * counts[s] / total:.3g} %)"
                     for s in STAGES if counts.get(s))
