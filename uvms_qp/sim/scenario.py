"""Scenarios: a model, an initial state, a stack, a solver and a time span, from a TOML file.

:func:`load_scenario` reads a scenario file (or a bundled scenario by name, see
:func:`bundled_scenarios`) into a :class:`Scenario`. Validation is strict and complete before
anything runs: every error is a :class:`~uvms_qp.errors.ConfigError` whose message starts with the
field path (``levels[1].tasks[0].gain: expected a positive number, got -1.0``). The file format is
described in ``docs/scenarios.md``.

Tasks and constraints are built from the registries ``uvms_qp.tasks.TASK_TYPES`` and
``uvms_qp.constraints.CONSTRAINT_TYPES`` by introspecting their keyword constructors
(:func:`uvms_qp.sim.config.construct`), so a new task class is usable in scenario files as soon as
it is registered.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..errors import ConfigError, InputError, UnknownNameError, UvmsQpError
from .config import (
    NOT_HANDLED,
    Table,
    config_error_from,
    construct,
    convert,
    join,
    keyword_parameters,
    parameter_hints,
    read_toml,
)
from .current import ConstantCurrent
from .integrators import Integrator
from .trajectories import TRAJECTORY_TYPES, Trajectory

#: Largest number of steps a scenario may ask for (duration / dt).
MAX_STEPS = 2_000_000
_SCENARIO_PACKAGE = "uvms_qp.scenarios"
#: Keys of the top-level table (``docs/scenarios.md``); a required key is reported missing only
#: when no other key is unknown, so a misspelt ``duration`` is named as the unknown key.
_TOP_KEYS = (
    "name", "description", "model", "dt", "duration", "solver", "strict", "deadline", "metric",
    "schemes", "integrator", "initial", "current", "passive", "trajectories", "constraints",
    "levels", "events", "tracking", "phases",
)


@dataclass(frozen=True)
class Event:
    """A run-time parameter change: at ``time`` [s], ``task.update(**update)``.

    Attributes:
        time: When the event fires [s] (at the first step with ``t >= time``).
        task: Name of the task to update.
        update: Keyword arguments passed to the task's ``update``.
        path: Field path of the event in the scenario file (for messages).
    """

    time: float
    task: str
    update: Mapping[str, Any]
    path: str = ""


@dataclass(frozen=True)
class Phase:
    """A named time window [s] whose metrics are reported separately in ``results.json``."""

    name: str
    start: float
    end: float


@dataclass
class Scenario:
    """A fully validated, ready-to-run scenario.

    A scenario is used by one run: tasks keep run-time state (targets, events applied). Use
    :meth:`rebuild` for a fresh copy.

    Attributes:
        name: Scenario name.
        description: Free text.
        model: The :class:`~uvms_qp.model.Model`.
        q0: Initial configuration (nq,).
        stack: The :class:`~uvms_qp.stack.Stack` (levels of tasks and hard constraints).
        constraints: The stack's hard constraints (same objects as ``stack.constraints``).
        trajectories: Named trajectories defined by the file.
        solver: Solver name (``"daqp"``, ``"cascade:<backend>"``, ...).
        metric: Diagonal metric W (nv,) of the final minimum-norm regularisation, or None.
        dt: Control period [s].
        duration: Simulated time [s].
        events: Run-time parameter changes, sorted by time.
        current: Optional constant current.
        integrator: The configured :class:`~uvms_qp.sim.integrators.Integrator`.
        schemes: Schemes to compare (``"hqp"`` always first).
        tracking: Name of the task whose target is the tool reference in the metrics, or None.
        phases: Named time windows with their own metrics.
        source: File the scenario came from, when any.
        strict: The controller raises :class:`~uvms_qp.errors.NoSolutionFound` instead of
            degrading when no back-end returns a verified solution (``docs/reliability.md``).
        deadline: Wall-time budget of one controller step [s], or None for none.
    """

    name: str
    description: str
    model: Any
    q0: FloatArray
    stack: Any
    constraints: list[Any]
    trajectories: dict[str, Trajectory]
    solver: str
    metric: FloatArray | None
    dt: float
    duration: float
    events: list[Event]
    current: ConstantCurrent | None
    integrator: Integrator
    schemes: list[str]
    tracking: str | None = None
    phases: list[Phase] = field(default_factory=list)
    source: Path | None = None
    data: dict[str, Any] = field(default_factory=dict, repr=False)
    strict: bool = False
    deadline: float | None = None

    @property
    def steps(self) -> int:
        """Number of control steps, ``round(duration / dt)``."""
        return round(self.duration / self.dt)

    def tasks(self) -> Iterator[Any]:
        """Iterate over every task of the stack, highest priority first."""
        for level in self.stack.levels:
            yield from level.tasks

    def task(self, name: str) -> Any:
        """Return the task called ``name``.

        Raises:
            UnknownNameError: no such task (the known names are listed).
        """
        for task in self.tasks():
            if task.name == name:
                return task
        raise UnknownNameError("task", name, [t.name for t in self.tasks()])

    def make_controller(self, solver: str | None = None) -> Any:
        """Build a :class:`~uvms_qp.controller.Controller` for this scenario's stack.

        The controller gets the scenario's ``dt``, ``metric``, ``strict`` and ``deadline``.

        Args:
            solver: Override of the scenario's solver.
        """
        from ..controller import Controller

        return Controller(
            self.model, self.stack, solver=solver or self.solver, dt=self.dt, metric=self.metric,
            strict=self.strict, deadline=self.deadline,
        )

    @classmethod
    def build(
        cls,
        model: Any,
        stack: Any,
        q0: Any,
        *,
        dt: float,
        duration: float,
        solver: str = "daqp",
        metric: Any = None,
        events: list[Event] | None = None,
        current: ConstantCurrent | None = None,
        integrator: Integrator | None = None,
        trajectories: dict[str, Trajectory] | None = None,
        phases: list[Phase] | None = None,
        tracking: str | None = None,
        name: str = "custom",
        description: str = "",
        strict: bool = False,
        deadline: float | None = None,
    ) -> Scenario:
        """Assemble a scenario in code (no file): the stack is bound to ``model`` here.

        Args:
            model: The model.
            stack: A :class:`~uvms_qp.stack.Stack`.
            q0: Initial configuration (nq,) (checked by ``model.check_configuration``).
            dt: Control period [s].
            duration: Simulated time [s].
            solver: Solver name.
            metric: Diagonal metric W (nv,) or None.
            events: Run-time parameter changes.
            current: Optional constant current.
            integrator: Default: explicit Euler, passive attitude held, with ``current``.
            trajectories: Named trajectories (informative; tasks hold their own).
            phases: Time windows with their own metrics.
            tracking: Task whose target is the tool reference of the metrics; default: the first
                task with a ``target`` method and a ``frame``.
            name: Scenario name.
            description: Free text.
            strict: Raise instead of degrading when no back-end solves a step.
            deadline: Wall-time budget of one controller step [s], or None.

        Raises:
            InputError: invalid dt/duration/q0/deadline, or any error of the stack or controller.
        """
        from .._validation import as_scalar

        dt = as_scalar(dt, "dt", positive=True)
        duration = as_scalar(duration, "duration", positive=True)
        q0 = np.asarray(model.check_configuration(q0), dtype=np.float64)
        stack.bind(model)
        scenario = cls(
            name=name,
            description=description,
            model=model,
            q0=q0,
            stack=stack,
            constraints=list(stack.constraints),
            trajectories=dict(trajectories or {}),
            solver=solver,
            metric=None if metric is None else np.asarray(metric, dtype=np.float64),
            dt=dt,
            duration=duration,
            events=sorted(events or [], key=lambda e: e.time),
            current=current,
            integrator=integrator or Integrator(model, current=current),
            schemes=["hqp"],
            tracking=tracking,
            phases=list(phases or []),
            strict=bool(strict),
            deadline=None if deadline is None else as_scalar(deadline, "deadline", positive=True),
        )
        if scenario.tracking is None:
            for task in scenario.tasks():
                if callable(getattr(task, "target", None)) and hasattr(task, "frame"):
                    scenario.tracking = task.name
                    break
        for event in scenario.events:
            scenario.task(event.task)  # raises on an unknown task name
        scenario.make_controller()  # validates solver, metric and stack now
        return scenario

    def rebuild(self) -> Scenario:
        """Return a fresh scenario from the same data (new tasks, no event applied).

        Raises:
            InputError: the scenario was built in code (no file data to rebuild from).
        """
        if not self.data:
            raise InputError(f"scenario {self.name!r} was built in code; it cannot be rebuilt")
        return scenario_from_dict(self.data, source=self.source, name=self.name)


# ----------------------------------------------------------------------------------------------
# Locating scenarios


def bundled_scenarios() -> list[str]:
    """Names of the scenarios shipped with the package (``uvms-qp run NAME``)."""
    root = resources.files(_SCENARIO_PACKAGE)
    return sorted(
        entry.name.removesuffix(".toml") for entry in root.iterdir() if entry.name.endswith(".toml")
    )


def resolve_scenario(source: str | Path) -> Path:
    """Return the file of a scenario given as a path or as a bundled scenario name.

    Raises:
        ConfigError: neither an existing file nor a bundled name (bundled names are listed).
    """
    if not isinstance(source, str | Path):
        raise ConfigError(f"scenario: expected a file path or a bundled scenario name, "
                          f"got {type(source).__name__}")
    path = Path(source)
    if path.is_file():
        return path
    name = str(source)
    if path.suffix != ".toml" and "/" not in name and "\\" not in name:
        candidate = resources.files(_SCENARIO_PACKAGE).joinpath(f"{name}.toml")
        if candidate.is_file():
            return Path(str(candidate))
        listing = ", ".join(bundled_scenarios()) or "(none)"
        raise ConfigError(
            f"unknown scenario {name!r}: not a file and not a bundled scenario; "
            f"bundled scenarios: {listing}"
        )
    raise ConfigError(f"scenario file not found: {path}")


def load_scenario(source: str | Path) -> Scenario:
    """Load and validate a scenario file or bundled scenario.

    Args:
        source: Path of a TOML file, or the name of a bundled scenario (``"bluerov2_demo"``).

    Raises:
        ConfigError: the file is missing or malformed, or any field is invalid (path in message).
    """
    path = resolve_scenario(source)
    data = read_toml(path)
    return scenario_from_dict(data, source=path, name=path.stem)


# ----------------------------------------------------------------------------------------------
# Building


def _registries() -> tuple[Mapping[str, type], Mapping[str, type]]:
    from ..constraints import CONSTRAINT_TYPES
    from ..tasks import TASK_TYPES

    return TASK_TYPES, CONSTRAINT_TYPES


def _lookup_type(table: Table, registry: Mapping[str, type], kind: str) -> type:
    type_name = str(table.take_str("type", required=True))
    if type_name not in registry:
        known = ", ".join(sorted(registry))
        raise ConfigError(
            f"unknown {kind} type {type_name!r}; known {kind} types: {known}", table.at("type")
        )
    return registry[type_name]


def _load_model(table: Table) -> Any:
    from ..model import bundled_models, load_model

    name = str(table.take_str("model", required=True))
    try:
        return load_model(name)
    except UnknownNameError as exc:
        raise ConfigError(
            f"unknown model {name!r}; bundled models: {', '.join(bundled_models())}",
            table.at("model"),
        ) from exc
    except UvmsQpError as exc:
        raise ConfigError(str(exc), table.at("model")) from exc


def _initial_configuration(table: Table | None, model: Any) -> FloatArray:
    eta0, joints0 = model.split(model.neutral())
    eta = np.array(eta0, dtype=np.float64)
    joints = np.array(joints0, dtype=np.float64)
    if table is not None:
        eta_list = table.take_numbers("eta", size=int(model.eta_size))
        joint_list = table.take_numbers("joints", size=int(model.n_joints))
        table.finish()
        if eta_list is not None:
            eta = np.array(eta_list)
        if joint_list is not None:
            joints = np.array(joint_list)
            lower = np.asarray(model.joint_lower)
            upper = np.asarray(model.joint_upper)
            for i, value in enumerate(joints):
                if not lower[i] <= value <= upper[i]:
                    raise ConfigError(
                        f"{value:g} rad is outside the limits of joint "
                        f"{model.joint_names[i]!r} [{lower[i]:g}, {upper[i]:g}]",
                        join(table.at("joints"), i),
                    )
    path = table.path if table is not None else "initial"
    try:
        return np.asarray(model.configuration(eta, joints), dtype=np.float64)
    except UvmsQpError as exc:
        raise ConfigError(str(exc), path) from exc


def _build_current(table: Table | None) -> ConstantCurrent | None:
    if table is None:
        return None
    direction = table.take_number("direction", required=True)
    speed = table.take_number("speed", 0.0, nonnegative=True)
    drift = table.take_number("drift", 0.0, minimum=0.0, maximum=1.0)
    table.finish()
    return ConstantCurrent(direction, speed, drift)  # type: ignore[arg-type]


def _build_trajectory(table: Table) -> Trajectory:
    cls = _lookup_type(table, TRAJECTORY_TYPES, "trajectory")
    return construct(cls, table, kind="trajectory")  # type: ignore[no-any-return]


class _TaskResolver:
    """Resolve scenario references: ``trajectory = "name"`` and ``heading = "current"``."""

    def __init__(
        self, trajectories: dict[str, Trajectory], current: ConstantCurrent | None
    ) -> None:
        self.trajectories = trajectories
        self.current = current

    def __call__(self, key: str, hint: Any, value: Any, path: str) -> Any:
        if key == "trajectory":
            if isinstance(value, str):
                if value not in self.trajectories:
                    known = ", ".join(sorted(self.trajectories)) or "(none defined)"
                    raise ConfigError(
                        f"unknown trajectory {value!r}; known trajectories: {known}", path
                    )
                return self.trajectories[value]
            if isinstance(value, dict):
                return _build_trajectory(Table(value, path))
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


def _bind(obj: Any, model: Any, table: Table, kwargs_source: Mapping[str, Any]) -> None:
    bind = getattr(obj, "bind", None)
    if bind is None:
        return
    try:
        bind(model)
    except (UvmsQpError, ValueError) as exc:
        parameters = list(keyword_parameters(type(obj)))
        raise config_error_from(exc, table.path, parameters, kwargs_source) from exc


def _dry_run_rows(
    cls: type, task_table: Table, resolver: _TaskResolver, model: Any, state: Any
) -> None:
    """Evaluate a scratch copy of a task once at the initial state.

    Catches what only shows when a task is evaluated (e.g. a heading never set) without touching
    the run-time state of the real task.
    """
    scratch = construct(cls, Table(dict(task_table.data), task_table.path), resolver=resolver,
                        kind="task")
    raw = dict(task_table.data)
    _bind(scratch, model, task_table, raw)
    try:
        scratch.rows(state, 0.0)
    except (UvmsQpError, ValueError) as exc:
        raise config_error_from(exc, task_table.path, list(keyword_parameters(cls)), raw) from exc


def _build_levels(
    top: Table,
    model: Any,
    task_types: Mapping[str, type],
    resolver: _TaskResolver,
    state: Any = None,
) -> tuple[list[list[Any]], dict[str, tuple[Any, Table]]]:
    levels: list[list[Any]] = []
    by_name: dict[str, tuple[Any, Table]] = {}
    level_tables = top.take_tables("levels", required=True, keys=("tasks",))
    if not level_tables:
        raise ConfigError("expected at least one level", top.at("levels"))
    for level_table in level_tables:
        task_tables = level_table.take_tables("tasks", required=True)
        level_table.finish()
        if not task_tables:
            raise ConfigError("expected at least one task in a level", level_table.at("tasks"))
        tasks = []
        for task_table in task_tables:
            cls = _lookup_type(task_table, task_types, "task")
            raw = dict(task_table.data)
            task = construct(cls, task_table, resolver=resolver, kind="task")
            if task.name in by_name:
                raise ConfigError(
                    f"duplicate task name {task.name!r} (also at {by_name[task.name][1].path}); "
                    "give each task a unique 'name'",
                    task_table.at("name"),
                )
            _bind(task, model, task_table, raw)
            if getattr(task, "has_target", True) is False:
                raise ConfigError(
                    f"task {task.name!r} has no target: give it a 'trajectory' or a fixed target "
                    "(e.g. 'position')",
                    task_table.path,
                )
            if state is not None and callable(getattr(task, "rows", None)):
                _dry_run_rows(cls, task_table, resolver, model, state)
            by_name[task.name] = (task, task_table)
            tasks.append(task)
        levels.append(tasks)
    return levels, by_name


def _build_constraints(
    top: Table, model: Any, constraint_types: Mapping[str, type]
) -> list[Any]:
    constraints = []
    for table in top.take_tables("constraints"):
        cls = _lookup_type(table, constraint_types, "constraint")
        raw = dict(table.data)
        constraint = construct(cls, table, kind="constraint")
        _bind(constraint, model, table, raw)
        constraints.append(constraint)
    return constraints


def _build_events(
    top: Table,
    duration: float,
    tasks: dict[str, tuple[Any, Table]],
    resolver: _TaskResolver,
    model: Any,
) -> list[Event]:
    events = []
    for table in top.take_tables("events", keys=("time", "task", "update")):
        time = float(table.take_number("time", required=True, minimum=0.0, maximum=duration) or 0)
        name = str(table.take_str("task", required=True))
        update_table = table.take_table("update", required=True) or Table({}, "")
        table.finish()
        if name not in tasks:
            raise ConfigError(
                f"unknown task {name!r}; known tasks: {', '.join(tasks)}", table.at("task")
            )
        task, task_table = tasks[name]
        cls = type(task)
        updatable = getattr(task, "updatable", None)
        allowed = (
            tuple(updatable()) if callable(updatable) else tuple(keyword_parameters(cls))
        )
        hints = parameter_hints(cls)
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
        _dry_run_update(cls, task_table, resolver, model, update, update_table.path)
        events.append(Event(float(time), name, update, table.path))
    events.sort(key=lambda e: e.time)
    return events


def _dry_run_update(
    cls: type,
    task_table: Table,
    resolver: _TaskResolver,
    model: Any,
    update: dict[str, Any],
    path: str,
) -> None:
    """Validate an event's update on a scratch copy of the task (its constructor's table).

    The copy is bound to ``model`` first, so checks that need the model (a 2-coordinate
    ``position`` on a spatial model, a trajectory's dimension) fail here, at the event's path,
    rather than when the event fires.
    """
    scratch = construct(cls, Table(dict(task_table.data), task_table.path), resolver=resolver,
                        kind="task")
    _bind(scratch, model, task_table, dict(task_table.data))
    method = getattr(scratch, "update", None)
    if method is None:
        raise ConfigError(f"task type {cls.__name__} has no run-time update", path)
    try:
        method(**update)
    except (UvmsQpError, ValueError, TypeError) as exc:
        raise config_error_from(exc, path, list(update), update) from exc


def _build_phases(top: Table, duration: float) -> list[Phase]:
    phases: list[Phase] = []
    for table in top.take_tables("phases", keys=("name", "start", "end")):
        name = str(table.take_str("name", required=True))
        start = float(table.take_number("start", required=True, minimum=0.0) or 0.0)
        end = float(table.take_number("end", required=True, maximum=duration) or 0.0)
        table.finish()
        if not end > start:
            raise ConfigError(f"expected end > start ({end:g} <= {start:g})", table.at("end"))
        if any(p.name == name for p in phases):
            raise ConfigError(f"duplicate phase name {name!r}", table.at("name"))
        phases.append(Phase(name, start, end))
    return phases


def _check_schemes(top: Table) -> list[str]:
    schemes = top.take_strs("schemes", ["hqp"]) or ["hqp"]
    try:
        from ..schemes import SCHEME_TYPES
    except ImportError:  # closed-form schemes not installed: names are checked when built
        known = None
    else:
        known = ["hqp", *SCHEME_TYPES]
    for i, name in enumerate(schemes):
        if known is not None and name not in known:
            raise ConfigError(
                f"unknown scheme {name!r}; known schemes: {', '.join(known)}",
                join(top.at("schemes"), i),
            )
        if name in schemes[:i]:
            raise ConfigError(f"scheme {name!r} listed twice", join(top.at("schemes"), i))
    return schemes if "hqp" in schemes else ["hqp", *schemes]


def _check_solver(table: Table) -> str:
    solver = str(table.take_str("solver", "daqp"))
    try:
        from ..hqp import available_solvers
    except ImportError:  # solver package not importable: the controller will report it
        return solver
    known = available_solvers()
    if solver not in known:
        raise ConfigError(
            f"unknown or unavailable solver {solver!r}; usable solvers: {', '.join(known)}",
            table.at("solver"),
        )
    return solver


def _tracking_task(top: Table, tasks: dict[str, tuple[Any, Table]]) -> str | None:
    name = top.take_str("tracking")
    if name is not None:
        if name not in tasks:
            raise ConfigError(
                f"unknown task {name!r}; known tasks: {', '.join(tasks)}", top.at("tracking")
            )
        return name
    for task_name, (task, _table) in tasks.items():
        if callable(getattr(task, "target", None)) and hasattr(task, "frame"):
            return task_name
    return None


def scenario_from_dict(
    data: dict[str, Any],
    *,
    source: Path | None = None,
    name: str = "scenario",
    task_types: Mapping[str, type] | None = None,
    constraint_types: Mapping[str, type] | None = None,
) -> Scenario:
    """Build a :class:`Scenario` from parsed TOML data (see ``docs/scenarios.md``).

    Args:
        data: Parsed TOML (top-level table).
        source: File the data came from (kept for messages and :meth:`Scenario.rebuild`).
        name: Default scenario name (the file stem) when the data has no ``name``.
        task_types: Task registry; default ``uvms_qp.tasks.TASK_TYPES``.
        constraint_types: Constraint registry; default ``uvms_qp.constraints.CONSTRAINT_TYPES``.

    Raises:
        ConfigError: any invalid field, with its path.
    """
    if task_types is None or constraint_types is None:
        default_tasks, default_constraints = _registries()
        task_types = task_types or default_tasks
        constraint_types = constraint_types or default_constraints
    top = Table(data, "", _TOP_KEYS)
    scenario_name = top.take_str("name", name) or name
    description = top.take_str("description", "") or ""
    model = _load_model(top)
    dt = float(top.take_number("dt", required=True, positive=True, maximum=10.0) or 0.0)
    duration = float(top.take_number("duration", required=True, positive=True) or 0.0)
    if duration / dt > MAX_STEPS:
        raise ConfigError(
            f"{duration:g} s at dt = {dt:g} s is {math.ceil(duration / dt)} steps; "
            f"at most {MAX_STEPS} are allowed",
            "duration",
        )
    solver = _check_solver(top)
    strict = top.take_bool("strict", False)
    deadline = top.take_number("deadline", None, positive=True)
    metric_list = top.take_numbers("metric", size=int(model.nv))
    metric = None
    if metric_list is not None:
        metric = np.array(metric_list)
        if np.any(metric <= 0.0):
            i = int(np.flatnonzero(metric <= 0.0)[0])
            raise ConfigError(f"expected a positive weight, got {metric[i]:g}", f"metric[{i}]")
    schemes = _check_schemes(top)
    method = top.take_str("integrator", "euler", choices=("euler", "rk4"))
    q0 = _initial_configuration(top.take_table("initial"), model)
    current = _build_current(top.take_table("current", keys=("direction", "speed", "drift")))
    passive_table = top.take_table("passive")
    passive, tau = "hold", 2.0
    if passive_table is not None:
        passive = passive_table.take_str("mode", "hold", choices=("hold", "restore")) or "hold"
        tau = float(passive_table.take_number("time_constant", 2.0, positive=True) or 2.0)
        passive_table.finish()
    integrator = Integrator(model, method, passive, tau, current)  # type: ignore[arg-type]

    trajectories: dict[str, Trajectory] = {}
    trajectory_tables = top.take_table("trajectories")
    if trajectory_tables is not None:
        for key in list(trajectory_tables.data):
            trajectory_tables.raw(key)
            trajectories[key] = _build_trajectory(
                Table(trajectory_tables.data[key], trajectory_tables.at(key))
            )
    resolver = _TaskResolver(trajectories, current)
    constraints = _build_constraints(top, model, constraint_types)
    levels, tasks = _build_levels(top, model, task_types, resolver, model.state(q0))
    events = _build_events(top, duration, tasks, resolver, model)
    tracking = _tracking_task(top, tasks)
    phases = _build_phases(top, duration)
    top.finish()

    from ..stack import Level, Stack

    try:
        stack = Stack(levels=[Level(*tasks_) for tasks_ in levels], constraints=constraints)
    except (UvmsQpError, ValueError) as exc:
        raise ConfigError(str(exc), "levels") from exc
    scenario = Scenario(
        name=scenario_name,
        description=description,
        model=model,
        q0=q0,
        stack=stack,
        constraints=list(constraints),
        trajectories=trajectories,
        solver=solver,
        metric=metric,
        dt=dt,
        duration=duration,
        events=events,
        current=current,
        integrator=integrator,
        schemes=schemes,
        tracking=tracking,
        phases=phases,
        source=source,
        data=data,
        strict=strict,
        deadline=deadline,
    )
    try:
        scenario.make_controller()
    except (UvmsQpError, ValueError) as exc:
        raise ConfigError(str(exc), "solver") from exc
    return scenario
