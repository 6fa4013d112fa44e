"""The fallback ladder: a finite command inside the hard box on every step, and the truth about it.

:class:`SafeSolver` is the one place where a failure is decided, for every scheme. Each call of
:meth:`SafeSolver.solve` climbs down the ladder until a stage produces an answer that the
measurement of :mod:`uvms_qp.hqp.measure` accepts (finite ``x`` of the right length, hard box and
hard rows within tolerance, the optimum proven by the certificate); anything a back-end does
instead (raise any exception, return None, a wrong length, NaN, a point outside the hard set, a
failure status) is a failed stage. Every stage tried is recorded with its verdict and its time
(:class:`StageRecord`, :attr:`SafeSolve.record`), so that one record answers "why this command".
The stage that produced the command is named in :attr:`SafeSolve.stage`:

=====================  =====================================================================
stage                  what it does
=====================  =====================================================================
``primary``            the configured back-end, warm-started as usual (the happy path)
``repair``             an answer of a solver stage that the certificate cannot prove, made
                       proven by exact level solves (:meth:`~uvms_qp.hqp.HierarchySolver.repaired`;
                       recorded, the command keeps the stage of the solve it repaired)
``damped``             near a singularity, the problem with damping rows solved again
                       (:mod:`uvms_qp.hqp.damping`; recorded, the command keeps its stage)
``cold_retry``         the same back-end after its warm start has been dropped
``alternate``          a back-end of another family (DAQP hierarchical <-> a qpsolvers cascade)
``relaxed``            the lowest levels dropped one by one (``relaxed_levels`` says how many)
``decayed_previous``   ``decay`` times the previous command, if it satisfies the hard set now
``zero``               zero clipped into the box (zero rates: the vehicle and arm hold still)
``hold_zero``          after ``max_fallbacks`` consecutive degraded steps: zero, until a solver
                       stage succeeds again (every solver stage is still tried on every step)
=====================  =====================================================================

An answer that is feasible but not proven optimal (status ``unproven``) is kept while the
``cold_retry`` and ``alternate`` stages look for a proven one; if none is found it is the
command (its stage and its ``unproven`` status say so), before any stage that drops levels or
degrades the command. An ill-posed level (the certificate's ``ill_posed``: no solver can do
better) and a scheme that takes its primary's unproven answers as they are
(``accept_unproven``, a closed form) stop at the primary.

Stages after ``alternate`` degrade the command; in strict mode they are not taken and
:class:`~uvms_qp.errors.NoSolutionFound` is raised instead (carrying the failed result). A hard set
that is empty (confirmed by an independent LP) skips every solver stage.

**Time.** A step has a deadline (:attr:`SafeSolver.deadline`, the control period in a
controller); every stage takes its time from what is left: a back-end stops at the end
(DAQP's ``time_limit``, a cascade starts no QP after it), and so do the certificate, the repair
and the damping screen. The ladder checks the clock once, before each stage after the first:
once the deadline has passed, the remaining solver stages are skipped and the step returns
the best command it has that is safe (an unproven answer inside the hard set, else the decayed
previous command or zero), flagged ``deadline_missed`` when it is late. The solve path's linear
algebra runs on one BLAS thread (:data:`uvms_qp.hqp.linalg.one_blas_thread`).

Whatever the stage, the returned command lies inside the box (exactly: a final clip,
:func:`uvms_qp.hqp.measure.clip_to_box`, whose amount is reported), and
:attr:`SafeSolve.result` is the measurement of that command against the problem it answers, so
per-level residuals and the status are truthful: ``optimal`` (proven) or ``unproven`` only for
solver stages, ``backend_error`` (or ``hard_infeasible``) for the decayed, zero and hold stages.
"""

from __future__ import annotations

import functools
import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, NamedTuple

from .._validation import FloatArray, as_scalar
from ..errors import InputError, NoSolutionFound
from ..hqp import HierarchyResult, HierarchySolver, Problem, Status
from ..hqp.damping import Damping
from ..hqp.hard_set import hard_feasible
from ..hqp.linalg import one_blas_thread, warm_up
from ..hqp.measure import clip_to_box, evaluate, placeholder
from ..hqp.registry import available_solvers, get_spec
from ..hqp.result import OK_STATUSES
from .deadline import backend_limits

PRIMARY = "primary"
REPAIR = "repair"
DAMPED = "damped"
COLD_RETRY = "cold_retry"
ALTERNATE = "alternate"
RELAXED = "relaxed"
DECAYED = "decayed_previous"
ZERO = "zero"
HOLD_ZERO = "hold_zero"

_OPTIMAL, _UNPROVEN = Status.OPTIMAL, Status.UNPROVEN
_VALUES = {status: status.value for status in Status}  # without the enum's property per step

#: Every stage that can produce the command, in ladder order.
STAGES: tuple[str, ...] = (PRIMARY, COLD_RETRY, ALTERNATE, RELAXED, DECAYED, ZERO, HOLD_ZERO)
#: Stages whose command is a verified solve of the problem (all levels, or the kept levels).
SOLVED_STAGES: frozenset[str] = frozenset((PRIMARY, COLD_RETRY, ALTERNATE, RELAXED))
#: Stages that did not solve the problem.
DEGRADED_STAGES: frozenset[str] = frozenset((DECAYED, ZERO, HOLD_ZERO))

#: Default clip amount above which a clip is flagged [m/s, rad/s]: after a verified solve a clip
#: is round-off (below the hard tolerance), so more means something upstream went wrong.
CLIP_FLAG_TOL = 1e-6

_CASCADE_PREFERENCE = ("cascade:quadprog", "cascade:proxqp", "cascade:piqp", "cascade:clarabel",
                       "cascade:daqp", "cascade:osqp", "cascade:highs")

#: ``damper(x, end) -> (damping, damped problem)``: the damping rows a scheme adds at the
#: answer ``x`` and the problem with them (None for both: no level needs damping; a damping of
#: None with a problem: the screen ran out of time). Handed to :meth:`SafeSolver.solve`.
Damper = Callable[[FloatArray, float], tuple[Damping | None, Problem | None]]


def default_alternate(solver: str, *, cascade_only: bool = False) -> str | None:
    """A back-end of another family for the fallback ladder, or None if none is installed.

    DAQP's hierarchical mode falls back to a qpsolvers cascade (quadprog first), a cascade or the
    closed form to DAQP's hierarchical mode; with ``cascade_only`` (problems whose weights DAQP's
    row normalisation would change, e.g. the weighted scheme) a cascade on another library.

    Args:
        solver: The primary solver name.
        cascade_only: Only cascades qualify.
    """
    installed = set(available_solvers())
    if solver != "daqp" and not cascade_only and "daqp" in installed:
        return "daqp"
    library = solver.split(":", 1)[-1]
    for name in _CASCADE_PREFERENCE:
        if name in installed and name != solver and name.split(":", 1)[1] != library:
            return name
    return None


class StageRecord(NamedTuple):
    """One stage a step tried (a named tuple: one is built on every step).

    Attributes:
        stage: The stage (:data:`STAGES`, ``repair``, ``damped``; ``relaxed to k levels`` and
            ``alternate <solver>`` name what they ran).
        verdict: What came of it: a status (``optimal``, ``unproven``, ``backend_error``...),
            ``raised <Exception>``, ``used`` (a degraded command), ``kept`` (an answer kept as
            it was) or ``skipped``.
        seconds: Wall time of the stage [s].
        note: Why, in words (the back-end's message, what was skipped and why).
        used: This stage's answer is the command (or the answer the command refines).
    """

    stage: str
    verdict: str
    seconds: float = 0.0
    note: str = ""
    used: bool = False

    def __str__(self) -> str:
        return f"{self.stage}: {self.verdict}" + (f" ({self.note})" if self.note else "")


@dataclass(eq=False, slots=True)
class SafeSolve:
    """One step of the safe solver.

    Attributes:
        x: The command, finite and inside the hard box, shape (n,) [m/s, rad/s].
        result: Measurement of ``x`` against the problem it answers (``problem``): truthful
            status and residuals.
        stage: The ladder stage that produced ``x`` (one of :data:`STAGES`).
        record: Every stage the step tried, in order, with its verdict and time.
        clipped: Amount the box clip removed from the answer [m/s, rad/s] (round-off after a
            verified solve; the saturation of a closed form).
        clip_flagged: ``clipped`` exceeded the flag threshold.
        deadline_missed: The step took longer than its deadline.
        relaxed_levels: Number of lowest levels dropped (``relaxed`` stage), else 0.
        elapsed: Wall time of the whole ladder [s].
        damping: The damping rows the answer was solved with (``damped``), or None.
        problem: The problem ``result`` measures ``x`` on (the damped one after damping).
    """

    x: FloatArray
    result: HierarchyResult
    stage: str
    record: tuple[StageRecord, ...] = ()
    clipped: float = 0.0
    clip_flagged: bool = False
    deadline_missed: bool = False
    relaxed_levels: int = 0
    elapsed: float = 0.0
    damping: Damping | None = None
    problem: Problem | None = None

    @property
    def attempts(self) -> tuple[str, ...]:
        """One line per stage whose answer was not used (``"<stage>: <verdict> (<why>)"``)."""
        return tuple([str(r) for r in self.record if not r.used])

    @property
    def solved(self) -> bool:
        """True when ``x`` comes from a verified solve (full or relaxed problem)."""
        return self.stage in SOLVED_STAGES

    @property
    def degraded(self) -> bool:
        """True when the ladder fell back beyond the primary back-end."""
        return self.stage != PRIMARY


class _Step:
    """What one call of :meth:`SafeSolver.solve` carries between its stages."""

    __slots__ = ("end", "failed", "problem", "record", "start", "unproven")

    def __init__(self, problem: Problem, start: float, end: float) -> None:
        self.problem, self.start, self.end = problem, start, end
        self.record: list[StageRecord] = []
        self.failed: HierarchyResult | None = None  # the latest result that was no answer
        self.unproven: tuple[HierarchyResult, str] | None = None  # the first unproven answer


class SafeSolver:
    """A hierarchy solver that measures every answer and falls back safely.

    Args:
        solver: Primary solver name (see :func:`uvms_qp.hqp.available_solvers`).
        weights: Diagonal metric W (n,) of the final regularisation, or None (problems carry
            their own metric; this one is for problems that do not set it).
        options: Options of the primary back-end (merged over the deadline's limits).
        alternate: Back-end of another family for the ``alternate`` stage: ``"auto"``
            (:func:`default_alternate`), a solver name, or None to skip the stage.
        deadline: Budget of one step [s], or None for no deadline.
        max_fallbacks: Consecutive degraded steps after which zero is held (instead of the
            decayed previous command) until a solver stage succeeds.
        decay: Factor on the previous command in the ``decayed_previous`` stage, ``0 <= decay < 1``.
        relax: Take the ``relaxed`` stage.
        strict: Raise :class:`~uvms_qp.errors.NoSolutionFound` instead of degrading.
        clip_flag_tol: Clip amount above which a clip is flagged [m/s, rad/s].
        saturate: Clip the primary's answers into the box before measuring them (a closed form
            that cannot enforce the box: its command is the saturated closed form).
        accept_unproven: The primary's ``unproven`` answers are the command as they are (a
            closed form, whose answer is what the scheme is); False: the repair and the next
            solver stages look for a proven answer first.
        clock: Wall clock [s] (``time.perf_counter``; a test may pass a fake one); also the
            clock of the solvers, the certificate and the repair.

    Attributes:
        primary: The primary :class:`~uvms_qp.hqp.HierarchySolver`.
        alternate: The alternate solver, or None.
        stage_counts: Steps per stage since construction.
        status_counts: Steps per status since construction.

    Raises:
        UnknownSolverError: unknown or uninstalled primary or alternate solver.
        InputError: a bad deadline, decay or max_fallbacks.
    """

    def __init__(self, solver: str = "daqp", weights: Any = None,
                 options: dict[str, Any] | None = None, *, alternate: str | None = "auto",
                 deadline: float | None = None, max_fallbacks: int = 3, decay: float = 0.5,
                 relax: bool = True, strict: bool = False,
                 clip_flag_tol: float = CLIP_FLAG_TOL, saturate: bool = False,
                 accept_unproven: bool = False,
                 clock: Callable[[], float] = time.perf_counter) -> None:
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
        self.saturate = bool(saturate)
        self.accept_unproven = bool(accept_unproven)
        self._budget = math.inf if self.deadline is None else self.deadline
        options = {} if options is None else options
        if not isinstance(options, dict):
            raise InputError(f"options: expected a dict, got {type(options).__name__}")
        self.primary = HierarchySolver(
            solver, weights, {**backend_limits(get_spec(solver).name, self.deadline), **options})
        self.primary.saturate = self.saturate
        self.name = self.primary.name
        if alternate == "auto":
            alternate = default_alternate(self.name)
        if alternate is not None:
            get_spec(alternate)  # raises UnknownSolverError early
            if alternate == self.name:
                alternate = None
        self.alternate: HierarchySolver | None = None if alternate is None else HierarchySolver(
            alternate, weights, backend_limits(alternate, self.deadline))
        self.clock = clock
        warm_up()
        self.previous: FloatArray | None = None
        self.consecutive = 0
        self.stage_counts: Counter[str] = Counter()
        self.status_counts: Counter[str] = Counter()
        self._relaxed: dict[int, tuple[Problem, Problem]] = {}

    @property
    def clock(self) -> Callable[[], float]:
        """The clock [s] of the deadline (also the solvers')."""
        return self._clock

    @clock.setter
    def clock(self, clock: Callable[[], float]) -> None:
        self._clock = clock
        for hs in (self.primary, self.alternate):
            if hs is not None:
                hs.clock = clock

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
        self.primary.reset()
        if self.alternate is not None:
            self.alternate.reset()

    # ---------------------------------------------------------------------------------- solve
    def solve(self, problem: Problem, start: float | None = None,
              damper: Damper | None = None) -> SafeSolve:
        """Solve ``problem`` through the ladder (see the module docstring).

        Args:
            problem: The problem (validated upstream: no bad input reaches a back-end).
            start: Clock value at which the step began (for the deadline); now if None.
            damper: The scheme's damping rows at an answer (the ``damped`` stage), or None.

        Returns:
            The command and how it was obtained (never None, ``x`` always finite and in the box).

        Raises:
            NoSolutionFound: strict mode, and no solver stage produced a verified solve.
        """
        if start is None:
            start = self._clock()
        step = _Step(problem, start, start + self._budget)
        if self.primary.single_threaded(problem):
            return self._ladder(step, damper)
        with one_blas_thread:
            return self._ladder(step, damper)

    def _ladder(self, step: _Step, damper: Damper | None) -> SafeSolve:
        """:meth:`solve` after its set-up (inside the BLAS thread limit or not).

        Without the limit when no product of the primary's solve can thread (a solver stage
        that factorises enters it itself).
        """
        found = self._solver_stages(step)
        if found is not None:
            result, stage, dropped = found
            out = self._damped(step, result, stage, damper)
            if isinstance(out, SafeSolve):
                return out
            return self._finish(step, result, stage, dropped)
        if self.strict:
            raise NoSolutionFound(
                f"{self.name}: no verified solution ({'; '.join(map(str, step.record))})",
                result=step.failed)
        infeasible = step.failed is not None and step.failed.status is Status.HARD_INFEASIBLE \
            and any(r.note == _EMPTY for r in step.record)
        return self._degraded(step, Status.HARD_INFEASIBLE if infeasible
                              else Status.BACKEND_ERROR)

    def solve_once(self, problem: Problem, start: float, damper: Damper | None = None
                   ) -> SafeSolve | None:
        """The primary's verified answer to ``problem`` (repaired and damped), or None.

        For the other solves of a step (the subsets of a blend): no other stage, no counts,
        nothing remembered; None once the step's deadline has passed or when the primary
        gives no proven answer.
        """
        step = _Step(problem, start, start + self._budget)
        if self.primary.single_threaded(problem):
            return self._once(step, damper)
        with one_blas_thread:
            return self._once(step, damper)

    def _once(self, step: _Step, damper: Damper | None) -> SafeSolve | None:
        """:meth:`solve_once` inside the limit, or without it (as :meth:`_ladder`)."""
        if self._clock() > step.end:
            return None
        result = self._solve(self.primary, step.problem, PRIMARY, step)
        if result is None or not result.ok:
            return None
        damped = self._damped(step, result, PRIMARY, damper, count=False, fallback=False)
        if damped is _UNANSWERED:
            return None
        if isinstance(damped, SafeSolve):
            return damped
        return self._finish(step, result, PRIMARY, 0, count=False)

    # --------------------------------------------------------------------------------- stages
    def _solver_stages(self, step: _Step) -> tuple[HierarchyResult, str, int] | None:
        """The solver stages in ladder order: ``(result, stage, levels dropped)`` or None.

        One deadline check, before every stage after the first; one exit.
        """
        problem = step.problem
        result = self._solve(self.primary, problem, PRIMARY, step)
        if result is not None and result.status in OK_STATUSES:  # (result.ok, without a call)
            return result, PRIMARY, 0
        kept = step.unproven
        if kept is not None and (self.accept_unproven or _ill_posed(kept[0])):
            step.record[-1] = _used(step.record[-1])
            return kept[0], kept[1], 0
        if step.failed is not None and step.failed.status is Status.HARD_INFEASIBLE \
                and not hard_feasible(problem):
            step.record.append(StageRecord(PRIMARY, "hard_infeasible", 0.0, _EMPTY))
            return None
        stages: list[tuple[str, Callable[[], tuple[HierarchyResult, str, int] | None]]] = [
            (COLD_RETRY, lambda: self._cold_retry(step))]
        if self.alternate is not None:
            stages.append((ALTERNATE, lambda: self._alternate(step)))
        stages.append(("unproven", lambda: self._kept(step)))
        if self.relax and not self.strict:
            stages.extend((f"{RELAXED} to {keep} levels",
                           functools.partial(self._relax, step, keep))
                          for keep in range(len(problem.sizes) - 1, -1, -1))
        found = None
        for name, stage in stages:
            # keeping the unproven answer costs no time: it is never skipped for the deadline
            if name != "unproven" and self._clock() > step.end:
                step.record.append(StageRecord(name, "skipped", 0.0,
                                               "deadline passed: solver stages skipped"))
                found = self._kept(step)
                break
            found = stage()
            if found is not None:
                break
        return found

    def _solve(self, solver: HierarchySolver, problem: Problem, stage: str, step: _Step
               ) -> HierarchyResult | None:
        """One back-end call and, for an answer it cannot prove, its repair (both recorded).

        Returns the result when it is an answer (proven, or unproven inside the hard set), else
        None; the first unproven answer of the step is kept in ``step.unproven``.
        """
        began = self._clock()
        try:
            result = solver.solve_problem(problem, step.end, repair=False)
        except Exception as exc:  # any back-end exception, ours or foreign, is a failed stage
            step.record.append(StageRecord(stage, f"raised {type(exc).__name__}",
                                           self._clock() - began, str(exc)))
            return None
        status = result.status
        if status is _OPTIMAL:
            step.record.append(StageRecord(stage, _VALUES[status], self._clock() - began,
                                           used=True))
            return result
        if status is _UNPROVEN and solver.repair and not self.accept_unproven:
            first = self._clock()
            step.record.append(StageRecord(stage, "unproven", first - began, result.message))
            if first > step.end:
                step.record.append(StageRecord(REPAIR, "skipped", 0.0, "deadline passed"))
            else:
                result = solver.repaired(problem, result, step.end)
                status = result.status
                step.record.append(StageRecord(REPAIR, _VALUES[status], self._clock() - first,
                                               result.message, used=result.ok))
                if result.ok:
                    return result
        else:
            step.record.append(StageRecord(stage, _VALUES[status], self._clock() - began,
                                           result.message))
        if status is _UNPROVEN:
            if step.unproven is None:
                step.unproven = (result, stage.split(" ", 1)[0])
            return result
        step.failed = result
        return None

    def _cold_retry(self, step: _Step) -> tuple[HierarchyResult, str, int] | None:
        self.primary.reset()
        result = self._solve(self.primary, step.problem, COLD_RETRY, step)
        return (result, COLD_RETRY, 0) if result is not None and result.ok else None

    def _alternate(self, step: _Step) -> tuple[HierarchyResult, str, int] | None:
        alternate = self.alternate
        assert alternate is not None
        result = self._solve(alternate, step.problem, f"{ALTERNATE} {alternate.name}", step)
        return (result, ALTERNATE, 0) if result is not None and result.ok else None

    def _kept(self, step: _Step) -> tuple[HierarchyResult, str, int] | None:
        """The first unproven answer of the step (feasible: better than dropping levels)."""
        if step.unproven is None:
            return None
        result, stage = step.unproven
        step.record.append(StageRecord(stage, "kept", 0.0, "the unproven answer, inside the "
                                       "hard set, is the command", used=True))
        return result, stage, 0

    def _relax(self, step: _Step, keep: int) -> tuple[HierarchyResult, str, int] | None:
        problem = step.problem
        p = len(problem.sizes)
        owner, sub = self._relaxed.get(keep, (None, None))
        if owner is not problem or sub is None:
            sub = problem.relaxed(keep)
            self._relaxed[keep] = (problem, sub)
        result = self._solve(self.primary, sub, f"{RELAXED} to {keep} levels", step)
        if result is None or not result.ok:
            return None
        full = evaluate(problem, result.x, Status.OPTIMAL,
                        f"{result.solver} ({keep} of {p} levels)",
                        f"relaxed: lowest {p - keep} level(s) dropped", result.info,
                        level_tol=self.primary.level_tol, hard_tol=self.primary.hard_tol,
                        solve_time=result.solve_time, certify=self.primary.certify)
        return full, RELAXED, p - keep

    def _damped(self, step: _Step, result: HierarchyResult, stage: str,
                damper: Damper | None, count: bool = True, fallback: bool = True
                ) -> SafeSolve | object | None:
        """The ``damped`` stage: the answer solved again with the scheme's damping rows.

        None when no level needs damping, or when the damped problem gets no proven answer
        (the undamped answer is then the command, and the record says why). Without
        ``fallback`` (the other solves of a step) only the primary answers the damped problem,
        and an unanswered one gives :data:`_UNANSWERED`.
        """
        if damper is None or stage not in SOLVED_STAGES:
            return None
        began = self._clock()
        if began > step.end:
            step.record.append(StageRecord(DAMPED, "skipped", 0.0, _LATE_DAMPING))
            return None
        damping, damped = damper(result.x, step.end)
        if damped is None:
            return None  # no level needs damping
        if damping is None:
            step.record.append(StageRecord(DAMPED, "skipped", self._clock() - began,
                                           _LATE_DAMPING))
            return None
        again = self._verified(self.primary, damped, step)
        if again is None and not fallback:
            return _UNANSWERED
        if again is None and self.alternate is not None and self._clock() <= step.end:
            # the primary failed on the damped problem (its deadline, an error): the alternate
            # back-end answers it; the undamped answer may chatter
            step.record.append(StageRecord(
                DAMPED, "unanswered", 0.0, f"{PRIMARY}: no verified answer to the damped problem"))
            again = self._verified(self.alternate, damped, step)
            if again is not None:
                stage = ALTERNATE
        if again is None:
            note = (_LATE_DAMPING if self._clock() > step.end
                    else "damping: no back-end answered the damped problem") + (
                "; the undamped answer is kept")
            step.record.append(StageRecord(DAMPED, "unanswered", self._clock() - began, note))
            return None
        step.record.append(StageRecord(DAMPED, _VALUES[again.status], self._clock() - began,
                                       "levels " + ", ".join(map(str, damping.damped_levels)),
                                       used=True))
        return self._finish(step, again, stage, 0, count=count, damping=damping,
                            problem=damped)

    def _verified(self, solver: HierarchySolver, problem: Problem, step: _Step
                  ) -> HierarchyResult | None:
        """One proven answer of ``solver`` (repaired inside), or None; never raises."""
        try:
            result = solver.solve_problem(problem, step.end)
        except Exception:  # any back-end exception, ours or foreign: the stage fails
            return None
        if not result.ok or result.hard_violation > solver.hard_tol * max(
                1.0, problem.hard_scale):
            return None
        return result

    # ---------------------------------------------------------------------------- the result
    def _finish(self, step: _Step, result: HierarchyResult, stage: str, dropped: int, *,
                count: bool = True, damping: Damping | None = None,
                problem: Problem | None = None) -> SafeSolve:
        """The one place a step's outcome is built: clipped into the box, counted, timed."""
        problem = step.problem if problem is None else problem
        x = result.x
        clipped = float(result.info.get("clipped", 0.0))  # type: ignore[arg-type]
        if result.hard_violation:  # within tolerance, maybe outside the box: clip, measure again
            sat, extra = clip_to_box(x, problem.lower, problem.upper)
            if extra:
                clipped = max(clipped, extra)
                result = evaluate(problem, sat, Status.OPTIMAL, result.solver, result.message,
                                  result.info, level_tol=self.primary.level_tol,
                                  hard_tol=self.primary.hard_tol, solve_time=result.solve_time,
                                  certify=self.primary.certify)
                x = sat
        if count:
            self.previous = x
            self.consecutive = 0 if stage not in DEGRADED_STAGES else self.consecutive + 1
            self.stage_counts[stage] += 1
            self.status_counts[_VALUES[result.status]] += 1
        elapsed = self._clock() - step.start
        return SafeSolve(x, result, stage, tuple(step.record), clipped,
                         clipped > self.clip_flag_tol, elapsed > self._budget, dropped, elapsed,
                         damping, problem)

    def _degraded(self, step: _Step, status: Status) -> SafeSolve:
        problem = step.problem
        hold = self.consecutive >= self.max_fallbacks
        tol = self.primary.hard_tol * problem.hard_scale
        result = None
        began = self._clock()
        if not hold and self.previous is not None and self.previous.shape == (problem.n,):
            cand = clip_to_box(self.decay * self.previous, problem.lower, problem.upper)[0]
            result = self._measure(step, cand, status, DECAYED)
            if result.hard_violation > tol:
                step.record.append(StageRecord(DECAYED, "violates the hard set now",
                                               self._clock() - began))
                result = None
        stage = DECAYED if result is not None else HOLD_ZERO if hold else ZERO
        if result is None:
            result = self._measure(step, placeholder(problem), status, stage)
        step.record.append(StageRecord(stage, "used", self._clock() - began, used=True))
        return self._finish(step, result, stage, 0)

    def _measure(self, step: _Step, x: FloatArray, status: Status, stage: str
                 ) -> HierarchyResult:
        notes = "; ".join(str(r) for r in step.record if not r.used)
        return evaluate(step.problem, x, status, self.name, f"{stage}: " + notes,
                        level_tol=self.primary.level_tol, hard_tol=self.primary.hard_tol,
                        solve_time=self._clock() - step.start)


_EMPTY = "the hard box and hard rows admit no point (confirmed by an LP)"
_LATE_DAMPING = "damping: the step's deadline passed before the damped problem was solved"
_UNANSWERED = object()  # the damped problem of another solve of a step got no answer


def _used(record: StageRecord) -> StageRecord:
    return StageRecord(record.stage, record.verdict, record.seconds, record.note, True)


def fallback_summary(counts: Counter[str]) -> str:
    """One line ``stage: count`` per stage that occurred, in ladder order."""
    total = sum(counts.values()) or 1
    return ", ".join(f"{s}: {counts[s]} ({100.0 * counts[s] / total:.3g} %)"
                     for s in STAGES if counts.get(s))


def _ill_posed(result: HierarchyResult) -> bool:
    """True when the result's first unproven level is ill-posed (no solver can do better)."""
    cert = result.certificate
    return cert is not None and cert.ill_posed
