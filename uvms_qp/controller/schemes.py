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
  (``000_7b5f597fe4e36aa4.txt, Eq. (10)`` extended to p levels, in the metric W of Eq. (17)),
  saturated into the hard box (``StepResult.saturated`` says when that changed the command);
  its status judges the saturated command against the levels, and hard rows it breaks send the
  step down the ladder. It has no notion of inequality rows: a stack with inequality tasks is
  refused at construction.

The papers' schemes (:mod:`uvms_qp.schemes`) implement the same :class:`Scheme` protocol.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

from ..errors import InputError, NoSolutionFound
from ..hqp import Problem
from ..hqp.registry import get_spec
from ..safety import DEGRADED_STAGES, SafeSolver, default_alternate
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
    """A scheme that solves the assembled stack through the fallback ladder."""

    name: ClassVar[str] = ""

    def __init__(self, assembler: StackAssembler, safe: SafeSolver, problem: Problem) -> None:
        self.assembler = assembler
        self.safe = safe
        self.problem = problem
        self.solver_name = safe.name

    def step(self, state: State, t: float = 0.0) -> StepResult:
        """Fill the problem, solve it through the ladder, measure the command.

        Raises:
            InputError: a task whose target was never set, a state of another model, or
                something other than a State (e.g. a configuration array).
            NonFiniteError: a task produced NaN/inf rows (the message names the task).
            BoundsError: the hard box is empty (the message names the constraints).
            NoSolutionFound: strict mode, and no back-end returned a verified solution.
        """
        clock = self.safe.clock
        start = clock()
        assembler = self.assembler
        assembler.fill(state, t)
        self._prepare()
        try:
            out = self.safe.solve(self.problem, start)
        except NoSolutionFound:
            assembler.check_box(state)
            raise
        if out.stage in DEGRADED_STAGES:  # e.g. an empty box, which no back-end can answer
            assembler.check_box(state)
        return assembler.step_result(out, t, clock() - start, self.name, self.solver_name)

    def _prepare(self) -> None:
        """Per-tick work of the scheme after the stack is written (none by default)."""

    def reset(self) -> None:
        """Reset every task's run-time memory and the fallback ladder."""
        self.assembler.stack.reset()
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
        self._factors = np.repeat([priority_ratio ** (p - 1 - k) for k in range(p)], sizes)
        self._version = -1

    def _prepare(self) -> None:
        version = self.assembler.weights_version
        if version != self._version:
            self.problem.set_weights(self.assembler.problem.w * self._factors)
            self._version = version


class NullspaceScheme(_StackScheme):
    """The closed-form recursive null-space scheme, saturated into the box."""

    name = "nullspace"

    def __init__(self, assembler: StackAssembler, solver: str, options: dict[str, Any] | None,
                 deadline: float | None, strict: bool, **_: Any) -> None:
        require_equality_tasks(assembler, "scheme 'nullspace'")
        safe = SafeSolver("nullspace", None, options, alternate=default_alternate("nullspace"),
                          deadline=deadline, strict=strict, saturate=True)
        super().__init__(assembler, safe, assembler.problem)


#: The controller's schemes by name (each built from the assembler and the keyword arguments
#: ``solver``, ``options``, ``deadline``, ``strict``, ``priority_ratio``).
SCHEMES: dict[str, Callable[..., _StackScheme]] = {
    "hqp": HqpScheme, "weighted": WeightedScheme, "nullspace": NullspaceScheme}
