"""The control loop: model + stack + scheme -> one zeta per tick.

``Controller(model, stack, solver, dt, ...)`` binds the stack into a
:class:`~uvms_qp.controller.assembler.StackAssembler` (rows written straight into one problem's
buffers every tick) and hands it to one scheme (:mod:`~uvms_qp.controller.schemes`: ``"hqp"``,
``"weighted"``, ``"nullspace"``). ``metric`` is the diagonal W of the final regularisation
``min zeta' W zeta`` (e.g. :func:`uvms_qp.tasks.motion_distribution_weights`,
Wang et al. (2017), Eq. (14), or ``diag(10, 10, 10, 1, 1, 1)`` of Soylu et al. (2007)).
"""

from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from ..hqp.damping import DEFAULT_THRESHOLD
from ..model import Model
from ..rows import Rows
from ..safety import SafeSolver
from ..stack import Stack
from ..tasks import Task, TaskSlot
from .assembler import StackAssembler
from .result import StepResult
from .schemes import SCHEMES

if TYPE_CHECKING:  # pragma: no cover
    from ..model import State


def _check_arguments(model: Any, solver: Any, options: Any, strict: Any) -> None:
    """Reject constructor arguments of the wrong type, naming the argument.

    Raises:
        InputError: ``model`` is not a :class:`~uvms_qp.model.Model`, ``solver`` not a string,
            ``options`` neither None nor a dict, or ``strict`` not a bool.
    """
    if not isinstance(model, Model):
        hint = (f"; load a bundled model with uvms_qp.load_model({model!r})"
                if isinstance(model, str) else "")
        raise InputError(f"model: expected a Model, got {type(model).__name__}{hint}")
    if not isinstance(solver, str):
        raise InputError(f"solver: expected a solver name (str), got {type(solver).__name__}")
    if options is not None and not isinstance(options, dict):
        raise InputError(
            f"options: expected a dict of back-end options or None, got {type(options).__name__}")
    if not isinstance(strict, bool | np.bool_):
        raise InputError(f"strict: expected True or False, got {strict!r}")


class Controller:
    """Solve a :class:`~uvms_qp.stack.Stack` on a model every tick.

    Args:
        model: The UVMS model (the stack is bound to it here).
        stack: Levels of tasks and hard constraints. The controller keeps its own run-time
            memory of them (:meth:`slot`), so several controllers may share one stack.
        solver: Back-end (``"daqp"``, ``"cascade:<qpsolvers name>"``, ``"nullspace"``).
        dt: Control period [s] (turns position limits into rate bounds).
        metric: Diagonal W (nv,) of the final regularisation ``min zeta' W zeta`` (positive), or
            None for the identity.
        scheme: ``"hqp"``, ``"weighted"`` or ``"nullspace"`` (:mod:`uvms_qp.controller.schemes`).
        priority_ratio: Weight ratio between consecutive levels for ``scheme="weighted"``.
        options: Back-end options passed to :class:`~uvms_qp.hqp.HierarchySolver`.
        strict: Raise :class:`~uvms_qp.errors.NoSolutionFound` when no back-end returns a
            verified solution, instead of degrading (relaxed levels, decayed previous command,
            zero; see :mod:`uvms_qp.safety` and ``docs/reliability.md``).
        deadline: Wall-time budget of one step [s]; ``"period"`` (the default): the control
            period ``dt``; None: none (an offline simulation whose answers must not depend on
            the machine's load: a scenario without a ``deadline`` key). Every part of the step
            takes its time from it (the back-end, the certificate, the repair, the damping
            screen), and the fallback ladder skips its solver stages once it has passed
            (``docs/reliability.md``).
        damping: Damping threshold of every level that sets none (``Level(damping=...)``),
            >= 0: a level's directions whose singular value, in the freedom the higher levels
            leave, is below it get bounded rates (:mod:`uvms_qp.hqp.damping`); away from
            singularities nothing changes. 0 turns damping off.
        coordination: Arm-vehicle coordination (Simetti et al. (2014), J. Field Robotics
            31(3)): when a state carries the vehicle's measured body velocity
            (``model.state(q, velocity)``, as a floating plant gives it), the joints are
            re-solved with the vehicle's rates fixed at their measured values, so the arm
            absorbs the vehicle's tracking error; such steps have status ``coordinated``.
            ``hqp`` and ``weighted`` schemes; a state without a velocity is solved as usual.

    Raises:
        InputError: bad dt, metric or scheme; any binding error of the stack (unknown frame,
            joint, axis...), with its location in the stack; a solver that handles equality
            rows only (``"nullspace"``) with inequality tasks, naming them.
        UnknownSolverError: unknown or uninstalled solver.
    """

    def __init__(self, model: Model, stack: Stack, solver: str = "daqp", dt: float = 0.05,
                 metric: Any = None, *, scheme: str = "hqp", priority_ratio: float = 1e4,
                 options: dict[str, Any] | None = None, strict: bool = False,
                 deadline: float | str | None = "period",
                 damping: float = DEFAULT_THRESHOLD, coordination: bool = False) -> None:
        _check_arguments(model, solver, options, strict)
        if not isinstance(stack, Stack):
            raise InputError(f"stack: expected a Stack, got {type(stack).__name__}")
        if scheme not in SCHEMES:
            raise InputError(f"scheme: expected one of {', '.join(SCHEMES)}, got {scheme!r}")
        self.model = model
        self.dt = as_scalar(dt, "dt", positive=True)
        self.priority_ratio = as_scalar(priority_ratio, "priority_ratio", positive=True)
        self.nv = int(model.nv)
        self.metric = (np.ones(self.nv) if metric is None
                       else as_vector(metric, "metric", self.nv, positive=True).copy())
        self.strict = bool(strict)
        self.scheme = scheme
        self.damping = as_scalar(damping, "damping", nonnegative=True)
        self.assembler = StackAssembler(model, stack, self.dt, self.metric, self.damping)
        self.stack = self.assembler.stack
        if isinstance(deadline, str):
            if deadline != "period":
                raise InputError(f"deadline: expected seconds, 'period' or None, got {deadline!r}")
            deadline = self.dt
        self._scheme = SCHEMES[scheme](self.assembler, solver=solver, options=options,
                                       deadline=deadline, strict=self.strict,
                                       priority_ratio=self.priority_ratio)
        self.solver_name = self._scheme.solver_name
        self.level_names = self.assembler.level_names
        if not isinstance(coordination, bool | np.bool_):
            raise InputError(f"coordination: expected True or False, got {coordination!r}")
        if coordination and scheme == "nullspace":
            raise InputError("coordination: the closed-form 'nullspace' scheme has no box to fix "
                             "the vehicle's rates in; use scheme='hqp' or 'weighted'")
        self.coordination = bool(coordination)
        if self.coordination:
            self._scheme.coordination = SafeSolver(self.solver_name, None, options,
                                                   alternate=None, deadline=deadline)

    def step(self, state: State, t: float = 0.0) -> StepResult:
        """Compute zeta for ``state`` at time ``t`` [s].

        Every command is measured and lies inside the hard box (``docs/reliability.md``): when
        the back-end fails, the fallback ladder runs and ``StepResult.stage`` names the stage
        that produced zeta.

        Raises:
            InputError: a task whose target was never set, a state of another model,
                something other than a State (e.g. a configuration array; use
                ``model.state(q)``), or a time ``t`` that is not a real number.
            NonFiniteError: a task produced NaN/inf rows (the message names the task), or ``t``
                is NaN or inf; bad input never reaches a back-end.
            BoundsError: the hard box is empty (the message names the constraints involved): no
                command can satisfy it.
            NoSolutionFound: strict mode, and no back-end returned a verified solution.
        """
        return self._scheme.step(state, t)

    def reset(self) -> None:
        """Reset this controller's memory of every task and constraint, and the fallback ladder."""
        self._scheme.reset()

    @property
    def tasks(self) -> tuple[Task, ...]:
        """All tasks, highest priority first."""
        return self.assembler.tasks

    def slot(self, name: str) -> TaskSlot:
        """The run-time memory of task ``name`` in this controller (:class:`~.TaskSlot`).

        Its last error (``last_error``), its activation, a held target.

        Raises:
            InputError: an unknown task (the known ones are listed).
        """
        return self.assembler.slot(name)

    @property
    def safe(self) -> SafeSolver:
        """The fallback ladder every step runs through."""
        return self._scheme.safe

    @property
    def stage_counts(self) -> Counter[str]:
        """Steps per fallback stage since construction."""
        return self._scheme.safe.stage_counts

    @property
    def status_counts(self) -> Counter[str]:
        """Steps per status of their results since construction (``damped``, ``blended`` too)."""
        return self._scheme.status_counts

    def level_rows(self, state: State, t: float = 0.0) -> list[Rows]:
        """Rows of every level at ``(state, t)`` (fresh copies; for inspection and tests)."""
        return self.assembler.level_rows(state, t)

    def bounds(self, state: State) -> tuple[FloatArray, FloatArray]:
        """Merged hard box ``(lower, upper)`` on zeta at ``state`` (copies)."""
        return self.assembler.bounds(state)

    def __repr__(self) -> str:
        return (f"Controller({self.model.name!r}, {len(self.stack.levels)} levels, "
                f"scheme={self.scheme!r}, solver={self.solver_name!r}, dt={self.dt:g})")
