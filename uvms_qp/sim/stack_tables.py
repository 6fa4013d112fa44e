"""A scenario file's stack: trajectories, constraint and task tables, events.

The tables are read and checked once (:func:`read_stack`, :func:`read_events`): every task and
constraint is built once from its table, bound to the model, linked into a stack and evaluated at
the initial state, and every event's update is applied to that stack in time order. What remains
is a :class:`StackTables`: the classes and their checked keyword arguments, which builds a fresh
stack (new task and constraint objects) each time it is called, one per run.

Tasks and constraints are built from the registries ``uvms_qp.tasks.TASK_TYPES`` and
``uvms_qp.constraints.CONSTRAINT_TYPES`` by introspecting their keyword constructors
(:func:`uvms_qp.sim.config.keyword_arguments`), so a new class is usable in scenario files as
soon as it is registered. Every error is a :class:`~uvms_qp.errors.ConfigError` at its field path.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

from ..errors import ConfigError, UvmsQpError
from ..stack import Level, Stack, as_activation
from ..tasks.task import STACK_KEYS
from .config import (
    NOT_HANDLED,
    Table,
    config_error_from,
    convert,
    instantiate,
    keyword_arguments,
    keyword_parameters,
    parameter_hints,
)
from .current import ConstantCurrent
from .trajectories import TRAJECTORY_TYPES, Trajectory


def _fresh(value: Any) -> Any:
    """A private copy of a plain TOML value (lists, tables).

    Objects such as trajectories, which hold no run-time state, are shared.
    """
    return copy.deepcopy(value) if isinstance(value, list | dict) else value


@dataclass(frozen=True)
class Event:
    """A run-time parameter change: at ``time`` [s], ``task.update(**update)``.

    The keys ``activation`` and ``ramp`` go to the task's stack entry instead
    (:meth:`~uvms_qp.stack.Stack.set_activation`).

    Attributes:
        time: When the event fires [s] (at the first step with ``t >= time``).
        task: Name of the task to update.
        update: Keyword arguments passed to the task's ``update``.
        path: Field path of the event's update (``events[0].update``), for messages.
    """

    time: float
    task: str
    update: Mapping[str, Any]
    path: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "update", MappingProxyType(dict(self.update)))

    def apply(self, stack: Stack) -> None:
        """``task.update(**update)`` on the task of ``stack`` named :attr:`task` (all or nothing).

        ``activation`` and ``ramp`` are set with ``stack.set_activation`` once the rest is
        accepted (the activation is validated first).
        """
        entry = {key: v for key, v in self.update.items() if key in STACK_KEYS}
        if "activation" in entry:
            as_activation(entry["activation"], f"{self.task}.activation")
        params = {key: _fresh(v) for key, v in self.update.items() if key not in STACK_KEYS}
        if params:
            stack.task(self.task).update(**params)
        if entry:
            stack.set_activation(self.task, **entry)


@dataclass(frozen=True)
class Item:
    """A task or constraint of a scenario file: its class and checked keyword arguments.

    Attributes:
        cls: The task or constraint class.
        kwargs: Keyword arguments of its constructor (converted; trajectories resolved).
        path: Field path of its table (``levels[1].tasks[0]``).
        activation: A task's initial activation in its stack (None: 1).
    """

    cls: type
    kwargs: Mapping[str, Any]
    path: str
    activation: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "kwargs", MappingProxyType(dict(self.kwargs)))

    def build(self) -> Any:
        """A new, unbound object of :attr:`cls` (the arguments were checked when read)."""
        return self.cls(**{key: _fresh(value) for key, value in self.kwargs.items()})


@dataclass(frozen=True)
class StackTables:
    """The checked levels and constraints of a scenario file; calling it builds a fresh stack.

    Attributes:
        levels: Task items per level, highest priority first.
        constraints: Constraint items.
        damping: Each level's damping threshold (None: the controller's).
    """

    levels: tuple[tuple[Item, ...], ...]
    constraints: tuple[Item, ...] = field(default=())
    damping: tuple[float | None, ...] = field(default=())

    def __call__(self) -> Stack:
        """A new, unbound :class:`~uvms_qp.stack.Stack` (new task and constraint objects)."""
        damping = self.damping or (None,) * len(self.levels)
        stack = Stack(levels=[Level(*(item.build() for item in level), damping=d)
                              for level, d in zip(self.levels, damping, strict=True)],
                      constraints=[item.build() for item in self.constraints])
        for level, items in zip(stack.levels, self.levels, strict=True):
            for task, item in zip(level.tasks, items, strict=True):
                if item.activation is not None:
                    stack.set_activation(task.name, item.activation)
        return stack


def lookup_type(table: Table, registry: Mapping[str, type], kind: str) -> type:
    """The class named by the table's ``type`` key in ``registry``.

    Raises:
        ConfigError: missing or unknown type (the known ones are listed).
    """
    type_name = str(table.take_str("type", required=True))
    if type_name not in registry:
        known = ", ".join(sorted(registry))
        raise ConfigError(
            f"unknown {kind} type {type_name!r}; known {kind} types: {known}", table.at("type")
        )
    return registry[type_name]


def task_class(table: Table, registry: Mapping[str, type]) -> type:
    """The task class of a table: its ``type``, then its ``mode`` where modes are classes.

    A type whose modes yield different kinds of rows picks the class of the mode
    (``JointLimitTask.for_mode``).

    Raises:
        ConfigError: missing or unknown type or mode (the known ones are listed).
    """
    cls = lookup_type(table, registry, "task")
    for_mode = getattr(cls, "for_mode", None)
    if for_mode is None:
        return cls
    try:
        return for_mode(table.data.get("mode"), table.data.get("name"))  # type: ignore[no-any-return]
    except UvmsQpError as exc:
        raise ConfigError(str(exc).split(": ", 1)[-1], table.at("mode")) from exc


def read_trajectory(table: Table) -> Trajectory:
    """Build a trajectory from its table (``type`` and the class's keyword arguments)."""
    cls = lookup_type(table, TRAJECTORY_TYPES, "trajectory")
    kwargs = keyword_arguments(cls, table, kind="trajectory")
    return instantiate(cls, kwargs, table.path)  # type: ignore[no-any-return]


def read_trajectories(table: Table | None) -> dict[str, Trajectory]:
    """The named trajectories of ``[trajectories.NAME]`` tables."""
    trajectories: dict[str, Trajectory] = {}
    if table is not None:
        for key in list(table.data):
            table.raw(key)
            trajectories[key] = read_trajectory(Table(table.data[key], table.at(key)))
    return trajectories


class TaskResolver:
    """Resolve scenario references: ``trajectory = "name"`` and ``heading = "current"``."""

    def __init__(
        self, trajectories: Mapping[str, Trajectory], current: ConstantCurrent | None
    ) -> None:
        self.trajectories = trajectories
        self.current = current

    def __call__(self, key: str, hint: Any, value: Any, path: str) -> Any:
        """The object a reference names, or ``NOT_HANDLED`` (see ``config.Resolver``)."""
        if key == "trajectory":
            if isinstance(value, str):
                if value not in self.trajectories:
                    known = ", ".join(sorted(self.trajectories)) or "(none defined)"
                    raise ConfigError(
                        f"unknown trajectory {value!r}; known trajectories: {known}", path
                    )
                return self.trajectories[value]
            if isinstance(value, dict):
                return read_trajectory(Table(value, path))
            raise ConfigError("expected a trajectory name or an inline trajectory table", path)
        if key == "heading" and isinstance(value, str):
            if value != "current":
                raise ConfigError(
                    f"expected a number [rad] or the string 'current' (the direction of the "
                    f"[current] table), got {value!r}",
                    path,
                )
            if self.current is None:
                raise ConfigError("'current' needs a [current] table in the scenario", path)
            return self.current.heading
        return NOT_HANDLED


def _error(exc: Exception, item: Item) -> ConfigError:
    return config_error_from(exc, item.path, list(keyword_parameters(item.cls)), item.kwargs)


def _bind(obj: Any, item: Item, model: Any) -> None:
    try:
        obj.bind(model)
    except (UvmsQpError, ValueError) as exc:
        raise _error(exc, item) from exc


def read_stack(
    top: Table,
    model: Any,
    resolver: TaskResolver,
    task_types: Mapping[str, type],
    constraint_types: Mapping[str, type],
    state: Any,
) -> tuple[StackTables, Stack]:
    """Read ``[[constraints]]`` and ``[[levels]]``, and check them on one stack built from them.

    Each task and constraint is built and bound once, the stack is linked (``Stack.bind``), and
    each task's rows are evaluated at ``state`` (what only shows in an evaluation, e.g. a heading
    never set).

    Returns:
        The tables, and the stack they were checked on (bound, not stepped; events not applied).

    Raises:
        ConfigError: any invalid table or value, at its path.
    """
    constraint_items: list[Item] = []
    constraints = []
    for table in top.take_tables("constraints"):
        cls = lookup_type(table, constraint_types, "constraint")
        item = Item(cls, keyword_arguments(cls, table, kind="constraint"), table.path)
        constraint = instantiate(cls, item.kwargs, item.path)
        _bind(constraint, item, model)
        constraint_items.append(item)
        constraints.append(constraint)

    level_items: list[tuple[Item, ...]] = []
    level_damping: list[float | None] = []
    levels: list[list[Any]] = []
    items_by_name: dict[str, Item] = {}
    level_tables = top.take_tables("levels", required=True, keys=("tasks", "damping"))
    if not level_tables:
        raise ConfigError("expected at least one level", top.at("levels"))
    for level_table in level_tables:
        task_tables = level_table.take_tables("tasks", required=True)
        level_damping.append(level_table.take_number("damping", None, nonnegative=True))
        level_table.finish()
        if not task_tables:
            raise ConfigError("expected at least one task in a level", level_table.at("tasks"))
        items: list[Item] = []
        tasks = []
        for table in task_tables:
            cls = task_class(table, task_types)
            activation = table.take_number("activation", None, minimum=0.0, maximum=1.0)
            item = Item(cls, keyword_arguments(cls, table, skip=("type", "activation"),
                                               resolver=resolver, kind="task"),
                        table.path, activation)
            task = instantiate(cls, item.kwargs, item.path)
            if task.name in items_by_name:
                raise ConfigError(
                    f"duplicate task name {task.name!r} (also at "
                    f"{items_by_name[task.name].path}); give each task a unique 'name'",
                    table.at("name"),
                )
            _bind(task, item, model)
            if getattr(task, "has_target", True) is False:
                raise ConfigError(
                    f"task {task.name!r} has no target: give it a 'trajectory' or a fixed target "
                    "(e.g. 'position')",
                    table.path,
                )
            items_by_name[task.name] = item
            items.append(item)
            tasks.append(task)
        level_items.append(tuple(items))
        levels.append(tasks)

    try:
        stack = Stack(levels=[Level(*tasks, damping=d) for tasks, d in zip(
            levels, level_damping, strict=True)], constraints=constraints)
        stack.bind(model)
    except (UvmsQpError, ValueError) as exc:
        raise ConfigError(str(exc), "levels") from exc
    for level, items_ in zip(stack.levels, level_items, strict=True):
        for task, item in zip(level.tasks, items_, strict=True):
            if item.activation is not None:
                stack.set_activation(task.name, item.activation)
    for level, items_ in zip(stack.levels, level_items, strict=True):
        for task, item in zip(level.tasks, items_, strict=True):
            try:
                task.rows(state, 0.0)
            except (UvmsQpError, ValueError) as exc:
                raise _error(exc, item) from exc
    return StackTables(tuple(level_items), tuple(constraint_items), tuple(level_damping)), stack


def read_events(
    top: Table, duration: float, stack: Stack, resolver: TaskResolver
) -> tuple[Event, ...]:
    """Read ``[[events]]``: the task each names (in ``stack``) and its update's keys and types.

    The values themselves are judged by :func:`apply_events` on the checked stack.

    Returns:
        The events, sorted by time.

    Raises:
        ConfigError: an unknown task or parameter or a value of the wrong type, at its path.
    """
    names = [task.name for task in stack.tasks]
    events = []
    for table in top.take_tables("events", keys=("time", "task", "update")):
        time = float(table.take_number("time", required=True, minimum=0.0, maximum=duration) or 0)
        name = str(table.take_str("task", required=True))
        update_table = table.take_table("update", required=True) or Table({}, "")
        table.finish()
        if name not in names:
            raise ConfigError(
                f"unknown task {name!r}; known tasks: {', '.join(names)}", table.at("task")
            )
        task = stack.task(name)
        cls = type(task)
        allowed = (*task.updatable(), *STACK_KEYS)
        hints = {**parameter_hints(cls), **dict.fromkeys(STACK_KEYS, float)}
        update: dict[str, Any] = {}
        for key, value in update_table.data.items():
            path = update_table.at(key)
            if key not in allowed or key == "name":
                known = ", ".join(p for p in allowed if p != "name")
                raise ConfigError(
                    f"unknown parameter {key!r} of task {name!r}; known parameters: {known}", path
                )
            converted = resolver(key, hints.get(key), value, path)
            if converted is NOT_HANDLED:
                converted = convert(value, hints.get(key, Any), path)
            update[key] = converted
        events.append(Event(time, name, update, update_table.path))
    events.sort(key=lambda e: e.time)
    return tuple(events)


def apply_events(events: Sequence[Event], stack: Stack, dt: float | None = None) -> None:
    """Apply each event's update to its task of ``stack``, in the given order.

    Used once on the stack a scenario is checked on, so a value that only the bound task can
    judge (a 2-coordinate ``position`` on a spatial model, a gain that would not settle at the
    control period ``dt`` [s]) fails when the scenario is loaded or built, at the event's path,
    rather than when the event fires.

    Raises:
        ConfigError: an update the task rejects, at the event's path.
    """
    for event in events:
        try:
            event.apply(stack)
            if dt is not None:
                stack.task(event.task).check_period(dt)
        except (UvmsQpError, ValueError, TypeError) as exc:
            raise config_error_from(exc, event.path, list(event.update), event.update) from exc


def check_periods(tables: StackTables, stack: Stack, dt: float) -> None:
    """Check every task of ``stack`` against the control period ``dt`` [s].

    (:meth:`~uvms_qp.tasks.Task.check_period`: set-based rows whose gain overshoots, error
    tasks whose error would never settle; :func:`apply_events` checks the events.)

    Raises:
        ConfigError: at the task's field, e.g. ``levels[1].tasks[0].gain``.
    """
    for level, items in zip(stack.levels, tables.levels, strict=True):
        for task, item in zip(level.tasks, items, strict=True):
            try:
                task.check_period(dt)
            except (UvmsQpError, ValueError) as exc:
                raise _error(exc, item) from exc
