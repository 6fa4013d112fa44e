"""Scenarios: the frozen specification of a closed-loop run, from a TOML file or from code.

:func:`load_scenario` reads a scenario file (or a bundled scenario by name, see
:func:`bundled_scenarios`) into a :class:`Scenario`: an immutable, validated description of the
model, initial state, stack, solver, time span, schemes, events and phases. Validation is strict
and complete before anything runs: every error is a :class:`~uvms_qp.errors.ConfigError` whose
message starts with the field path (``levels[1].tasks[0].gain: expected a positive number, got
-1.0``). The file format is described in ``docs/scenarios.md``.

A scenario holds no run-time state. Each run builds its own objects from it::

    scenario = load_scenario("bluerov2_demo")
    stack = scenario.build_stack()                       # new tasks and constraints, bound
    controller = scenario.make_controller(stack=stack)   # a controller on that stack
    result = simulate(scenario, controller, stack=stack) # what simulate(scenario) does itself

:meth:`Scenario.build` assembles a scenario in code from a model and a stack (used as a template:
every run gets a copy).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..constraints import CONSTRAINT_TYPES
from ..controller import Controller
from ..errors import ConfigError, InputError, UnknownNameError, UvmsQpError
from ..hqp import available_solvers
from ..hqp.hard_set import hard_feasible
from ..model import Model, bundled_models, load_model, model_names
from ..schemes import SCHEME_TYPES, build_scheme
from ..stack import Stack
from ..tasks import TASK_TYPES
from .config import Table, did_you_mean, instantiate, join, keyword_arguments, read_toml
from .current import ConstantCurrent
from .dynamic_plant import DynamicPlant
from .integrators import Integrator
from .model_file import MODEL_KEYS, model_from_table
from .plant_config import PLANT_KEYS, SENSOR_KEYS, PlantSpec, read_plant, read_sensors
from .plants import KinematicPlant, Plant
from .sensors import MeasurementChannel, Sensors
from .stack_tables import (
    Event,
    StackTables,
    TaskResolver,
    apply_events,
    check_periods,
    read_events,
    read_stack,
    read_trajectories,
)
from .trajectories import Trajectory
from .trajectory_start import warn_far_starts

#: Most control steps a run may take (``duration / dt``, command-line overrides included).
MAX_STEPS = 2_000_000
#: Shortest and longest control period [s].
MIN_DT = 1e-6
MAX_DT = 10.0
#: Largest magnitude of an initial vehicle pose entry [m or rad].
MAX_POSE = 1e6
_SCENARIO_PACKAGE = "uvms_qp.scenarios"
#: Keys of the top-level table (``docs/scenarios.md``); a required key is reported missing only
#: when no other key is unknown, so a misspelt ``duration`` is named as the unknown key.
_TOP_KEYS = (
    "name", "description", "model", "dt", "duration", "solver", "strict", "deadline", "damping",
    "metric",
    "schemes", "scheme_options", "integrator", "initial", "current", "passive", "trajectories",
    "constraints", "levels", "events", "tracking", "phases", "plant", "sensors",
)

__all__ = [
    "MAX_STEPS",
    "Event",
    "Phase",
    "Scenario",
    "bundled_scenarios",
    "load_scenario",
    "resolve_scenario",
    "scenario_from_dict",
    "step_count",
]


def step_count(duration: Any, dt: float, path: str = "duration") -> int:
    """Number of control steps of a run, ``round(duration / dt)``, checked.

    Args:
        duration: Simulated time [s].
        dt: Control period [s] (already checked).
        path: Field or option named in messages (``"duration"``, ``"--duration"``).

    Raises:
        ConfigError: ``duration`` is not a positive finite number, is shorter than one control
            period, or asks for more than :data:`MAX_STEPS` steps.
    """
    if (not isinstance(duration, int | float) or isinstance(duration, bool)
            or not math.isfinite(duration) or not duration > 0.0):
        raise ConfigError(f"expected a positive number of seconds, got {duration!r}", path)
    ratio = duration / dt  # inf when the quotient overflows
    if not ratio <= MAX_STEPS + 0.5:
        count = f"{ratio:.4g}" if math.isfinite(ratio) else "over 1e308"
        raise ConfigError(f"{duration:g} s at dt = {dt:g} s is {count} steps; at most "
                          f"{MAX_STEPS} are allowed", path)
    if ratio < 1.0 - 1e-9:
        raise ConfigError(f"{duration:g} s is shorter than one control period "
                          f"(dt = {dt:g} s)", path)
    return max(1, round(ratio))


@dataclass(frozen=True)
class Phase:
    """A named time window [s] whose metrics are reported separately in ``results.json``."""

    name: str
    start: float
    end: float


def _read_only(array: Any) -> FloatArray:
    out = np.array(array, dtype=np.float64)
    out.flags.writeable = False
    return out


@dataclass(frozen=True, eq=False)
class Scenario:
    """The frozen specification of a closed-loop run.

    Nothing here changes during a run: :meth:`build_stack` and :meth:`make_controller` build the
    objects of each run.

    Attributes:
        name: Scenario name.
        description: Free text.
        model: The :class:`~uvms_qp.model.Model`.
        q0: Initial configuration (nq,), read-only.
        dt: Control period [s].
        duration: Simulated time [s].
        solver: Solver name (``"daqp"``, ``"cascade:<backend>"``, ...).
        metric: Diagonal metric W (nv,) of the final minimum-norm regularisation (read-only), or
            None.
        strict: The controller raises :class:`~uvms_qp.errors.NoSolutionFound` instead of
            degrading when no back-end returns a verified solution (``docs/reliability.md``).
        deadline: Wall-time budget of one controller step [s], or None for none.
        damping: The controller's damping threshold of the levels that set none, or None for
            the library's (:data:`uvms_qp.hqp.damping.DEFAULT_THRESHOLD`).
        schemes: Schemes to compare (``"hqp"`` first unless listed elsewhere).
        listed_schemes: The schemes as the file (or the caller) listed them, ``"hqp"`` only if
            listed: what a message's ``schemes[i]`` counts (:meth:`scheme_path`).
        scheme_options: Keyword arguments of each listed closed-form scheme, by scheme name.
        integrator: The configured :class:`~uvms_qp.sim.integrators.Integrator` (stateless).
        current: Optional constant current.
        trajectories: Named trajectories of the file (stateless).
        events: Run-time parameter changes, sorted by time.
        phases: Named time windows with their own metrics.
        tracking: Name of the task whose target is the tool reference in the metrics, or None.
        tracking_trajectory: The tool reference the closed-form schemes follow: the tracking
            task's trajectory (in code: the only one of ``trajectories``), else None.
        task_names: Names of the stack's tasks per level, highest priority first.
        source: File the scenario came from, when any.
        stack_source: Returns a new, unbound stack (the checked tables of a file, or copies of a
            stack given in code); use :meth:`build_stack`.
    """

    name: str
    description: str
    model: Model
    q0: FloatArray
    dt: float
    duration: float
    solver: str
    metric: FloatArray | None
    strict: bool
    deadline: float | None
    schemes: tuple[str, ...]
    scheme_options: Mapping[str, Mapping[str, Any]]
    integrator: Integrator
    current: ConstantCurrent | None
    trajectories: Mapping[str, Trajectory]
    events: tuple[Event, ...]
    phases: tuple[Phase, ...]
    tracking: str | None
    tracking_trajectory: Trajectory | None
    task_names: tuple[tuple[str, ...], ...]
    source: Path | None
    stack_source: Callable[[], Stack] = field(repr=False)
    damping: float | None = None
    plant: PlantSpec = field(default_factory=PlantSpec)
    sensors: Sensors | None = None
    listed_schemes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "q0", _read_only(self.q0))
        if self.metric is not None:
            object.__setattr__(self, "metric", _read_only(self.metric))
        object.__setattr__(self, "schemes", tuple(self.schemes))
        object.__setattr__(self, "listed_schemes", tuple(self.listed_schemes))
        object.__setattr__(self, "scheme_options", MappingProxyType(
            {k: MappingProxyType(dict(v)) for k, v in self.scheme_options.items()}))
        object.__setattr__(self, "trajectories", MappingProxyType(dict(self.trajectories)))
        object.__setattr__(self, "events", tuple(sorted(self.events, key=lambda e: e.time)))
        object.__setattr__(self, "phases", tuple(self.phases))

    def scheme_path(self, name: str) -> str:
        """Where scheme ``name`` is listed, for messages: ``schemes[i]`` of the file's list."""
        if name in self.listed_schemes:
            return join("schemes", self.listed_schemes.index(name))
        return "schemes"

    @property
    def steps(self) -> int:
        """Number of control steps, ``round(duration / dt)``."""
        return step_count(self.duration, self.dt)

    def build_stack(self) -> Stack:
        """A new stack of this scenario (new task and constraint objects), bound to the model."""
        return self.stack_source().bind(self.model)

    def make_controller(self, solver: str | None = None, *, stack: Stack | None = None
                        ) -> Controller:
        """A :class:`~uvms_qp.controller.Controller` with this scenario's settings.

        The controller gets the scenario's ``dt``, ``metric``, ``strict``, ``deadline`` and
        ``damping``, and arm-vehicle coordination when the plant is dynamic and its
        ``[plant]`` table asks for it.

        Args:
            solver: Override of the scenario's solver.
            stack: The stack to control (default: a new one, :meth:`build_stack`). Pass the
                stack whose tasks the run's events update.
        """
        return Controller(
            self.model, self.build_stack() if stack is None else stack,
            solver=solver or self.solver, dt=self.dt, metric=self.metric, strict=self.strict,
            deadline=self.deadline,
            coordination=self.plant.kind == "dynamic" and self.plant.coordination,
            **({} if self.damping is None else {"damping": float(self.damping)}),  # type: ignore[arg-type]
        )

    def make_plant(self, sensors: MeasurementChannel | None = None) -> Plant:
        """A new plant for one run: :attr:`plant` ``kind`` decides kinematic or dynamic.

        Args:
            sensors: The run's measurement channel (the velocity the dynamic plant's loop
                reads), or None for exact measurements.
        """
        if self.plant.kind == "kinematic":
            return KinematicPlant(self.integrator, self.dt)
        return DynamicPlant(self.model, self.plant, self.dt, self.current, sensors)

    def with_plant(self, kind: str, path: str = "plant") -> Scenario:
        """This scenario on another plant kind (``"kinematic"`` or ``"dynamic"``).

        The dynamic plant takes the scenario's ``[plant]`` settings, or the defaults of the
        model's parameter set when it has none.

        Raises:
            ConfigError: at ``path``: an unknown kind, or a model without dynamic data (the
                message names what is missing).
        """
        try:
            spec = self.plant.as_kind(kind, self.model)
        except UvmsQpError as exc:
            raise ConfigError(str(exc), path) from exc
        scenario = dataclasses.replace(self, plant=spec)
        scenario._check_plant(path)
        return scenario

    def _check_plant(self, path: str = "plant") -> None:
        """Build the dynamic plant once (when it has parameters), so that bad settings fail now.

        Checks that the parameters describe the model (a body per joint), that the thrusters can
        produce every DOF the vehicle actuates, and that the servo period divides the control
        period and the physics step the servo period.

        Raises:
            ConfigError: at ``path``, with the reason.
        """
        if self.plant.parameters is None:
            return
        try:
            DynamicPlant(self.model, self.plant, self.dt, self.current)
        except UvmsQpError as exc:
            raise ConfigError(str(exc), path) from exc

    def with_duration(self, duration: Any, path: str = "duration") -> Scenario:
        """This scenario with another simulated time [s] (same step cap).

        Raises:
            ConfigError: at ``path`` (see :func:`step_count`).
        """
        step_count(duration, self.dt, path)
        return dataclasses.replace(self, duration=float(duration))

    @classmethod
    def build(
        cls,
        model: Model,
        stack: Stack | Callable[[], Stack],
        q0: Any,
        *,
        dt: float,
        duration: float,
        solver: str = "daqp",
        metric: Any = None,
        events: Sequence[Event] | None = None,
        current: ConstantCurrent | None = None,
        integrator: Integrator | None = None,
        trajectories: Mapping[str, Trajectory] | None = None,
        phases: Sequence[Phase] | None = None,
        tracking: str | None = None,
        name: str = "custom",
        description: str = "",
        strict: bool = False,
        deadline: float | None = None,
        damping: float | None = None,
        schemes: Sequence[str] = ("hqp",),
        scheme_options: Mapping[str, Mapping[str, Any]] | None = None,
        plant: PlantSpec | None = None,
        sensors: Sensors | None = None,
    ) -> Scenario:
        """Assemble a scenario in code (no file), validated as a file would be.

        Args:
            model: The model.
            stack: A :class:`~uvms_qp.stack.Stack` (copied now; each run gets its own copy) or a
                function returning a new one.
            q0: Initial configuration (nq,) (checked by ``model.check_configuration``).
            dt: Control period [s].
            duration: Simulated time [s].
            solver: Solver name.
            metric: Diagonal metric W (nv,) or None.
            events: Run-time parameter changes (each applied once to a check stack here).
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
            damping: Damping threshold of the controller's levels (None: the library's).
            schemes: Schemes ``compare`` runs (``"hqp"`` is the stack).
            scheme_options: Keyword arguments of listed closed-form schemes, by scheme name.
            plant: What the run drives (:class:`~uvms_qp.sim.plant_config.PlantSpec`); default
                the kinematic plant.
            sensors: Noise and delay of what the controller measures; default exact.

        Raises:
            InputError: invalid dt/duration/q0/deadline, an event naming an unknown task
                (:class:`~uvms_qp.errors.UnknownNameError`) or carrying an update its task
                rejects, or any error of the stack, schemes or controller.

        Warns:
            ScenarioWarning: a trajectory starts away from the frame it moves
                (:mod:`uvms_qp.sim.trajectory_start`).
        """
        dt = _check_dt(as_scalar(dt, "dt", positive=True), "dt")
        duration = as_scalar(duration, "duration", positive=True)
        step_count(duration, dt)
        q0 = model.check_configuration(q0)
        if isinstance(stack, Stack):
            # copies of a copy taken now: later changes to the caller's stack do not leak in
            source: Callable[[], Stack] = stack.copy().copy
        elif callable(stack):
            source = stack
        else:
            raise InputError(f"stack: expected a Stack or a function returning one, got "
                             f"{type(stack).__name__}")
        check = source()
        if not isinstance(check, Stack):
            raise InputError(f"stack: the function returned {type(check).__name__}, not a Stack")
        check.bind(model)
        known = [task.name for task in check.tasks]
        given = list(events or [])
        for i, event in enumerate(given):
            if event.task not in known:
                raise UnknownNameError("task", event.task, known)
            if not event.path:
                given[i] = dataclasses.replace(event, path=f"events[{i}].update")
        ordered = sorted(given, key=lambda e: e.time)
        names = _check_scheme_names(list(schemes), "schemes")
        options = {
            key: _scheme_keywords(key, Table(dict(value), join("scheme_options", key)), names)
            for key, value in (scheme_options or {}).items()
        }
        scenario = cls(
            name=name,
            description=description,
            model=model,
            q0=q0,
            dt=dt,
            duration=duration,
            solver=solver,
            metric=None if metric is None else as_vector(metric, "metric", model.nv,
                                                         positive=True),
            strict=bool(strict),
            deadline=None if deadline is None else as_scalar(deadline, "deadline", positive=True),
            damping=None if damping is None else as_scalar(damping, "damping", nonnegative=True),
            schemes=names,
            listed_schemes=tuple(schemes),
            scheme_options=options,
            integrator=integrator or Integrator(model, current=current),
            current=current,
            trajectories=dict(trajectories or {}),
            events=tuple(ordered),
            phases=tuple(phases or ()),
            tracking=tracking if tracking is not None else _default_tracking(check),
            tracking_trajectory=_only(trajectories or {}),
            task_names=tuple(level.names for level in check.levels),
            source=None,
            stack_source=source,
            plant=plant or PlantSpec(),
            sensors=sensors,
        )
        check.check_period(scenario.dt)  # the events are then checked against the period
        warn_far_starts(check, model.state(q0))  # before the events change the targets
        scenario._check_objects(check)
        scenario._check_hard_set(scenario.make_controller(stack=check))
        return scenario

    def _check_hard_set(self, controller: Controller) -> None:
        """Refuse hard constraints that admit no command at ``q0`` (every step would fail).

        ``controller`` is one built on a stack of this scenario (the events change tasks only,
        never the constraints that make the hard set). The message names the constraints in
        conflict: those without any one of which there is room (one LP each); all of them when
        no single one is to blame.

        Raises:
            ConfigError: at ``constraints``, naming the constraints.
        """
        state = self.model.state(self.q0)
        if hard_feasible(controller.assembler.fill(state, 0.0)):
            return
        stack, blamed = controller.stack, []
        for c in stack.constraints:
            others = [o for o in stack.constraints if o is not c]
            trial = self.make_controller(stack=Stack(levels=stack.levels, constraints=others))
            if hard_feasible(trial.assembler.fill(state, 0.0)):
                blamed.append(c.name)
        names = ", ".join(blamed or [c.name for c in stack.constraints])
        raise ConfigError(
            f"the hard constraints {names} admit no command together at the initial "
            "configuration: every step would end hard_infeasible; check the sides of their rows "
            "against their bounds", "constraints")

    def _check_objects(self, stack: Stack) -> None:
        """Build each closed-form scheme once, then apply the events to ``stack``.

        ``stack`` is the bound stack the scenario is checked on; the schemes read it before the
        events change it (the payload force of a paper scheme is the task's initial one).
        """
        for name in self.schemes:
            if name != "hqp":
                build_scheme(name, self, self.scheme_path(name), stack=stack)
        apply_events(self.events, stack, self.dt)


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
        known = bundled_scenarios()
        close = difflib.get_close_matches(name, known, n=1, cutoff=0.6)
        hint = f" (did you mean {close[0]!r}?)" if close else ""
        raise ConfigError(
            f"unknown scenario {name!r}{hint}: not a file and not a bundled scenario; "
            f"bundled scenarios: {', '.join(known) or '(none)'}"
        )
    raise ConfigError(f"scenario file not found: {path}")


def load_scenario(source: str | Path) -> Scenario:
    """Load and validate a scenario file or bundled scenario.

    Args:
        source: Path of a TOML file, or the name of a bundled scenario (``"bluerov2_demo"``).

    Raises:
        ConfigError: the file is missing or malformed, or any field is invalid (path in message).

    Warns:
        ScenarioWarning: a trajectory starts away from the frame it moves
            (:mod:`uvms_qp.sim.trajectory_start`).
    """
    path = resolve_scenario(source)
    data = read_toml(path)
    return scenario_from_dict(data, source=path, name=path.stem)


# ----------------------------------------------------------------------------------------------
# Reading the top-level table


def _check_dt(dt: float, path: str) -> float:
    if not MIN_DT <= dt <= MAX_DT:
        raise ConfigError(f"expected a control period in [{MIN_DT:g}, {MAX_DT:g}] s, got {dt:g}",
                          path)
    return dt


def _read_model(top: Table, base: Path) -> Model:
    value = top.raw("model", required=True)
    if isinstance(value, dict):
        return model_from_table(Table(value, top.at("model"), MODEL_KEYS), base)
    name = str(top.take_str("model", required=True))
    try:
        return load_model(name)
    except UnknownNameError as exc:
        others = [n for n in model_names() if n not in bundled_models()]
        extra = f"; other known models: {', '.join(others)}" if others else ""
        raise ConfigError(
            f"unknown model {name!r}; bundled models: {', '.join(bundled_models())}{extra}; "
            "a [model] table builds one from a URDF file or a DH table",
            top.at("model"),
        ) from exc
    except UvmsQpError as exc:
        raise ConfigError(str(exc), top.at("model")) from exc


def _initial_configuration(table: Table | None, model: Model) -> FloatArray:
    """``q0``: the model's home (vehicle at the origin, home joint angles), or ``[initial]``."""
    eta0, joints0 = model.split(model.home())
    eta = np.array(eta0, dtype=np.float64)
    joints = np.array(joints0, dtype=np.float64)
    path = "initial"
    if table is not None:
        path = table.path
        eta_list = table.take_numbers("eta", size=int(model.eta_size))
        joint_list = table.take_numbers("joints", size=int(model.n_joints))
        table.finish()
        if eta_list is not None:
            eta = np.array(eta_list)
            path = table.at("eta")
            for i, value in enumerate(eta):
                if abs(value) > MAX_POSE:
                    raise ConfigError(f"expected a magnitude <= {MAX_POSE:g} [m or rad], "
                                      f"got {value:g}", join(path, i))
        if joint_list is not None:
            joints = np.array(joint_list)
            outside = model.joint_outside_limits(joints)
            if outside is not None:
                raise ConfigError(outside[1], join(table.at("joints"), outside[0]))
    try:
        return model.check_configuration(model.configuration(eta, joints))
    except UvmsQpError as exc:
        raise ConfigError(str(exc), path) from exc


def _read_current(table: Table | None) -> ConstantCurrent | None:
    if table is None:
        return None
    direction = table.take_number("direction", required=True)
    speed = table.take_number("speed", 0.0, nonnegative=True)
    drift = table.take_number("drift", 0.0, minimum=0.0, maximum=1.0)
    oscillation = table.take_number("oscillation", 0.0, nonnegative=True)
    period = table.take_number("period", 60.0, positive=True)
    table.finish()
    return ConstantCurrent(direction, speed, drift, oscillation, period)  # type: ignore[arg-type]


def _read_phases(top: Table, duration: float) -> list[Phase]:
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


def _check_scheme_names(schemes: list[str], path: str) -> tuple[str, ...]:
    known = ["hqp", *SCHEME_TYPES]
    for i, name in enumerate(schemes):
        if name not in known:
            raise ConfigError(
                f"unknown scheme {name!r}; known schemes: {', '.join(known)}"
                f"{did_you_mean(str(name), known)}",
                join(path, i),
            )
        if name in schemes[:i]:
            raise ConfigError(f"scheme {name!r} listed twice", join(path, i))
    return tuple(schemes if "hqp" in schemes else ["hqp", *schemes])


def _scheme_keywords(name: str, table: Table, schemes: Sequence[str]) -> dict[str, Any]:
    """The checked keyword arguments of ``[scheme_options.<name>]``."""
    listed = [s for s in schemes if s != "hqp"]
    if name == "hqp":
        raise ConfigError("the hqp stack takes no scheme options; its settings are the "
                          "top-level keys (solver, metric, strict, deadline)", table.path)
    if name not in listed:
        raise ConfigError(
            f"options for scheme {name!r}, which 'schemes' does not list; listed schemes: "
            f"{', '.join(listed) or '(none)'}{did_you_mean(name, listed)}",
            table.path,
        )
    cls = SCHEME_TYPES[name]
    kwargs = keyword_arguments(cls, table, skip=(), exclude=("name",),
                               label=f"scheme {name!r}")
    instantiate(cls, kwargs, table.path)  # the constructor's own checks, at this path
    return kwargs


def _read_scheme_options(top: Table, schemes: Sequence[str]) -> dict[str, dict[str, Any]]:
    table = top.take_table("scheme_options")
    if table is None:
        return {}
    options = {}
    for key in list(table.data):
        options[key] = _scheme_keywords(key, Table(table.raw(key), table.at(key)), schemes)
    return options


def _check_solver(table: Table) -> str:
    solver = str(table.take_str("solver", "daqp"))
    known = available_solvers()
    if solver not in known:
        raise ConfigError(
            f"unknown or unavailable solver {solver!r}; usable solvers: {', '.join(known)}",
            table.at("solver"),
        )
    return solver


def _default_tracking(stack: Stack) -> str | None:
    """The first task with a ``target`` method and a ``frame``, or None."""
    for task in stack.tasks:
        if callable(getattr(task, "target", None)) and hasattr(task, "frame"):
            return task.name
    return None


def _only(trajectories: Mapping[str, Trajectory]) -> Trajectory | None:
    return next(iter(trajectories.values())) if len(trajectories) == 1 else None


def _tracking(top: Table, stack: Stack, tables: StackTables
              ) -> tuple[str | None, Trajectory | None]:
    """The tracking task (``tracking`` key or the default) and its trajectory."""
    names = [task.name for task in stack.tasks]
    name = top.take_str("tracking")
    if name is not None and name not in names:
        raise ConfigError(
            f"unknown task {name!r}; known tasks: {', '.join(names)}", top.at("tracking")
        )
    if name is None:
        name = _default_tracking(stack)
    for level, items in zip(stack.levels, tables.levels, strict=True):
        for task, item in zip(level.tasks, items, strict=True):
            reference = item.kwargs.get("trajectory")
            if task.name == name and isinstance(reference, Trajectory):
                return name, reference
    return name, None


def scenario_from_dict(
    data: dict[str, Any],
    *,
    source: Path | None = None,
    name: str = "scenario",
    task_types: Mapping[str, type] | None = None,
    constraint_types: Mapping[str, type] | None = None,
) -> Scenario:
    """Read and validate parsed TOML data into a :class:`Scenario` (see ``docs/scenarios.md``).

    The tables are checked once: each task and constraint is built and bound once, evaluated at
    the initial state, the events are applied to it in time order, and each closed-form scheme
    and the controller are built once. The scenario keeps the checked tables, not these objects.

    Args:
        data: Parsed TOML (top-level table).
        source: File the data came from (a relative URDF path is relative to its folder).
        name: Default scenario name (the file stem) when the data has no ``name``.
        task_types: Task registry; default ``uvms_qp.tasks.TASK_TYPES``.
        constraint_types: Constraint registry; default ``uvms_qp.constraints.CONSTRAINT_TYPES``.

    Raises:
        ConfigError: any invalid field, with its path.
    """
    top = Table(data, "", _TOP_KEYS)
    scenario_name = top.take_str("name", name) or name
    description = top.take_str("description", "") or ""
    model = _read_model(top, source.parent if source is not None else Path.cwd())
    dt = float(top.take_number("dt", required=True, positive=True) or 0.0)
    dt = _check_dt(dt, top.at("dt"))
    duration = float(top.take_number("duration", required=True, positive=True) or 0.0)
    step_count(duration, dt, top.at("duration"))
    solver = _check_solver(top)
    strict = top.take_bool("strict", False)
    deadline = top.take_number("deadline", None, positive=True)
    damping = top.take_number("damping", None, nonnegative=True)
    metric_list = top.take_numbers("metric", size=int(model.nv))
    metric = None
    if metric_list is not None:
        metric = np.array(metric_list)
        if np.any(metric <= 0.0):
            i = int(np.flatnonzero(metric <= 0.0)[0])
            raise ConfigError(f"expected a positive weight, got {metric[i]:g}", f"metric[{i}]")
    listed = top.take_strs("schemes", ["hqp"]) or ["hqp"]
    schemes = _check_scheme_names(listed, top.at("schemes"))
    scheme_options = _read_scheme_options(top, schemes)
    method = top.take_str("integrator", "euler", choices=("euler", "rk4"))
    q0 = _initial_configuration(top.take_table("initial"), model)
    current = _read_current(top.take_table(
        "current", keys=("direction", "speed", "drift", "oscillation", "period")))
    passive_table = top.take_table("passive")
    passive, tau = "hold", 2.0
    if passive_table is not None:
        passive = passive_table.take_str("mode", "hold", choices=("hold", "restore")) or "hold"
        tau = float(passive_table.take_number("time_constant", 2.0, positive=True) or 2.0)
        passive_table.finish()
    integrator = Integrator(model, method, passive, tau, current)  # type: ignore[arg-type]
    if passive_table is not None and not integrator.passive_angles:
        why = {"planar": "a planar vehicle has no roll or pitch",
               "fixed": "its arm is on a fixed base"}.get(
            model.vehicle_kind, "its vehicle actuates roll and pitch, p and q")
        raise ConfigError(f"model {model.name!r} has no passive roll or pitch ({why}), so "
                          "[passive] would have no effect; remove it", top.at("passive"))

    trajectories = read_trajectories(top.take_table("trajectories"))
    resolver = TaskResolver(trajectories, current)
    tables, stack = read_stack(top, model, resolver, task_types or TASK_TYPES,
                               constraint_types or CONSTRAINT_TYPES, model.state(q0))
    events = read_events(top, duration, stack, resolver)
    tracking, reference = _tracking(top, stack, tables)
    phases = _read_phases(top, duration)
    base = source.parent if source is not None else Path.cwd()
    plant = read_plant(top.take_table("plant", keys=PLANT_KEYS), model, base, dt, duration)
    sensors = read_sensors(top.take_table("sensors", keys=SENSOR_KEYS))
    top.finish()
    scenario = Scenario(
        name=scenario_name,
        description=description,
        model=model,
        q0=q0,
        dt=dt,
        duration=duration,
        solver=solver,
        metric=metric,
        strict=strict,
        deadline=deadline,
        schemes=schemes,
        listed_schemes=tuple(listed),
        scheme_options=scheme_options,
        integrator=integrator,
        current=current,
        trajectories=trajectories,
        events=events,
        phases=tuple(phases),
        tracking=tracking,
        tracking_trajectory=reference,
        task_names=tuple(level.names for level in stack.levels),
        source=source,
        stack_source=tables,
        damping=damping,
        plant=plant,
        sensors=sensors,
    )
    check_periods(tables, stack, dt)
    scenario._check_plant()
    warn_far_starts(stack, model.state(q0))  # before the events change the targets
    scenario._check_objects(stack)
    try:
        controller = scenario.make_controller(stack=stack)
    except (UvmsQpError, ValueError) as exc:
        raise ConfigError(str(exc), "solver") from exc
    scenario._check_hard_set(controller)
    return scenario
