"""Schemes: ways to turn a state into a command, behind one protocol.

The controller's three schemes solve the assembled stack (:mod:`.assembler`) through the same
fallback ladder (:class:`~uvms_qp.safety.SafeSolver`), so every step of every scheme gets the same
guard and post-check (shape, finiteness, hard rows, deadline):

* :class:`HqpScheme` (``"hqp"``): the lexicographic QP (levels are strict priorities; the hard
  box and hard rows hold at every level), with any back-end of
  :func:`uvms_qp.hqp.available_solvers`;
* :class:`WeightedScheme` (``"weighted"``): one weighted QP, priorities turned into weights
  (level ``k`` of ``p`` gets its squared violations multiplied by
  ``priority_ratio ** (p - 1 - k)``), same hard bounds: the usual "soft priorities" of weighted
  differential IK, for comparison. ``solver="daqp"`` runs as the plain QP ``"cascade:daqp"`` (in
  DAQP's hierarchical mode the priority weights would become soft weights spanning
  ``priority_ratio ** (p - 1)``, far more than its soft-row regularisation resolves accurately);
  very large ratios make the QP ill-conditioned (1e2-1e4 work well);
* :class:`NullspaceScheme` (``"nullspace"``): the closed-form recursive null-space scheme
  (Soylu et al. (2007), Eq. (10), extended to p levels, in the metric W of Eq. (17)),
  saturated into the hard box (``StepResult.saturated`` says when that changed the command);
  its status judges the saturated command against the levels (``unproven`` when the
  optimality certificate cannot prove it the optimum of the boxed problem: the command stays
  the closed form's), and hard rows it breaks send the step down the ladder. It has no notion
  of inequality rows: a stack with inequality tasks is refused at construction.

The papers' schemes (:mod:`uvms_qp.schemes`) implement the same :class:`Scheme` protocol.
"""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from .._validation import as_time
from ..errors import InputError, NoSolutionFound
from ..hqp import Problem, Status
from ..hqp.damping import Damping, level_damping
from ..hqp.measure import clip_to_box, evaluate
from ..hqp.registry import get_spec
from ..safety import DEGRADED_STAGES, SafeSolve, SafeSolver, default_alternate
from ..safety.fallback import ALTERNATE, PRIMARY
from .assembler import StackAssembler
from .result import StepResult

if TYPE_CHECKING:  # pragma: no cover
    from ..model import State


class Scheme(Protocol):
    """A way to turn a state into a command.

    Attributes:
        name: Label of the scheme in results and tables.
        solver_name: The solver it runs (``"closed-form"`` when it solves no problem).
    """

    name: str
    solver_name: str

    def step(self, state: State, t: float) -> StepResult:
        """The command for ``state`` at time ``t`` [s]."""

    def reset(self) -> None:
        """Forget the memory kept between steps."""


def require_equality_tasks(assembler: StackAssembler, who: str) -> None:
    """Refuse a stack with inequality tasks for a solver that handles equalities only.

    Raises:
        InputError: naming the inequality tasks.
    """
    ineq = [t.name for t in assembler.tasks if not t.equality_rows]
    if ineq:
        raise InputError(f"{who} handles equality rows only, but the stack has inequality "
                         f"tasks: {', '.join(ineq)}; use solver='daqp' or a cascade")


class _StackScheme:
    """A scheme that solves the assembled stack through the fallback ladder.

    Every step: the tasks write their rows (:meth:`StackAssembler.fill`); tasks out of the stack
    (activation 0) leave the problem; the problem goes through the ladder; where a level is near
    a singularity in the freedom the levels above leave, its damping rows are added and the
    problem is solved again (:mod:`uvms_qp.hqp.damping`); while tasks ramp in or out
    (0 < activation < 1) the optima with and without them are blended; the command is handed to
    the constraints and kept for the reversal figure.
    """

    name: ClassVar[str] = ""

    def __init__(self, assembler: StackAssembler, safe: SafeSolver, problem: Problem) -> None:
        self.assembler = assembler
        self.safe = safe
        self.problem = problem
        self.solver_name = safe.name
        self.status_counts: Counter[str] = Counter()

    def step(self, state: State, t: float = 0.0) -> StepResult:
        """Fill the problem, solve it through the ladder, measure the command.

        Raises:
            InputError: a task whose target was never set, a state of another model, something
                other than a State (e.g. a configuration array), or a time that is not a real
                number.
            NonFiniteError: a task produced NaN/inf rows (the message names the task), or the
                time is NaN or inf.
            BoundsError: the hard box is empty (the message names the constraints).
            NoSolutionFound: strict mode, and no back-end returned a verified solution.
        """
        t = as_time(t)
        clock = self.safe.clock
        start = clock()
        assembler = self.assembler
        assembler.fill(state, t)
        self._prepare()
        excluded, ramping = assembler.activation()
        try:
            main, solved, damping = self._solve(excluded, start)
        except NoSolutionFound:
            assembler.check_box(state)
            raise
        out: SafeSolve = main  # type: ignore[assignment]  # the ladder always answers
        if out.stage in DEGRADED_STAGES:  # e.g. an empty box, which no back-end can answer
            assembler.check_box(state)
        status = out.result.status if damping is None else Status.DAMPED
        if ramping and out.solved:
            blend = self._blend(excluded, ramping, out, solved, start)
            if blend is not None:  # (a blend with an unproven answer is not proven either)
                out, status = blend, (Status.BLENDED if out.result.ok else Status.UNPROVEN)
        self.safe.previous = out.x
        self.status_counts[status.value] += 1
        step_time = clock() - start
        deadline = self.safe.deadline
        if deadline is not None and step_time > deadline and not out.deadline_missed:
            out = dataclasses.replace(out, deadline_missed=True)  # late in an optional solve
        return assembler.step_result(out, t, step_time, self.name, self.solver_name,
                                     status, solved, damping, excluded, ramping)

    def _solve(self, excluded: tuple[int, ...], start: float, ladder: bool = True
               ) -> tuple[SafeSolve | None, Problem, Damping | None]:
        """The answer to the stack without ``excluded``, damped where needed.

        The ladder answers the main problem (``ladder``); the other solves of a step (the damped
        problem, the subsets of a blend) are one verified call of the primary back-end each, and
        are skipped once the step's deadline has passed.

        Returns:
            ``(outcome, problem solved, damping or None)``; the outcome is None when a solve
            without the ladder fails.
        """
        assembler = self.assembler
        problem = (assembler.problem if not excluded
                   else assembler.derived(excluded, assembler.no_rows))
        if ladder:
            out: SafeSolve | None = self.safe.solve(self._scheme_problem(problem), start)
        else:
            out = self._verified(problem, None)
        thresholds = assembler.damping
        if out is None or thresholds is None or not out.solved or self._late(start):
            return out, problem, None
        damping = level_damping(problem, out.x, thresholds, assembler.dt)
        if not damping.acted:
            return out, problem, None
        damped = assembler.derived(excluded, damping.rows)
        again = self._verified(damped, out)
        if (again is None and ladder and self.safe.alternate is not None
                and not self._late(start)):
            # the primary failed on the damped problem (its time cap, an error): the alternate
            # back-end answers it, as the ladder would; the undamped answer may chatter
            again = self._verified(damped, out, ALTERNATE)
        if again is None:
            if not ladder:
                return None, problem, None
            # the damped problem unanswered: the undamped answer, said so (and why)
            note = ("damping: the step's deadline passed before the damped problem was solved"
                    if self._late(start) else
                    "damping: no back-end answered the damped problem") + (
                "; the undamped answer is kept")
            return dataclasses.replace(out, attempts=(*out.attempts, note)), problem, None
        return again, damped, damping

    def _late(self, start: float) -> bool:
        """The step's deadline has passed (no more optional solves)."""
        deadline = self.safe.deadline
        return deadline is not None and self.safe.clock() - start > deadline

    def _verified(self, problem: Problem, main: SafeSolve | None, stage: str = PRIMARY
                  ) -> SafeSolve | None:
        """One verified solve by the primary back-end (no ladder), clipped into the box.

        None when the back-end raises or does not return a verified answer (``optimal`` or
        ``level_infeasible`` within the hard tolerance); the stage and the ladder's report are
        those of ``main`` (the primary's, without one). With ``stage = ALTERNATE`` the
        alternate back-end solves, the stage is ``alternate`` and the report says that the
        primary failed on this problem.
        """
        solver = self.safe.primary if stage == PRIMARY else self.safe.alternate
        assert solver is not None
        try:
            result = solver.solve_problem(self._scheme_problem(problem))
        except Exception:  # any back-end exception, ours or foreign: the optional solve fails
            return None
        if not result.ok or result.hard_violation > solver.hard_tol * max(
                1.0, problem.hard_scale):
            return None
        x, clipped = clip_to_box(result.x, problem.lower, problem.upper)
        clipped = max(clipped, float(result.info.get("clipped", 0.0)))  # type: ignore[arg-type]
        flagged = clipped > self.safe.clip_flag_tol
        if main is None:
            return SafeSolve(x, result, stage, (), clipped, flagged)
        attempts = main.attempts
        if stage != PRIMARY:
            attempts = (*attempts, f"{PRIMARY}: no verified answer to the damped problem")
        return SafeSolve(x, result, main.stage if stage == PRIMARY else stage, attempts,
                         clipped, flagged, main.deadline_missed, main.relaxed_levels,
                         main.elapsed)

    def _blend(self, excluded: tuple[int, ...], ramping: tuple[int, ...], main: SafeSolve,
               solved: Problem, start: float) -> SafeSolve | None:
        """The blend of the optima with and without the ramping tasks, or None.

        ``sum_S prod_i a_i^[i in S] (1 - a_i)^[i not in S] x(S)`` over the subsets ``S`` of the
        ramping tasks (the continuous activation of Mansard, Khatib and Kheddar 2009, for scalar
        activations); ``x`` of the full set is ``main``. None when a solve fails.
        """
        tasks, slots = self.assembler.tasks, self.assembler.slots
        a = [slots[i].activation for i in ramping]
        x = np.zeros_like(main.x)
        for mask in range(1 << len(ramping)):
            weight = math.prod(a[j] if mask >> j & 1 else 1.0 - a[j] for j in range(len(a)))
            if mask == (1 << len(ramping)) - 1:
                x += weight * main.x
                continue
            out = tuple(sorted(excluded + tuple(i for j, i in enumerate(ramping)
                                                 if not mask >> j & 1)))
            if self._late(start):
                return None
            other, _, _ = self._solve(out, start, ladder=False)
            if other is None:
                return None
            x += weight * other.x
        problem = self._scheme_problem(solved)
        x, _ = clip_to_box(x, problem.lower, problem.upper)  # round-off only: the box is convex
        primary = self.safe.primary
        active = ", ".join(f"{tasks[i].name} {slots[i].activation:.3g}" for i in ramping)
        result = evaluate(problem, x, Status.BLENDED, main.result.solver,
                          f"blended: activation {active}", level_tol=primary.level_tol,
                          hard_tol=primary.hard_tol, solve_time=main.result.solve_time)
        return SafeSolve(x, result, main.stage, main.attempts, main.clipped, main.clip_flagged,
                         main.deadline_missed, main.relaxed_levels, main.elapsed)

    def _scheme_problem(self, problem: Problem) -> Problem:
        """The problem this scheme hands to the ladder for the stack's ``problem``."""
        return problem

    def _prepare(self) -> None:
        """Per-tick work of the scheme after the stack is written (none by default)."""

    def reset(self) -> None:
        """Reset every task's and constraint's run-time memory and the fallback ladder."""
        self.assembler.reset()
        self.safe.reset()


class HqpScheme(_StackScheme):
    """The lexicographic QP of the stack (see the module docstring)."""

    name = "hqp"

    def __init__(self, assembler: StackAssembler, solver: str, options: dict[str, Any] | None,
                 deadline: float | None, strict: bool, **_: Any) -> None:
        if not get_spec(solver).inequality_levels:
            require_equality_tasks(assembler, f"solver {solver!r}")
        safe = SafeSolver(solver, None, options, alternate=default_alternate(solver),
                          deadline=deadline, strict=strict)
        super().__init__(assembler, safe, assembler.problem)


class WeightedScheme(_StackScheme):
    """One weighted QP over every task row (see the module docstring)."""

    name = "weighted"

    def __init__(self, assembler: StackAssembler, solver: str, options: dict[str, Any] | None,
                 deadline: float | None, strict: bool, priority_ratio: float = 1e4,
                 **_: Any) -> None:
        if solver == "daqp":
            solver = "cascade:daqp"
        if not get_spec(solver).inequality_levels:
            require_equality_tasks(assembler, f"solver {solver!r}")
        safe = SafeSolver(solver, None, options,
                          alternate=default_alternate(solver, cascade_only=True),
                          deadline=deadline, strict=strict)
        full = assembler.problem
        sizes = full.sizes
        super().__init__(assembler, safe, full.regrouped([sum(sizes)]))
        p = len(sizes)
        self._level_factors = [priority_ratio ** (p - 1 - k) for k in range(p)]
        self._factors = np.repeat(self._level_factors, sizes)
        self._version = -1
        self._views: dict[Problem, Problem] = {}

    def _prepare(self) -> None:
        version = self.assembler.weights_version
        if version != self._version:
            self.problem.set_weights(self.assembler.problem.w * self._factors)
            self._version = version

    def _scheme_problem(self, problem: Problem) -> Problem:
        """One weighted level for the stack's ``problem`` or a problem derived from it.

        The stack's own keeps its weights current in :meth:`_prepare`; a derived problem gets a
        view with its rows weighted by their level's factor.
        """
        if problem is self.assembler.problem:
            return self.problem
        view = self._views.get(problem)
        if view is None:
            view = self._views[problem] = problem.regrouped([sum(problem.sizes)])
        view.set_weights(problem.w * np.repeat(self._level_factors, problem.sizes))
        return view


class NullspaceScheme(_StackScheme):
    """The closed-form recursive null-space scheme, saturated into the box."""

    name = "nullspace"

    def __init__(self, assembler: StackAssembler, solver: str, options: dict[str, Any] | None,
                 deadline: float | None, strict: bool, **_: Any) -> None:
        require_equality_tasks(assembler, "scheme 'nullspace'")
        safe = SafeSolver("nullspace", None, options, alternate=default_alternate("nullspace"),
                          deadline=deadline, strict=strict, saturate=True, accept_unproven=True)
        super().__init__(assembler, safe, assembler.problem)


#: The controller's schemes by name (each built from the assembler and the keyword arguments
#: ``solver``, ``options``, ``deadline``, ``strict``, ``priority_ratio``).
SCHEMES: dict[str, Callable[..., _StackScheme]] = {
    "hqp": HqpScheme, "weighted": WeightedScheme, "nullspace": NullspaceScheme}
