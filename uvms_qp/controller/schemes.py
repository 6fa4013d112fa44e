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

from .._validation import FloatArray, as_time
from ..errors import InputError, NoSolutionFound
from ..hqp import Problem, Status
from ..hqp.damping import Damping, level_damping
from ..hqp.measure import clip_to_box, evaluate, hard_violation
from ..hqp.registry import get_spec
from ..model.vehicle import NU_NAMES
from ..safety import DEGRADED_STAGES, SafeSolve, SafeSolver, default_alternate
from ..safety.fallback import Damper
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
        self._damped_stack: Problem | None = None  # this step's damped problem, if any
        #: The solver that re-solves the joints with the vehicle at its measured velocity
        #: (:meth:`_coordinate`; its own back-end, warm-started on its own problems), or None.
        self.coordination: SafeSolver | None = None
        model = assembler.model
        self._measured = [NU_NAMES.index(d) for d in model.actuated] if (
            model.vehicle_kind == "spatial") else []
        self._coordinated: dict[Problem, tuple[Problem, list[int]]] = {}

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
        problem = (assembler.problem if not excluded
                   else assembler.derived(excluded, assembler.no_rows))
        self._damped_stack = None
        try:
            out = self.safe.solve(self._scheme_problem(problem), start,
                                  self._damper(excluded, problem))
        except NoSolutionFound:
            assembler.check_box(state)
            raise
        if out.stage in DEGRADED_STAGES:  # e.g. an empty box, which no back-end can answer
            assembler.check_box(state)
        damping = out.damping
        solved = problem if damping is None or self._damped_stack is None else self._damped_stack
        status = out.result.status if damping is None else Status.DAMPED
        if ramping and out.solved:
            blend = self._blend(excluded, ramping, out, solved, start)
            if blend is not None:  # (a blend with an unproven answer is not proven either)
                out, status = blend, (Status.BLENDED if out.result.ok else Status.UNPROVEN)
        if (self.coordination is not None and state.velocity is not None and out.solved
                and self._measured):
            coordinated = self._coordinate(state.velocity, out, solved, start)
            if coordinated is not None:
                out, solved, status = coordinated[0], coordinated[1], Status.COORDINATED
        self.safe.previous = out.x
        self.status_counts[status.value] += 1
        step_time = clock() - start
        deadline = self.safe.deadline
        if deadline is not None and step_time > deadline and not out.deadline_missed:
            out = dataclasses.replace(out, deadline_missed=True)  # late in an optional solve
        return assembler.step_result(out, t, step_time, self.name, self.solver_name,
                                     status, solved, damping, excluded, ramping)

    def _damper(self, excluded: tuple[int, ...], problem: Problem) -> Damper | None:
        """The ladder's ``damped`` stage for the stack without ``excluded`` (None: no damping).

        At an answer ``x``: the damping rows of every level (:func:`level_damping`) and the
        problem with them, as this scheme hands it to the ladder.
        """
        thresholds = self.assembler.damping
        if thresholds is None:
            return None
        assembler = self.assembler

        def damper(x: FloatArray, end: float) -> tuple[Damping | None, Problem | None]:
            damping = level_damping(problem, x, thresholds, assembler.dt, end=end,
                                    clock=self.safe.clock)
            if damping is None:
                return None, problem  # the deadline passed in the screen
            if not damping.acted:
                return None, None
            damped = assembler.derived(excluded, damping.rows)
            self._damped_stack = damped
            return damping, self._scheme_problem(damped)

        return damper

    def _blend(self, excluded: tuple[int, ...], ramping: tuple[int, ...], main: SafeSolve,
               solved: Problem, start: float) -> SafeSolve | None:
        """The blend of the optima with and without the ramping tasks, or None.

        ``sum_S prod_i a_i^[i in S] (1 - a_i)^[i not in S] x(S)`` over the subsets ``S`` of the
        ramping tasks (the continuous activation of Mansard, Khatib and Kheddar 2009, for scalar
        activations); ``x`` of the full set is ``main``. Each other subset is one solve of the
        primary back-end through the ladder (:meth:`SafeSolver.solve_once`, damped where
        needed); None when one fails or the deadline passes.
        """
        tasks, slots = self.assembler.tasks, self.assembler.slots
        a = [slots[i].activation for i in ramping]
        x = np.zeros_like(main.x)
        damped_stack = self._damped_stack
        for mask in range(1 << len(ramping)):
            weight = math.prod(a[j] if mask >> j & 1 else 1.0 - a[j] for j in range(len(a)))
            if mask == (1 << len(ramping)) - 1:
                x += weight * main.x
                continue
            out = tuple(sorted(excluded + tuple(i for j, i in enumerate(ramping)
                                                 if not mask >> j & 1)))
            sub = self.assembler.derived(out, self.assembler.no_rows)
            other = self.safe.solve_once(self._scheme_problem(sub), start,
                                         self._damper(out, sub))
            if other is None:
                self._damped_stack = damped_stack
                return None
            x += weight * other.x
        self._damped_stack = damped_stack
        problem = self._scheme_problem(solved)
        x, _ = clip_to_box(x, problem.lower, problem.upper)  # round-off only: the box is convex
        primary = self.safe.primary
        active = ", ".join(f"{tasks[i].name} {slots[i].activation:.3g}" for i in ramping)
        result = evaluate(problem, x, Status.BLENDED, main.result.solver,
                          f"blended: activation {active}", level_tol=primary.level_tol,
                          hard_tol=primary.hard_tol, solve_time=main.result.solve_time)
        return dataclasses.replace(main, x=x, result=result)

    def _coordinate(self, velocity: FloatArray, main: SafeSolve, solved: Problem, start: float
                    ) -> tuple[SafeSolve, Problem] | None:
        """Arm-vehicle coordination: the joints re-solved with the vehicle at its measured rates.

        The kinematic layer's vehicle rates are a reference the vehicle follows with a lag; the
        arm, faster, can absorb the difference. As in Simetti et al. (2014), J. Field Robotics
        31(3), Section 4 (and Simetti, Casalino, Wanderlingh, Aicardi (2018), Ocean Engineering
        164), the stack is solved a second time with each actuated vehicle rate fixed at its
        measured value (its box entry set to it: the vehicle's rates are data, not decisions),
        so the joint rates are the lexicographic optimum given what the vehicle does; the
        vehicle keeps the first answer's reference. The problem is the one the first answer
        solved (its damping rows included).

        Returns:
            ``(outcome, problem)``: the command (vehicle rates of ``main``, joint rates of the
            second answer; its ``result`` is the second answer's measurement, vehicle at the
            measured rates) and the second problem; None when the
            second solve gives no proven answer or the deadline has passed, or when the command
            breaks a hard row of ``solved`` (rows that couple the vehicle's rates to the joints'
            hold for the measured rates, not always for the reference): the step then keeps
            ``main``.
        """
        source = self._scheme_problem(solved)
        entry = self._coordinated.get(source)
        if entry is None:
            entry = self._coordinated[source] = (source.copy(), [-1])
        problem, version = entry
        np.copyto(problem.A, source.A)
        np.copyto(problem.sides, source.sides)
        if version[0] != source.weights_version:
            problem.set_weights(source.w)
            version[0] = source.weights_version
        n_vehicle = len(self._measured)
        measured = velocity[self._measured]
        problem.lower[:n_vehicle] = measured
        problem.upper[:n_vehicle] = measured
        assert self.coordination is not None
        other = self.coordination.solve_once(problem, start)
        if other is None:
            return None
        x = main.x.copy()
        x[n_vehicle:] = other.x[n_vehicle:]
        hard = source.hard
        if hard_violation(x, source.lower, source.upper, hard.A, hard.lower,
                          hard.upper) > self.safe.hard_tol * source.hard_scale:
            return None
        return dataclasses.replace(main, x=x, result=other.result), problem

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
