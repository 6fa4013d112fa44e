"""Declarative stacks: levels of tasks in descending priority plus hard constraints.

Example:
    >>> from uvms_qp.stack import Level, Stack
    >>> from uvms_qp.tasks import EndEffectorTask, StationKeepingTask
    >>> from uvms_qp.constraints import JointVelocityBounds
    >>> stack = Stack(
    ...     levels=[Level(EndEffectorTask(position=[1.0, 0.0, 0.5], gain=2.0)),  # [1/s]
    ...             Level(StationKeepingTask(gain=1.0))],
    ...     constraints=[JointVelocityBounds()],
    ... )
    >>> [level.names for level in stack.levels]
    [('end_effector',), ('station_keeping',)]
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Iterator, Sequence
from typing import TYPE_CHECKING, Any

from ._validation import as_scalar
from .constraints.constraint import Constraint
from .errors import InputError
from .tasks.task import Task

if TYPE_CHECKING:  # pragma: no cover
    from .model import Model


#: Default duration of an activation ramp from 0 to 1 [s] (:meth:`Stack.set_activation`).
DEFAULT_RAMP = 1.0


def as_activation(value: Any, name: str) -> float:
    """Validate an activation: a number in [0, 1]."""
    a = as_scalar(value, name, nonnegative=True)
    if a > 1.0:
        raise InputError(f"{name}: expected an activation in [0, 1], got {a:g}")
    return a


class Entry:
    """A task's entry in a stack: its requested activation and ramp duration.

    Attributes:
        activation: The requested activation in [0, 1].
        ramp: Duration of a ramp from 0 to 1 [s].
        serial: Counts the requests (a controller starts a ramp when it moved).
    """

    __slots__ = ("activation", "ramp", "serial")

    def __init__(self) -> None:
        self.activation = 1.0
        self.ramp = DEFAULT_RAMP
        self.serial = 0


class Level:
    """One priority level: tasks whose rows are traded off by their weights.

    ``Level(task_a, task_b)`` or ``Level([task_a, task_b])``; an optional ``name`` labels it in
    diagnostics. ``damping`` sets the level's damping threshold ``epsilon`` (>= 0, 0: none; in
    the units of its weighted rows per unit of ``W^(1/2) zeta``): directions of the level whose
    singular value in the freedom the higher levels leave falls below it are damped
    (:mod:`uvms_qp.hqp.damping`); None takes the controller's.

    Raises:
        InputError: an empty level, an item that is not a :class:`~uvms_qp.tasks.Task`, or a
            negative damping.
    """

    def __init__(self, *tasks: Task | Iterable[Task], name: str | None = None,
                 damping: float | None = None) -> None:
        items: list[Any] = []
        for item in tasks:
            if isinstance(item, Task):
                items.append(item)
            elif isinstance(item, Iterable) and not isinstance(item, str | bytes):
                items.extend(item)
            else:
                items.append(item)
        label = f"level {name!r}" if name else "level"
        if not items:
            raise InputError(f"{label}: a level needs at least one task")
        for i, task in enumerate(items):
            if not isinstance(task, Task):
                raise InputError(f"{label} item {i}: expected a Task, got {type(task).__name__}")
        self.tasks: tuple[Task, ...] = tuple(items)
        self.name = name
        self.damping = None if damping is None else as_scalar(
            damping, f"{label}.damping", nonnegative=True)

    @property
    def names(self) -> tuple[str, ...]:
        """Names of the level's tasks."""
        return tuple(t.name for t in self.tasks)

    @property
    def dim(self) -> int:
        """Total row count (after binding)."""
        return sum(t.dim for t in self.tasks)

    def __iter__(self) -> Iterator[Task]:
        return iter(self.tasks)

    def __len__(self) -> int:
        return len(self.tasks)

    def __repr__(self) -> str:
        return f"Level({', '.join(repr(t) for t in self.tasks)})"


class Stack:
    """Levels of tasks (highest priority first) and hard constraints.

    Validated at construction (non-empty levels, unique task names, types) and at
    :meth:`bind` (frames, joints, axes and dimensions against the model).

    A stack is a description: its tasks and constraints keep no run-time memory (each
    controller keeps its own, see :class:`~uvms_qp.tasks.TaskSlot`), so any number of
    controllers may share it and each steps as it would on its own copy. A change to a task
    (``task.update(...)``, :meth:`set_activation`) reaches every controller built on the stack.

    Each task has an entry in the stack: its requested activation in [0, 1] (1: in the stack,
    0: out of it, in between: the commands with and without it blended, as in the continuous
    activation of Mansard, Khatib and Kheddar, IEEE Trans. Robotics 2009) and the duration of
    the ramp that takes a controller to a new request (:meth:`set_activation`), as TSID's
    formulation owns a task's priority, weight and transition duration.

    Args:
        levels: Levels in descending priority; a plain list of tasks is accepted as a level.
        constraints: Hard constraints (bounds and inequalities) holding at every level.

    Raises:
        InputError: no level, an empty level, duplicate task names, wrong item types.
    """

    def __init__(self, levels: Sequence[Level | Sequence[Task]],
                 constraints: Sequence[Constraint] = ()) -> None:
        if isinstance(levels, Level) or not isinstance(levels, Sequence) or not levels:
            raise InputError("levels: expected a non-empty list of levels")
        built: list[Level] = []
        for k, level in enumerate(levels):
            if isinstance(level, Level):
                built.append(level)
            elif isinstance(level, Task):
                built.append(Level(level))
            elif isinstance(level, Sequence) and not isinstance(level, str | bytes):
                if not level:
                    raise InputError(f"levels[{k}]: a level needs at least one task")
                built.append(Level(*level))
            else:
                raise InputError(f"levels[{k}]: expected a Level, got {type(level).__name__}")
        seen: dict[str, int] = {}
        for k, level in enumerate(built):
            for task in level:
                if task.name in seen:
                    raise InputError(
                        f"levels[{k}]: duplicate task name {task.name!r} (also in "
                        f"levels[{seen[task.name]}]); give each task a unique name=")
                seen[task.name] = k
            if len(set(map(id, level.tasks))) != len(level.tasks):
                raise InputError(f"levels[{k}]: the same task object appears twice")
        if isinstance(constraints, Constraint) or not isinstance(constraints, Sequence):
            raise InputError("constraints: expected a list of constraints")
        names: set[str] = set()
        for i, c in enumerate(constraints):
            if not isinstance(c, Constraint):
                raise InputError(f"constraints[{i}]: expected a Constraint, got "
                                 f"{type(c).__name__}")
            if c.name in names:
                raise InputError(f"constraints[{i}]: duplicate constraint name {c.name!r}")
            names.add(c.name)
        self.levels: tuple[Level, ...] = tuple(built)
        self.constraints: tuple[Constraint, ...] = tuple(constraints)
        self.model: Model | None = None
        self.entries: dict[str, Entry] = {task.name: Entry() for task in self.tasks}
        self.requests = 0  # counts the activation requests (a controller looks when it moved)

    def copy(self) -> Stack:
        """A copy with its own tasks, constraints and entries (the model is shared).

        Events and updates applied to the copy leave this stack as it is.
        """
        return copy.deepcopy(self)

    def set_activation(self, name: str, activation: float | None = None, *,
                       ramp: float | None = None) -> None:
        """Ask for task ``name`` to be in the stack (1), out of it (0), or in between.

        Every controller on the stack ramps its activation from where it is to ``activation``
        over ``ramp * |change|`` seconds from its next step, with a smoothstep
        ``3 s^2 - 2 s^3`` (zero slope at both ends), so inserting or removing a task does not
        step the command; a controller built later starts at the requested value. A task
        entering the stack (from 0) starts afresh: a held target is taken then. Scenario files:
        ``activation`` in a task's table, an event ``update = { activation = 1.0, ramp = 2.0 }``.

        Args:
            name: The task.
            activation: The requested activation in [0, 1] (None: leave it).
            ramp: Duration of a ramp from 0 to 1 [s], kept for later requests (0: a step;
                default 1 s).

        Raises:
            InputError: an unknown task, an activation outside [0, 1], a negative ramp (nothing
                is changed then).
        """
        entry = self._entry(name)
        a = None if activation is None else as_activation(activation, f"{name}.activation")
        r = None if ramp is None else as_scalar(ramp, f"{name}.ramp", nonnegative=True)
        if r is not None:
            entry.ramp = r
        if a is not None:
            entry.activation = a
            entry.serial += 1
            self.requests += 1

    def activation(self, name: str) -> float:
        """The activation requested for task ``name`` (see :meth:`set_activation`)."""
        return self._entry(name).activation

    def _entry(self, name: str) -> Entry:
        entry = self.entries.get(name)
        if entry is None:
            self.task(name)  # raises, listing the known tasks
        return entry  # type: ignore[return-value]

    @property
    def tasks(self) -> tuple[Task, ...]:
        """All tasks, highest priority first."""
        return tuple(t for level in self.levels for t in level)

    def task(self, name: str) -> Task:
        """The task called ``name`` (raises InputError listing the known names)."""
        for t in self.tasks:
            if t.name == name:
                return t
        raise InputError(f"unknown task {name!r}; known tasks: "
                         f"{', '.join(t.name for t in self.tasks)}")

    def bind(self, model: Model) -> Stack:
        """Bind every task and constraint to ``model`` (validates frames, joints, sizes).

        Errors are re-raised with the location (``levels[1].tasks[0] (name): ...``).
        """
        for k, level in enumerate(self.levels):
            for i, task in enumerate(level):
                try:
                    task.bind(model)
                except Exception as exc:
                    exc.args = (f"levels[{k}].tasks[{i}] ({task.name}): {exc}",
                                *exc.args[1:]) if exc.args else exc.args
                    raise
        by_name = {t.name: t for t in self.tasks}
        for k, level in enumerate(self.levels):
            for i, task in enumerate(level):
                try:
                    task.link(by_name)
                except Exception as exc:
                    exc.args = (f"levels[{k}].tasks[{i}] ({task.name}): {exc}",
                                *exc.args[1:]) if exc.args else exc.args
                    raise
        for i, c in enumerate(self.constraints):
            try:
                c.bind(model)
            except Exception as exc:
                exc.args = (f"constraints[{i}] ({c.name}): {exc}", *exc.args[1:]) \
                    if exc.args else exc.args
                raise
        self.model = model
        return self

    def check_period(self, dt: float) -> None:
        """Check every task against the control period ``dt`` [s] (:meth:`Task.check_period`).

        Raises:
            InputError: a task whose rows would not settle at this period, with its location.
        """
        for k, level in enumerate(self.levels):
            for i, task in enumerate(level.tasks):
                try:
                    task.check_period(dt)
                except InputError as exc:
                    exc.args = (f"levels[{k}].tasks[{i}] ({task.name}): {exc}", *exc.args[1:])
                    raise

    def describe(self) -> str:
        """A readable listing of levels, tasks and constraints."""
        lines = []
        for k, level in enumerate(self.levels):
            lines.append(f"level {k}" + (f" ({level.name})" if level.name else ""))
            lines.extend(f"  {t.describe()}" for t in level)
        if self.constraints:
            lines.append("hard: " + ", ".join(c.name for c in self.constraints))
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"Stack({len(self.levels)} levels, {len(self.constraints)} constraints)"
