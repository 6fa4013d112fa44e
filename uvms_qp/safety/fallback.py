"""The fallback ladder: a finite command inside the hard box on every step, and the truth about it.

:class:`SafeSolver` runs every solve of a control step, whatever the scheme. Each call of
:meth:`SafeSolver.solve` climbs down the ladder until a stage produces an answer that the
measurement of :mod:`uvms_qp.hqp.measure` accepts (finite ``x`` of the right length, hard box and
hard rows within tolerance, status ``optimal`` or ``level_infeasible``); anything a back-end does
instead (raise any exception, return None, a wrong length, NaN, a point outside the hard set, a
failure status) is a failed stage, recorded in :attr:`SafeSolve.attempts`. The stage that ran is
named in :attr:`SafeSolve.stage`:

=====================  =====================================================================
stage                  what it does
=====================  =====================================================================
``primary``            the configured back-end, warm-started as usual (the happy path)
``cold_retry``         the same back-end after its warm start has been dropped
``alternate``          a back-end of another family (DAQP hierarchical <-> a qpsolvers cascade)
``relaxed``            the lowest levels dropped one by one (``relaxed_levels`` says how many)
``decayed_previous``   ``decay`` times the previous command, if it satisfies the hard set now
``zero``               zero clipped into the box (zero rates: the vehicle and arm hold still)
``hold_zero``          after ``max_fallbacks`` consecutive degraded steps: zero, until a solver
                       stage succeeds again (every solver stage is still tried on every step)
=====================  =====================================================================

An answer that is feasible but not proven optimal (status ``unproven``: the optimality
certificate failed and the solver's repair could not fix it) is kept while the ``cold_retry`` and
``alternate`` stages look for a proven one; if none is found it is the command (its stage and
its ``unproven`` status say so), before any stage that drops levels or degrades the command. An
ill-posed level (the certificate's ``ill_posed``: no solver can do better) and a scheme that
takes its primary's unproven answers as they are (``accept_unproven``, a closed form) stop at
the primary.

Stages after ``alternate`` degrade the command; in strict mode they are not taken and
:class:`~uvms_qp.errors.NoSolutionFound` is raised instead (carrying the failed result). A hard set
that is empty (confirmed by an independent LP) skips every solver stage. Once the step's deadline
has passed (:mod:`uvms_qp.safety.deadline`) the remaining solver stages are skipped as well.
Whatever the stage, the returned command lies inside the box (exactly: a final clip,
:func:`uvms_qp.hqp.measure.clip_to_box`, whose amount is reported), and
:attr:`SafeSolve.result` is the measurement of that command against the *full* problem, so
per-level residuals and the status are truthful: ``optimal`` / ``level_infeasible`` (proven) or
``unproven`` only for solver stages, ``backend_error`` (or ``hard_infeasible``) for the decayed,
zero and hold stages.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .._validation import FloatArray, as_scalar
from ..errors import InputError, NoSolutionFound
from ..hqp import HierarchyResult, HierarchySolver, Problem, Status
from ..hqp.hard_set import hard_feasible
from ..hqp.measure import clip_to_box, evaluate, placeholder
from ..hqp.registry import available_solvers, get_spec
from .deadline import CascadeGuard, backend_limits, guard_cascade

PRIMARY = "primary"
COLD_RETRY = "cold_retry"
ALTERNATE = "alternate"
RELAXED = "relaxed"
DECAYED = "decayed_previous"
ZERO = "zero"
HOLD_ZERO = "hold_zero"

_OPTIMAL, _LEVEL_INFEASIBLE, _UNPROVEN = Status.OPTIMAL, Status.LEVEL_INFEASIBLE, Status.UNPROVEN
_VALUES = {status: status.value for status in Status}  # without the enum's property per step

#: Default cap of one solve of a solver stage [s] (no cascade solve past it at n <= 30).
TIME_CAP = 0.05

#: Every stage name, in ladder order.
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


@dataclass(eq=False, slots=True)
class SafeSolve:
    """One step of the safe solver.

    Attributes:
        x: The command, finite and inside the hard box, shape (n,) [m/s, rad/s].
        result: Measurement of ``x`` against the full problem (truthful status and residuals).
        stage: The ladder stage that produced ``x`` (one of :data:`STAGES`).
        attempts: One line per failed stage: ``"<stage>: <reason>"``.
        clipped: Amount the box clip removed from the answer [m/s, rad/s] (round-off after a
            verified solve; the saturation of a closed form).
        clip_flagged: ``clipped`` exceeded the flag threshold.
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
            closed form, whose answer is what the scheme is); False: the next solver stages
            look for a proven answer first.
        time_cap: Cap of each solve of a solver stage [s] on ``clock`` (:data:`TIME_CAP`; an
            ``options["time_cap"]`` overrides it for the primary): a cascade starts no QP past
            it and reports ``backend_error``, a repair gives up, and the ladder goes on.
        clock: Wall clock [s] (``time.perf_counter``; a test may pass a fake one); also the
            clock of the solvers' time caps.

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
                 accept_unproven: bool = False, time_cap: float = TIME_CAP,
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
        self._budget = float("inf") if self.deadline is None else self.deadline
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
        self.time_cap = as_scalar(time_cap, "time_cap", positive=True, allow_inf=True)
        if "time_cap" not in options:
            self.primary.time_cap = self.time_cap
        if self.alternate is not None:
            self.alternate.time_cap = self.time_cap
        self._guards: list[CascadeGuard] = []
        if self.deadline is not None:
            for hs in (self.primary, self.alternate):
                guard = None if hs is None else guard_cascade(hs.backend, clock)
                if guard is not None:
                    self._guards.append(guard)
        self.clock = clock  # the deadline's, the guards' and the solvers' time caps'
        self.previous: FloatArray | None = None
        self.consecutive = 0
        self.stage_counts: Counter[str] = Counter()
        self.status_counts: Counter[str] = Counter()
        self._relaxed: dict[int, tuple[Problem, Problem]] = {}
        self._failed: HierarchyResult | None = None
        self._unproven: tuple[HierarchyResult, str] | None = None  # first unproven answer

    @property
    def clock(self) -> Callable[[], float]:
        """The clock [s] of the deadline (also the cascades' guards' clock)."""
        return self._clock

    @clock.setter
    def clock(self, clock: Callable[[], float]) -> None:
        self._clock = clock
        for hs in (self.primary, self.alternate):
            if hs is not None:
                hs.clock = clock
        for guard in self._guards:
            guard.clock = clock

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
    def solve(self, problem: Problem, start: float | None = None) -> SafeSolve:
        """Solve ``problem`` through the ladder (see the module docstring).

        Args:
            problem: The problem (validated upstream: no bad input reaches a back-end).
            start: Clock value at which the step began (for the deadline); now if None.

        Returns:
            The command and how it was obtained (never None, ``x`` always finite and in the box).

        Raises:
            NoSolutionFound: strict mode, and no solver stage produced a verified solve.
        """
        if start is None:
            start = self._clock()
        end = start + self._budget
        for guard in self._guards:
            guard.end = end
        attempts: list[str] = []
        self._failed = self._unproven = None
        result = self._attempt(self.primary, problem, PRIMARY, attempts)
        if result is not None:
            if result.hard_violation or self.saturate:
                return self._solved(problem, result, PRIMARY, attempts, start, 0)
            # the happy path: a verified answer inside the box, nothing to clip
            self.previous = result.x
            self.consecutive = 0
            self.stage_counts[PRIMARY] += 1
            self.status_counts[_VALUES[result.status]] += 1
            elapsed = self._clock() - start
            return SafeSolve(result.x, result, PRIMARY, (), 0.0, False, elapsed > self._budget,
                             0, elapsed)
        kept = self._unproven
        if kept is not None and (self.accept_unproven or _ill_posed(kept[0])):
            return self._solved(problem, kept[0], PRIMARY, attempts, start, 0)
        failed = self._failed
        infeasible = (failed is not None and failed.status == Status.HARD_INFEASIBLE
                      and not hard_feasible(problem))
        if infeasible:
            attempts.append("the hard box and hard rows admit no point (confirmed by an LP)")
        else:
            solved = self._solver_stages(problem, attempts, start, end)
            if solved is not None:
                return solved
        if self.strict:
            raise NoSolutionFound(
                f"{self.name}: no verified solution ({'; '.join(attempts)})",
                result=self._failed or failed)
        status = Status.HARD_INFEASIBLE if infeasible else Status.BACKEND_ERROR
        return self._degraded(problem, status, attempts, start)

    def _attempt(self, solver: HierarchySolver, problem: Problem, stage: str,
                 attempts: list[str]) -> HierarchyResult | None:
        """One back-end call; its result if verified, else None with the reason recorded."""
        try:
            result = solver.solve_problem(problem)
        except Exception as exc:  # any back-end exception, ours or foreign, is a failed stage
            attempts.append(f"{stage}: raised {type(exc).__name__}: {exc}")
            return None
        status = result.status
        if status is _OPTIMAL or status is _LEVEL_INFEASIBLE:
            return result
        if status is _UNPROVEN and self._unproven is None:
            self._unproven = (result, stage.split(" ", 1)[0])
        self._failed = result
        attempts.append(f"{stage}: {result.status.value}"
                        + (f" ({result.message})" if result.message else ""))
        return None

    def _solver_stages(self, problem: Problem, attempts: list[str], start: float,
                       end: float) -> SafeSolve | None:
        clock = self._clock
        if clock() > end:
            attempts.append("deadline passed: solver stages skipped")
            return self._kept_unproven(problem, attempts, start)
        self.primary.reset()
        result = self._attempt(self.primary, problem, COLD_RETRY, attempts)
        if result is not None:
            return self._solved(problem, result, COLD_RETRY, attempts, start, 0)
        alternate = self.alternate
        if alternate is not None:
            if clock() > end:
                attempts.append("deadline passed: solver stages skipped")
                return self._kept_unproven(problem, attempts, start)
            result = self._attempt(alternate, problem, f"{ALTERNATE} {alternate.name}", attempts)
            if result is not None:
                return self._solved(problem, result, ALTERNATE, attempts, start, 0)
        if self._unproven is not None:  # feasible, not proven: better than dropping levels
            kept, stage = self._unproven
            return self._solved(problem, kept, stage, attempts, start, 0)
        if not self.relax or self.strict:
            return None
        p = len(problem.sizes)
        for keep in range(p - 1, -1, -1):
            if clock() > end:
                attempts.append("deadline passed: solver stages skipped")
                return None
            owner, sub = self._relaxed.get(keep, (None, None))
            if owner is not problem or sub is None:
                sub = problem.relaxed(keep)
                self._relaxed[keep] = (problem, sub)
            result = self._attempt(self.primary, sub, f"{RELAXED} to {keep} levels", attempts)
            if result is not None:
                full = evaluate(problem, result.x, Status.OPTIMAL,
                                f"{result.solver} ({keep} of {p} levels)",
                                f"relaxed: lowest {p - keep} level(s) dropped", result.info,
                                level_tol=self.primary.level_tol, hard_tol=self.primary.hard_tol,
                                solve_time=result.solve_time, certify=self.primary.certify)
                return self._solved(problem, full, RELAXED, attempts, start, p - keep)
        return None

    def _kept_unproven(self, problem: Problem, attempts: list[str], start: float
                       ) -> SafeSolve | None:
        """The first unproven answer of this step as the command (None when there is none)."""
        if self._unproven is None:
            return None
        kept, stage = self._unproven
        return self._solved(problem, kept, stage, attempts, start, 0)

    def _solved(self, problem: Problem, result: HierarchyResult, stage: str,
                attempts: list[str], start: float, dropped: int) -> SafeSolve:
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
        self.previous = x
        self.consecutive = 0
        self.stage_counts[stage] += 1
        self.status_counts[_VALUES[result.status]] += 1
        elapsed = self._clock() - start
        return SafeSolve(x, result, stage, tuple(attempts), clipped,
                         clipped > self.clip_flag_tol, elapsed > self._budget, dropped, elapsed)

    def _degraded(self, problem: Problem, status: Status, attempts: list[str],
                  start: float) -> SafeSolve:
        hold = self.consecutive >= self.max_fallbacks
        tol = self.primary.hard_tol * problem.hard_scale
        result = None
        if not hold and self.previous is not None and self.previous.shape == (problem.n,):
            cand = clip_to_box(self.decay * self.previous, problem.lower, problem.upper)[0]
            result = self._measure(problem, cand, status, DECAYED, attempts, start)
            if result.hard_violation > tol:
                attempts.append(f"{DECAYED}: violates the hard set now")
                result = None
        stage = DECAYED if result is not None else HOLD_ZERO if hold else ZERO
        if result is None:
            result = self._measure(problem, placeholder(problem), status, stage, attempts, start)
        self.previous = result.x
        self.consecutive += 1
        self.stage_counts[stage] += 1
        self.status_counts[_VALUES[result.status]] += 1
        elapsed = self._clock() - start
        return SafeSolve(result.x, result, stage, tuple(attempts), 0.0, False,
                         elapsed > self._budget, 0, elapsed)

    def _measure(self, problem: Problem, x: FloatArray, status: Status, stage: str,
                 attempts: list[str], start: float) -> HierarchyResult:
        return evaluate(problem, x, status, self.name, f"{stage}: " + "; ".join(attempts),
                        level_tol=self.primary.level_tol, hard_tol=self.primary.hard_tol,
                        solve_time=self._clock() - start)


def fallback_summary(counts: Counter[str]) -> str:
    """One line ``stage: count`` per stage that occurred, in ladder order."""
    total = sum(counts.values()) or 1
    return ", ".join(f"{s}: {counts[s]} ({100.0 * counts[s] / total:.3g} %)"
                     for s in STAGES if counts.get(s))


def _ill_posed(result: HierarchyResult) -> bool:
    """True when the result's first unproven level is ill-posed (no solver can do better)."""
    cert = result.certificate
    return cert is not None and cert.ill_posed
