"""A floating UVMS under the kinematic controller: the second, dynamic layer of a run.

The controller's command ``zeta = [nu_ref (actuated vehicle rates); joint rate references]`` is
a velocity reference (the kinematic layer). Between two control ticks the dynamic layer tracks it,
multi-rate as on a real vehicle (Simetti et al. (2014), J. Field Robotics 31(3); Antonelli,
Underwater Robots, Springer):

- every servo period (``servo_rate``, 100 Hz by default): the vehicle's body-velocity loop
  (:class:`~uvms_qp.dynamics.VelocityLoop`: PI with feed-forward of the restoring wrench and of
  the damping at the reference, relative to the water when ``feedforward = "model"``) turns
  ``nu_ref - nu`` (``nu`` as the sensors read it) into a demanded body wrench, the allocation
  (:class:`~uvms_qp.dynamics.ThrustAllocator`, bounded least squares) into thruster commands
  within their limits; the arm's velocity servos take their joint rate references (clipped into
  the joints' rate limits);
- every physics step (``physics_step``): the thrusters' forces follow their commands through
  dead band and lag (:class:`~uvms_qp.dynamics.ThrusterDynamics`), and the equations of motion of
  the whole chain (:class:`~uvms_qp.dynamics.FloatingPlant`: rigid bodies, added mass, damping,
  weight and buoyancy, current, the arm's reaction) advance the true state.

A payload (``PlantSpec.payload``) is attached to the tool at the first servo tick at or after its
time. :class:`DynamicSeries` keeps what happened at every servo tick.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..dynamics import (
    DEFAULT_STEP,
    FloatingPlant,
    SinusoidalCurrent,
    ThrustAllocator,
    ThrusterDynamics,
    ThrusterLayout,
    VelocityLoop,
)
from ..errors import InputError, PlantDataError
from ..model.vehicle import NU_NAMES
from .plant_config import PlantSpec
from .plants import RateFunction, RunState

#: A control period must hold a whole number of servo periods, and a servo period a whole number
#: of physics steps, to this relative tolerance.
RATE_TOLERANCE = 1e-9


def _whole(ratio: float, what: str) -> int:
    count = round(ratio)
    if count < 1 or abs(ratio - count) > RATE_TOLERANCE * max(1.0, ratio):
        raise InputError(f"{what} must be a whole number >= 1, got {ratio:g}")
    return int(count)


def thruster_layout(parameters: Any, voltage: float | None) -> ThrusterLayout:
    """The thruster layout of a parameter set, at another supply ``voltage`` [V] if given.

    Raises:
        PlantDataError: the set has no thrusters. InputError: a voltage for a layout that is not
            the bundled T200 one (a user's table sets its own limits), or without published
            T200 figures.
    """
    layout = parameters.thrusters
    if not isinstance(layout, ThrusterLayout):
        raise PlantDataError(
            f"parameters {parameters.name!r} have no thruster layout: a dynamic plant needs "
            "the vehicle's thrusters (positions, axes, limits; docs/dynamics.md)")
    if voltage is None:
        return layout
    if not layout.name.startswith("bluerov2_heavy"):
        raise InputError(f"supply_voltage: applies to the bundled T200 layout; layout "
                         f"{layout.name!r} sets its own force limits")
    return ThrusterLayout.bluerov2_heavy(voltage)


def layout_voltage(layout: ThrusterLayout, voltage: float | None) -> float | None:
    """The supply [V] a layout's thrust limits are for.

    ``voltage`` if given, else the layout's own (:attr:`ThrusterLayout.supply_voltage`: the
    bundled T200 layout's), else None (a layout of one's own sets its own limits).
    """
    return float(voltage) if voltage is not None else layout.supply_voltage


def water(current: Any) -> Any:
    """The water's world velocity for the plant: None, a constant vector or a slow oscillation.

    ``current`` is the scenario's :class:`~uvms_qp.sim.current.ConstantCurrent` (or None); with
    an ``oscillation`` amplitude [m/s] and ``period`` [s] its speed varies as
    ``speed + oscillation sin(2 pi t / period)`` along its direction.
    """
    if current is None:
        return None
    velocity = current.velocity()
    if not current.oscillation:
        return velocity
    return SinusoidalCurrent(velocity, current.oscillation * current.unit(), current.period)


def _velocity_loop(params: Any, spec: PlantSpec, layout: ThrusterLayout,
                   actuated: tuple[str, ...], period: float, restoring: Any) -> VelocityLoop:
    """The vehicle's velocity loop: the ``[plant.gains]`` given, the others by pole placement.

    Raises:
        InputError: the placement fails for the vehicle and ``[plant.gains]`` does not give
            both gains (the message says to).
    """
    body = params.vehicle
    try:
        return VelocityLoop.for_body(
            body.mass, body.inertia, body.added_mass, body.linear_damping,
            quadratic_damping=body.quadratic_damping, dt=period, actuated=actuated,
            restoring=restoring, layout=layout, kp=spec.proportional, ki=spec.integral)
    except InputError as exc:
        raise InputError(f"velocity loop of {params.name!r}: {exc}; or give its gains in "
                         "[plant.gains] (proportional and integral, 6 each)") from None


@dataclass
class DynamicSeries:
    """What a dynamic plant recorded, at every servo tick (M ticks).

    Attributes:
        time: Tick times (M,) [s].
        thruster_names: Names of the thrusters (n,).
        thrust: Thruster forces at the end of each tick (M, n) [N].
        thrust_command: Commands the allocation gave (M, n) [N] (before dead band and lag).
        thrust_lower: Reverse force limits (n,) [N] (negative).
        thrust_upper: Forward force limits (n,) [N].
        saturated: Whether each thruster's command sat at a limit (M, n).
        power: Electrical power of all thrusters at the end of each tick (M,) [W].
        energy: Electrical energy drawn since the start at the end of each tick (M,) [J].
        wrench_demand: Body wrench the velocity loop demanded (M, 6) [N, N m], FRD.
        wrench_unmet: What the allocation could not produce (M, 6) [N, N m].
        body_velocity: True vehicle body velocity at the start of each tick (M, 6) [m/s, rad/s].
        velocity_reference: The reference of each tick (M, 6) (NaN on passive DOFs).
        joint_rates: True joint rates at the start of each tick (M, n_joints) [rad/s].
        joint_reference: Joint rate references of each tick (M, n_joints) [rad/s].
        joint_torque: Joint torques the servos produced at the start of each tick (its first
            physics step's, :attr:`~uvms_qp.dynamics.FloatingPlant.joint_torques`)
            (M, n_joints) [N m].
        actuated: Actuated body DOFs (names in ``nu`` order).
        payload_time: When the payload was attached [s], or None.
    """

    time: FloatArray
    thruster_names: tuple[str, ...]
    thrust: FloatArray
    thrust_command: FloatArray
    thrust_lower: FloatArray
    thrust_upper: FloatArray
    saturated: np.ndarray
    power: FloatArray
    energy: FloatArray
    wrench_demand: FloatArray
    wrench_unmet: FloatArray
    body_velocity: FloatArray
    velocity_reference: FloatArray
    joint_rates: FloatArray
    joint_reference: FloatArray
    joint_torque: FloatArray
    actuated: tuple[str, ...]
    payload_time: float | None = None


class DynamicPlant(RunState):
    """A floating UVMS tracking the controller's velocity references (module docstring).

    Args:
        model: The controller's model (a spatial vehicle).
        spec: The plant specification (its ``parameters`` set).
        dt: Control period [s] (a whole number of servo periods).
        current: The scenario's current (its world velocity acts on every body), or None.
        sensors: The run's measurement channel (velocity noise of the loop), or None.

    Raises:
        InputError: periods that do not nest, a model the parameters do not describe.
    """

    kind = "dynamic"

    def __init__(self, model: Any, spec: PlantSpec, dt: float, current: Any = None,
                 sensors: Any = None) -> None:
        if spec.parameters is None:
            raise InputError("plant: a dynamic plant needs a parameter set")
        params = spec.parameters
        physics = spec.physics_step or DEFAULT_STEP
        self.physics = FloatingPlant(model, params, current=water(current), step=physics)
        self.model = model
        self.spec = spec
        self.dt = dt
        self.servo_period = 1.0 / spec.servo_rate
        self.servo_ticks = _whole(dt / self.servo_period,
                                  f"servo_rate: the control period {dt:g} s / the servo period "
                                  f"{self.servo_period:g} s")
        self.physics_steps = _whole(self.servo_period / physics,
                                    f"physics_step: the servo period {self.servo_period:g} s / "
                                    f"the physics step {physics:g} s")
        self.physics_step = self.servo_period / self.physics_steps
        layout = thruster_layout(params, spec.supply_voltage)
        passive = [d for d in model.actuated if d not in layout.actuated]
        if passive:
            raise PlantDataError(
                f"thruster layout {layout.name or '(unnamed)'!r} leaves {', '.join(passive)} "
                f"passive, which model {model.name!r} commands: the controller would ask for "
                "rates no thruster gives; actuate them in the layout, or build the model with "
                "those DOFs passive (Vehicle(actuated=...))")
        self.layout = layout
        self.allocator = ThrustAllocator(layout)
        self.thrusters = ThrusterDynamics(layout)
        self.feedforward = {"model": self.physics.restoring_wrench, "none": None,
                            "nominal": FloatingPlant(model, params).restoring_wrench,
                            }[spec.feedforward]
        self.loop = _velocity_loop(params, spec, layout, model.actuated, self.servo_period,
                                   self.feedforward)
        # the model feed-forward knows the water: its damping is fed at the relative velocity
        self._told_current = spec.feedforward == "model" and self.physics.current is not None
        self.sensors = sensors
        self._actuated = [NU_NAMES.index(d) for d in model.actuated]
        self._n_vehicle = int(model.n_vehicle)
        self._rate_limit = np.asarray(model.joint_rate_limit, dtype=np.float64)
        super().__init__()
        self._v = np.zeros(6 + int(model.n_joints))
        self._records: dict[str, list[Any]] = {}
        self._unmet = np.zeros(6)
        self._payload_attached: float | None = None

    # --- the run ------------------------------------------------------------------------------

    def start(self, q0: FloatArray) -> None:
        """Begin at rest at ``q0``, trimmed (the thrusters hold it), with no payload.

        Zero velocity, integral and energy; the thrusters' forces are the allocation of the
        loop's feed-forward at ``q0`` (the wrench that holds the vehicle there).
        """
        self._q = np.array(q0, dtype=np.float64)
        self._v[:] = 0.0
        self.loop.reset()
        self.physics.detach_payload()
        # trimmed: the thrusters already hold the vehicle against its weight and buoyancy
        hold = self.feedforward(self._q) if self.feedforward is not None else np.zeros(6)
        self.thrusters.reset(self.allocator.allocate(hold).forces)
        self._payload_attached = None
        self._unmet[:] = 0.0
        self._records = {key: [] for key in (
            "time", "thrust", "thrust_command", "saturated", "power", "energy",
            "wrench_demand", "wrench_unmet", "body_velocity", "velocity_reference",
            "joint_rates", "joint_reference", "joint_torque")}

    @property
    def body_velocity(self) -> FloatArray:
        """The true vehicle body velocity ``nu`` (6,) [m/s, rad/s] (a copy)."""
        return self._v[:6].copy()

    @property
    def joint_rates(self) -> FloatArray:
        """The true joint rates (n_joints,) [rad/s] (a copy)."""
        return self._v[6:].copy()

    def advance(self, zeta: FloatArray, t: float, rates: RateFunction | None = None
                ) -> FloatArray:
        """Track ``zeta`` from ``t`` [s] for one control period; the new true configuration.

        Raises:
            SimulationDiverged: the equations of motion left their range (non-finite state or
                a velocity beyond the plant's sanity bound); the message names time and state.
        """
        nu_ref = np.full(6, math.nan)
        nu_ref[self._actuated] = zeta[: self._n_vehicle]
        reference = np.where(np.isnan(nu_ref), 0.0, nu_ref)
        joint_ref = np.clip(zeta[self._n_vehicle:], -self._rate_limit, self._rate_limit)
        q, v = self.q, self._v
        h = self.physics_step
        physics, thrusters, records = self.physics, self.thrusters, self._records
        payload = self.spec.payload
        for j in range(self.servo_ticks):
            tick = t + j * self.servo_period
            if (payload is not None and self._payload_attached is None
                    and tick >= payload.time - 1e-9):
                physics.attach_payload(payload.mass, payload.volume, payload.offset)
                self._payload_attached = tick
            nu = v[:6]
            measured = nu if self.sensors is None else self.sensors.body_velocity(nu)
            water = physics.water_velocity(q, tick) if self._told_current else None
            demand = self.loop.step(reference, measured, q, self._unmet, water)
            allocation = self.allocator.allocate(demand)
            self._unmet = allocation.unmet
            thrusters.set_command(allocation.forces)
            records["time"].append(tick)
            records["body_velocity"].append(nu.copy())
            records["joint_rates"].append(v[6:].copy())
            time = tick
            for i in range(self.physics_steps):
                thrusters.step(h)
                q, v = physics.step(q, v, thrusters.wrench(), joint_ref, time, h)
                time += h
                if i == 0:
                    records["joint_torque"].append(physics.joint_torques)
            records["thrust"].append(thrusters.forces)
            records["thrust_command"].append(allocation.forces)
            records["saturated"].append(allocation.saturated)
            records["power"].append(float(thrusters.power.sum()))
            records["energy"].append(thrusters.energy)
            records["wrench_demand"].append(demand)
            records["wrench_unmet"].append(allocation.unmet)
            records["velocity_reference"].append(nu_ref)
            records["joint_reference"].append(joint_ref)
        self._q, self._v = q, v
        return q

    def settings(self, spec: PlantSpec) -> dict[str, Any]:
        """The record's ``plant_settings``: the values this plant runs with, given or default.

        ``physics_step`` [s], ``supply_voltage`` [V] (None for a layout that sets its own
        limits) and the velocity loop's ``gains`` (6 each, ``nu`` order) are those used;
        ``defaults`` names the ones the scenario did not give.
        """
        record = dict(spec.settings())
        record["physics_step"] = self.physics_step
        record["supply_voltage"] = layout_voltage(self.layout, spec.supply_voltage)
        record["gains"] = {"proportional": [float(g) for g in self.loop.kp],
                           "integral": [float(g) for g in self.loop.ki]}
        given = {"physics_step": spec.physics_step, "supply_voltage": spec.supply_voltage,
                 "gains.proportional": spec.proportional, "gains.integral": spec.integral}
        record["defaults"] = [key for key, value in given.items() if value is None]
        return record

    def series(self, steps: int) -> DynamicSeries:
        """What the first ``steps`` control periods of the run recorded (servo ticks)."""
        count = steps * self.servo_ticks
        r = {key: values[:count] for key, values in self._records.items()}
        n_thr, n_j = self.layout.size, int(self.model.n_joints)

        def stack(key: str, width: int) -> FloatArray:
            return np.array(r[key], dtype=np.float64).reshape(-1, width)

        return DynamicSeries(
            time=np.array(r["time"], dtype=np.float64),
            thruster_names=tuple(self.layout.names),
            thrust=stack("thrust", n_thr),
            thrust_command=stack("thrust_command", n_thr),
            thrust_lower=np.array(self.layout.lower, dtype=np.float64),
            thrust_upper=np.array(self.layout.upper, dtype=np.float64),
            saturated=np.array(r["saturated"], dtype=bool).reshape(-1, n_thr),
            power=np.array(r["power"], dtype=np.float64),
            energy=np.array(r["energy"], dtype=np.float64),
            wrench_demand=stack("wrench_demand", 6),
            wrench_unmet=stack("wrench_unmet", 6),
            body_velocity=stack("body_velocity", 6),
            velocity_reference=stack("velocity_reference", 6),
            joint_rates=stack("joint_rates", n_j),
            joint_reference=stack("joint_reference", n_j),
            joint_torque=stack("joint_torque", n_j),
            actuated=tuple(self.model.actuated),
            payload_time=self._payload_attached,
        )
