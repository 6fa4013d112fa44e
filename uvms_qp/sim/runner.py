"""Closed-loop simulation of a scenario.

Each control step ``k`` at ``t_k = k dt``:

1. apply the scenario events due at ``t_k`` (``task.update(**params)``);
2. the controller's view of the plant: the :class:`~uvms_qp.model.State` of the measured
   configuration (the true one, or what the scenario's :class:`~uvms_qp.sim.sensors.Sensors`
   make of it: noisy, late) with the measured body velocity of a dynamic plant;
3. ``zeta_k = scheme.step(state, t_k).zeta`` (the HQP controller or any scheme with the same
   ``step``/``reset`` interface); a non-finite command is counted and replaced by zero;
4. record the series (with the fallback stage that produced the command, the amount the final
   saturation clipped and whether the step missed its deadline: three plain Python values per
   step) and check the command against every hard row of the stack's constraints, recomputed
   independently of the controller;
5. the plant (:mod:`uvms_qp.sim.plants`) applies ``zeta_k`` for one period: integrated exactly
   on the configuration manifold (kinematic), or tracked by the velocity loop, thrusters and
   joint servos of a floating vehicle (dynamic).

The recorded series and the metrics are those of the true state. A dynamic plant that diverges
(:class:`~uvms_qp.errors.SimulationDiverged`) ends the run early: the result keeps every step
recorded before the failure and says why in ``stopped``.

The result keeps plain numpy arrays; :mod:`uvms_qp.sim.metrics` turns them into numbers and
:mod:`uvms_qp.sim.results` writes them to ``results.json``.
"""

from __future__ import annotations

import dataclasses
import time as _time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from ..constraints import CommandRateBounds, intersect_boxes
from ..errors import SimulationDiverged
from ..hqp import hard_violation
from ..safety import STAGES
from ..stack import Stack
from . import metrics as run_metrics
from .dynamic_metrics import dynamic_metrics
from .dynamic_metrics import phase_metrics as dynamic_phase_metrics
from .probes import Probes
from .units import joint_units, zeta_units

if TYPE_CHECKING:  # pragma: no cover
    from .scenario import Scenario

#: Runs expected to take longer than this [s] of wall time show a progress bar (when asked to).
PROGRESS_AFTER = 2.0
#: Stage recorded for a scheme whose results carry none (it has no fallback ladder).
PRIMARY_STAGE = STAGES[0]


@dataclass
class SimulationResult:
    """Recorded series of one run (N steps, N+1 states).

    Attributes:
        scenario: Scenario name.
        scheme: Scheme name (``"hqp"`` for the lexicographic QP controller).
        solver: Solver name.
        model: Model name.
        dt: Control period [s].
        steps: Number of steps N.
        time: Step times ``t_k`` (N,) [s].
        time_states: State times (N+1,) [s] (the last state follows the last step).
        zeta: Commands (N, nv) [m/s, rad/s].
        zeta_lower: Box lower bounds of the hard constraints per step (N, nv) (``-inf`` if none).
        zeta_upper: Box upper bounds per step (N, nv) (``+inf`` if none).
        q: Configurations (N+1, nq).
        eta: Vehicle poses (N+1, eta_size) [m, rad].
        joints: Joint angles (N+1, n_joints) [rad].
        vehicle_position: Vehicle origin in the world (N+1, 3) [m].
        vehicle_speed: Norm of the commanded vehicle linear body rates (N,) [m/s].
        yaw: Vehicle heading psi (N+1,) [rad], or None for a fixed base.
        ee_position: Tracked frame position (N+1, 3) [m], world frame.
        ee_rotation: Tracked frame rotation (N+1, 3, 3).
        target_position: Its target (N+1, 3) [m] (NaN where none).
        manipulability: Manipulability measure (N+1,).
        payload_moment: Payload moment F |(x_E, y_E)| (N+1,) [N m], or None without a payload task.
        payload_objective: Payload objective (x_E^2 + y_E^2) F of Wang et al. (2017), Eq. (20),
            (N+1,) [N m^2], or None.
        step_time: Controller step wall time (N,) [s].
        status: Controller status per step.
        level_residuals: Per-level residual norms (N, levels) (NaN where not reported).
        task_residuals: Per-task row-violation norm series (N,) by task name.
        task_units: Unit of each task's rows (the residual's unit).
        bound_violation: Largest hard-row violation of each command (N,).
        nan_steps: Number of non-finite commands.
        joint_lower: Joint lower limits (n_joints,) [rad].
        joint_upper: Joint upper limits (n_joints,) [rad].
        zeta_names: Names of the entries of zeta.
        joint_names: Joint names.
        heading: Target heading of a current-alignment task or the current [rad], or None.
        events: Events applied (time, task, update).
        wall_time: Wall time of the whole run [s].
        phases: Scenario phases, name -> (start, end) [s].
        level_names: Label of each level (its task names).
        stage: Fallback stage that produced each command (N,) (:data:`uvms_qp.safety.STAGES`;
            ``"primary"`` on the happy path and for schemes without a fallback ladder).
        clipped: Amount the controller's final saturation removed from each command (N,)
            [m/s, rad/s] (0 for schemes that do not report it).
        deadline_missed: Whether each step overran the controller's ``deadline`` (N,).
        zeta_units: Unit of each entry of zeta (:func:`uvms_qp.sim.units.zeta_units`).
        joint_units: Unit of each joint position (``"rad"`` or ``"m"``).
        manipulability_unit: Unit of ``manipulability`` (``"m^k"`` for k position rows).
        manipulability_floor: Floor of the manipulability task per state (N+1,) (NaN while
            none), or None without a floor task.
        task_errors: Error norm of every regulated task per state (N+1,) by task name
            (:class:`~uvms_qp.sim.probes.Probes`), units in ``task_error_units``.
        task_error_units: Unit of each regulated task's error.
        command_rate_limit: Acceleration bound of each entry of zeta (nv,) [m/s^2, rad/s^2] of
            the stack's :class:`~uvms_qp.constraints.CommandRateBounds` (the tightest when
            several; ``inf`` where none), or None without them.
        command_initial: The previous command of the first step those bounds assumed (nv,)
            (zero: at rest), or None (free first step or no such bounds).
        plant: ``"kinematic"`` or ``"dynamic"`` (:mod:`uvms_qp.sim.plants`).
        dynamics: What a dynamic plant recorded
            (:class:`~uvms_qp.sim.dynamic_plant.DynamicSeries`), None for a kinematic run.
        stopped: Why the run ended early (``{"time": t [s], "step": k, "error": message}``),
            None when it ran to the end. The series then hold the steps before the failure.
        plant_settings: The plant's settings (:meth:`~uvms_qp.sim.plant_config.PlantSpec.settings`).
        sensors: The sensors' noise and delay (field name -> value), None when exact.
    """

    scenario: str
    scheme: str
    solver: str
    model: str
    dt: float
    steps: int
    time: FloatArray
    time_states: FloatArray
    zeta: FloatArray
    zeta_lower: FloatArray
    zeta_upper: FloatArray
    q: FloatArray
    eta: FloatArray
    joints: FloatArray
    vehicle_position: FloatArray
    vehicle_speed: FloatArray
    yaw: FloatArray | None
    ee_position: FloatArray
    ee_rotation: FloatArray
    target_position: FloatArray
    manipulability: FloatArray
    payload_moment: FloatArray | None
    payload_objective: FloatArray | None
    step_time: FloatArray
    status: list[str]
    level_residuals: FloatArray
    task_residuals: dict[str, FloatArray]
    task_units: dict[str, str]
    bound_violation: FloatArray
    nan_steps: int
    joint_lower: FloatArray
    joint_upper: FloatArray
    zeta_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    heading: float | None
    events: list[dict[str, Any]] = field(default_factory=list)
    wall_time: float = 0.0
    phases: dict[str, tuple[float, float]] = field(default_factory=dict)
    level_names: list[str] = field(default_factory=list)
    stage: list[str] = field(default_factory=list)
    clipped: FloatArray = field(default_factory=lambda: np.zeros(0))
    deadline_missed: list[bool] = field(default_factory=list)
    zeta_units: tuple[str, ...] = ()
    joint_units: tuple[str, ...] = ()
    manipulability_unit: str = ""
    manipulability_floor: FloatArray | None = None
    task_errors: dict[str, FloatArray] = field(default_factory=dict)
    task_error_units: dict[str, str] = field(default_factory=dict)
    command_rate_limit: FloatArray | None = None
    command_initial: FloatArray | None = None
    plant: str = "kinematic"
    dynamics: Any = None
    stopped: dict[str, Any] | None = None
    plant_settings: dict[str, Any] = field(default_factory=dict)
    sensors: dict[str, Any] | None = None

    def metrics(self) -> dict[str, Any]:
        """The run metrics (:func:`uvms_qp.sim.metrics.compute_metrics`) and the fallback ones.

        Added to the simulator's metrics: ``stage_counts`` (steps per fallback stage, in ladder
        order, stages that occurred only), ``deadline_missed_steps`` and ``clipped_max``
        [m/s, rad/s] (largest amount the final saturation removed from a command); on a dynamic
        plant, :func:`uvms_qp.sim.dynamic_metrics.dynamic_metrics`.
        """
        metrics = run_metrics.compute_metrics(self)
        metrics.update(self.fallback_metrics())
        metrics.update(dynamic_metrics(self))
        return metrics

    def fallback_metrics(self) -> dict[str, Any]:
        """``stage_counts``, ``deadline_missed_steps`` and ``clipped_max`` of the run."""
        counts: dict[str, int] = {}
        for stage in self.stage:
            counts[stage] = counts.get(stage, 0) + 1
        order = {name: i for i, name in enumerate(STAGES)}
        ordered = dict(sorted(counts.items(), key=lambda item: (order.get(item[0], len(order)),
                                                                 item[0])))
        clipped = self.clipped[np.isfinite(self.clipped)]
        return {
            "stage_counts": ordered,
            "deadline_missed_steps": int(sum(self.deadline_missed)),
            "clipped_max": float(clipped.max()) if clipped.size else 0.0,
        }

    def phase_metrics(self) -> dict[str, dict[str, Any]]:
        """Metrics of every scenario phase, by phase name."""
        return {name: {**run_metrics.phase_metrics(self, a, b), **dynamic_phase_metrics(self, a, b)}
                for name, (a, b) in self.phases.items()}


def _constraint_violation(constraints: list[Any], state: Any, dt: float, zeta: FloatArray,
                          lower: FloatArray, upper: FloatArray) -> float:
    """Largest violation by ``zeta`` of the box ``lower``/``upper`` and the constraints' hard rows.

    The box is the one :func:`~uvms_qp.constraints.intersect_boxes` gave before the step; the
    violation is :func:`uvms_qp.hqp.hard_violation` of that box and of the hard rows rebuilt
    from the constraint objects.
    """
    rows = [constraint.rows(state, dt) for constraint in constraints if constraint.rows_dim]
    if not rows:
        return hard_violation(zeta, lower, upper)
    return hard_violation(zeta, lower, upper, np.vstack([r.A for r in rows]),
                          np.concatenate([r.lower for r in rows]),
                          np.concatenate([r.upper for r in rows]))


def _measured_state(model: Any, plant: Any, channel: Any, truth: Any) -> Any:
    """The state the controller is given: the sensors' view of the plant (``truth`` if exact)."""
    nu = plant.body_velocity
    if channel is None:
        return truth if nu is None else model.state(truth.q, nu)
    q, measured = channel.state(truth.q, nu)
    if measured is not None:
        return model.state(q, measured)
    return truth if q is truth.q else model.state(q)


class _Progress:
    """A rich progress bar that appears only once a run has taken more than PROGRESS_AFTER [s]."""

    def __init__(self, total: int, label: str, enabled: bool) -> None:
        self.total = total
        self.label = label
        self.enabled = enabled
        self.start = _time.perf_counter()
        self._bar: Any = None
        self._task: Any = None

    def update(self, done: int) -> None:
        if not self.enabled or done % 20:
            return
        if self._bar is None:
            if _time.perf_counter() - self.start < PROGRESS_AFTER:
                return
            from rich.progress import Progress

            self._bar = Progress(transient=True)
            self._bar.start()
            self._task = self._bar.add_task(self.label, total=self.total)
        self._bar.update(self._task, completed=done)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.stop()


def simulate(
    scenario: Scenario,
    scheme: Any = None,
    *,
    stack: Stack | None = None,
    scheme_name: str = "hqp",
    duration: float | None = None,
    progress: bool = False,
) -> SimulationResult:
    """Run a scenario in closed loop and record the series.

    Args:
        scenario: The scenario (a frozen specification; the run builds its own objects).
        scheme: Object with ``step(state, t) -> result`` (``.zeta``, ``.status``, ``.step_time``)
            and ``reset()``; default: a controller of the scenario on ``stack``.
        stack: The run's stack: the tasks the scenario's events update and the probes read, and
            the constraints whose hard rows each command is checked against. Default: the
            scheme's own ``stack`` when it has one (a
            :class:`~uvms_qp.controller.Controller`), else a new one
            (:meth:`~uvms_qp.sim.scenario.Scenario.build_stack`). A scheme that wraps a
            controller must be given its controller's stack here.
        scheme_name: Name recorded in the results.
        duration: Override of the scenario duration [s] (same step cap as the file's).
        progress: Show a progress bar when the run takes more than a few seconds.

    Raises:
        ConfigError: a duration override that is not positive, shorter than one control period,
            or beyond the step cap.
    """
    if duration is not None:
        scenario = scenario.with_duration(duration)
    if stack is None:
        own = getattr(scheme, "stack", None)
        stack = own if isinstance(own, Stack) else scenario.build_stack()
    if scheme is None:
        scheme = scenario.make_controller(stack=stack)
    reset = getattr(scheme, "reset", None)
    if callable(reset):
        reset()
    model = scenario.model
    dt = scenario.dt
    n = scenario.steps
    nv, nq = int(model.nv), int(model.nq)
    n_levels = len(stack.levels)
    probes = Probes(scenario, stack, n + 1, getattr(scheme, "slot", None))
    constraints = list(stack.constraints)
    for constraint in constraints:  # the run starts from the constraints' initial memory
        constraint.reset()
    rate_bounds = [c for c in constraints if isinstance(c, CommandRateBounds)]
    rate_limit = (np.min([c.limits for c in rate_bounds], axis=0) if rate_bounds else None)
    initial = next((c.previous for c in rate_bounds if c.previous is not None), None)
    n_lin = sum(1 for dof in getattr(model, "actuated", ()) if dof in ("u", "v", "w"))

    time: FloatArray = np.arange(n, dtype=np.float64) * dt
    time_states: FloatArray = np.arange(n + 1, dtype=np.float64) * dt
    zeta_log = np.zeros((n, nv))
    lower_log = np.full((n, nv), -np.inf)
    upper_log = np.full((n, nv), np.inf)
    q_log = np.zeros((n + 1, nq))
    step_time = np.zeros(n)
    status: list[str] = []
    stage: list[str] = []
    clipped = np.zeros(n)
    missed: list[bool] = []
    level_res = np.full((n, n_levels), np.nan)
    task_names = [task.name for task in stack.tasks]
    task_res = {name: np.full(n, np.nan) for name in task_names}
    task_units: dict[str, str] = {
        task.name: str(getattr(task, "rate_unit", "")) for task in stack.tasks
    }
    violation = np.zeros(n)
    speed = np.zeros(n)
    nan_steps = 0
    applied: list[dict[str, Any]] = []
    pending = list(scenario.events)
    zero = np.zeros(nv)

    def rates(q: FloatArray, t: float) -> FloatArray:
        z = np.asarray(scheme.step(model.state(q), t).zeta, dtype=np.float64)
        return z if np.all(np.isfinite(z)) else zero

    bar = _Progress(n, f"{scenario.name} ({scheme_name})", progress)
    channel = scenario.sensors.channel(model, dt) if scenario.sensors is not None else None
    plant = scenario.make_plant(channel)
    plant.start(np.array(scenario.q0, dtype=np.float64))
    stopped: dict[str, Any] | None = None
    started = _time.perf_counter()
    for k in range(n):
        t = float(time[k])
        while pending and pending[0].time <= t + 1e-9:
            event = pending.pop(0)
            event.apply(stack)
            applied.append({"time": t, "task": event.task, "update": dict(event.update)})
        q = plant.q
        truth = model.state(q)
        q_log[k] = q
        probes.record(k, truth, t)
        state = _measured_state(model, plant, channel, truth)
        intersect_boxes(constraints, state, dt, lower_log[k], upper_log[k])
        result = scheme.step(state, t)
        zeta = np.asarray(result.zeta, dtype=np.float64)
        if zeta.shape != (nv,) or not np.all(np.isfinite(zeta)):
            nan_steps += 1
            zeta = zero
        zeta_log[k] = zeta
        step_time[k] = float(getattr(result, "step_time", float("nan")))
        status.append(str(getattr(result, "status", "")))
        stage.append(str(getattr(result, "stage", PRIMARY_STAGE)))
        clipped[k] = getattr(result, "clipped", 0.0)
        missed.append(bool(getattr(result, "deadline_missed", False)))
        hierarchy = getattr(result, "hierarchy", None)
        residuals = getattr(hierarchy, "level_residuals", None)
        if residuals is not None:
            count = min(len(residuals), n_levels)
            level_res[k, :count] = residuals[:count]
        for name, value in (getattr(result, "task_residuals", None) or {}).items():
            if name in task_res:
                if isinstance(value, tuple):
                    task_res[name][k] = float(value[0])
                    task_units[name] = str(value[1])
                else:
                    task_res[name][k] = float(value)
        violation[k] = _constraint_violation(
            constraints, state, dt, zeta, lower_log[k], upper_log[k]
        )
        for constraint in constraints:  # a scheme other than the controller may not tell them
            constraint.command_sent(zeta)
        speed[k] = float(np.linalg.norm(zeta[:n_lin])) if n_lin else 0.0
        try:
            plant.advance(zeta, t, rates)
        except SimulationDiverged as exc:
            stopped = {"time": float(exc.t), "step": k, "error": str(exc)}
            n = k  # the failed step's command was never realised: keep the steps before it
            break
        bar.update(k + 1)
    bar.close()
    wall = _time.perf_counter() - started
    q = plant.q if stopped is None else q_log[n]
    q_log[n] = q
    probes.record(n, model.state(q), float(time_states[n]))
    if stopped is not None:
        probes.truncate(n + 1)
        time, time_states = time[:n], time_states[: n + 1]
        zeta_log, lower_log, upper_log = zeta_log[:n], lower_log[:n], upper_log[:n]
        q_log, step_time, clipped = q_log[: n + 1], step_time[:n], clipped[:n]
        status, stage, missed = status[:n], stage[:n], missed[:n]
        level_res, violation, speed = level_res[:n], violation[:n], speed[:n]
        task_res = {name: series[:n] for name, series in task_res.items()}
    data = probes.arrays()
    return SimulationResult(
        scenario=scenario.name,
        scheme=scheme_name,
        solver=str(getattr(scheme, "solver_name", scenario.solver)),
        model=str(model.name),
        dt=dt,
        steps=n,
        time=time,
        time_states=time_states,
        zeta=zeta_log,
        zeta_lower=lower_log,
        zeta_upper=upper_log,
        q=q_log,
        eta=data["eta"],
        joints=data["joints"],
        vehicle_position=data["vehicle_position"],
        vehicle_speed=speed,
        yaw=data.get("yaw"),
        ee_position=data["ee_position"],
        ee_rotation=data["ee_rotation"],
        target_position=data["target_position"],
        manipulability=data["manipulability"],
        payload_moment=data.get("payload_moment"),
        payload_objective=data.get("payload_objective"),
        step_time=step_time,
        status=status,
        level_residuals=level_res,
        task_residuals=task_res,
        task_units=task_units,
        bound_violation=violation,
        nan_steps=nan_steps,
        joint_lower=np.asarray(model.joint_lower, dtype=np.float64),
        joint_upper=np.asarray(model.joint_upper, dtype=np.float64),
        zeta_names=tuple(model.zeta_names),
        joint_names=tuple(model.joint_names),
        heading=probes.heading,
        events=applied,
        wall_time=wall,
        phases={p.name: (p.start, p.end) for p in getattr(scenario, "phases", [])},
        level_names=[", ".join(task.name for task in level.tasks) for level in stack.levels],
        stage=stage,
        clipped=clipped,
        deadline_missed=missed,
        zeta_units=zeta_units(model),
        joint_units=joint_units(model),
        manipulability_unit=probes.manipulability_unit,
        manipulability_floor=data.get("manipulability_floor"),
        task_errors=probes.task_errors,
        task_error_units=probes.task_error_units,
        command_rate_limit=rate_limit,
        command_initial=initial,
        plant=plant.kind,
        dynamics=plant.series(n),
        stopped=stopped,
        plant_settings=plant.settings(scenario.plant),
        sensors=(None if scenario.sensors is None
                 else dataclasses.asdict(scenario.sensors)),
    )
