"""The ``[plant]`` and ``[sensors]`` tables of a scenario file, and the plant specification.

``[plant]`` selects what the controller drives (``docs/scenarios.md``, ``docs/dynamics.md``)::

    [plant]
    type = "dynamic"                 # or "kinematic" (the default: the command realised exactly)
    parameters = "bluerov2_heavy_von_benzon_2022"   # a bundled set, or file = "my_rov.toml"
    physics_step = 0.002             # [s] fixed step of the equations of motion
    servo_rate = 100.0               # [Hz] velocity loop, allocation and joint servos
    coordination = true              # arm levels re-solved with the measured vehicle velocity
    feedforward = "model"            # the loop's restoring wrench: "model", "nominal" or "none"
    supply_voltage = 16.0            # [V] T200 force limits (12, 16 or 20; default: the set's)

    [plant.payload]                  # taken by the tool at a time (a scenario's pick-up)
    time = 15.0                      # [s]
    mass = 2.5                       # [kg]
    volume = 0.0004                  # [m^3] displaced

The dynamic settings are read and checked even when ``type = "kinematic"``, so that
``uvms-qp run SCENARIO --plant dynamic`` uses them. ``[sensors]`` sets
:class:`~uvms_qp.sim.sensors.Sensors` (noise and delay of what the controller measures).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .. import dynamics
from .._validation import FloatArray, as_scalar, as_vector
from ..dynamics.thrusters import T200_RATINGS
from ..errors import ConfigError, InputError, ModelError, PlantDataError, UvmsQpError
from .config import Table
from .sensors import Sensors

#: Plant kinds.
PLANT_KINDS = ("kinematic", "dynamic")
#: Keys of ``[plant]``.
PLANT_KEYS = ("type", "parameters", "file", "physics_step", "servo_rate", "coordination",
              "supply_voltage", "payload", "gains", "feedforward")
#: What the vehicle's velocity loop feeds forward (:class:`PlantSpec`).
FEEDFORWARDS = ("model", "nominal", "none")
#: Shortest physics step [s]: below it a run of seconds takes hours.
MIN_PHYSICS_STEP = 1e-4
#: Keys of ``[plant.payload]``.
PAYLOAD_KEYS = ("time", "mass", "volume", "offset")
#: Keys of ``[plant.gains]``: the vehicle velocity loop's PI gains per body DOF.
GAIN_KEYS = ("proportional", "integral")
#: Keys of ``[sensors]``.
SENSOR_KEYS = tuple(f.name for f in dataclasses.fields(Sensors))


@dataclass(frozen=True)
class Payload:
    """A payload the tool takes at ``time`` [s]: ``mass`` [kg], displaced ``volume`` [m^3].

    ``offset`` (3,) [m] is its centre (of gravity and of buoyancy) in the tool frame.
    """

    time: float
    mass: float
    volume: float = 0.0
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "time", as_scalar(self.time, "time", nonnegative=True))
        object.__setattr__(self, "mass", as_scalar(self.mass, "mass", positive=True))
        object.__setattr__(self, "volume", as_scalar(self.volume, "volume", nonnegative=True))
        offset = as_vector(self.offset, "offset", 3)
        object.__setattr__(self, "offset", tuple(float(x) for x in offset))


@dataclass(frozen=True)
class PlantSpec:
    """What a run drives: the kind of plant and the settings of a dynamic one.

    Attributes:
        kind: ``"kinematic"`` (the command realised exactly) or ``"dynamic"`` (a floating UVMS).
        parameters: The dynamic plant's :class:`~uvms_qp.dynamics.PlantParameters` (None for a
            kinematic plant whose scenario set none; :meth:`as_kind` fills the model's default).
        physics_step: Fixed step of the equations of motion [s], None for the plant's default.
        servo_rate: Rate of the velocity loop, thruster allocation and joint servos [Hz].
        coordination: Re-solve the arm's levels with the measured vehicle velocity
            (Simetti et al. (2014)) on a dynamic plant.
        supply_voltage: T200 supply [V] (12, 16, 20), which sets their force limits, or None
            for the parameter set's own layout.
        payload: A payload taken by the tool during the run, or None.
        proportional: Velocity-loop proportional gains per body DOF (6,), None for the default.
        integral: Velocity-loop integral gains per body DOF (6,), None for the default.
        feedforward: The restoring wrench the velocity loop feeds forward: ``"model"`` (the
            plant's own, the payload included once it is taken: a payload the operator declares,
            as the controller's payload task is told of it), ``"nominal"`` (the vehicle and arm
            without any payload: a payload the loop must find by its integral) or ``"none"``.
    """

    kind: str = "kinematic"
    parameters: Any = field(default=None, repr=False)
    physics_step: float | None = None
    servo_rate: float = 100.0
    coordination: bool = False
    supply_voltage: float | None = None
    payload: Payload | None = None
    proportional: FloatArray | None = field(default=None, repr=False)
    integral: FloatArray | None = field(default=None, repr=False)
    feedforward: str = "model"

    def __post_init__(self) -> None:
        if self.kind not in PLANT_KINDS:
            raise InputError(f"plant: unknown kind {self.kind!r}; known: "
                             f"{', '.join(PLANT_KINDS)}")
        if self.feedforward not in FEEDFORWARDS:
            raise InputError(f"feedforward: expected one of {', '.join(FEEDFORWARDS)}, got "
                             f"{self.feedforward!r}")

    def settings(self) -> dict[str, Any]:
        """What a run's record says of the plant (``results.json``: ``plant_settings``)."""
        params = self.parameters
        return {
            "type": self.kind,
            "parameters": None if params is None else params.name,
            "parameters_source": None if params is None else params.source,
            "rated_payload": None if params is None else params.rated_payload,
            "physics_step": self.physics_step, "servo_rate": self.servo_rate,
            "coordination": self.coordination, "supply_voltage": self.supply_voltage,
            "feedforward": self.feedforward,
            "payload": None if self.payload is None else dataclasses.asdict(self.payload),
            "gains": {"proportional": self.proportional, "integral": self.integral},
        }

    def as_kind(self, kind: str, model: Any) -> PlantSpec:
        """This specification with another kind; a dynamic one gets the model's parameters.

        Raises:
            InputError: an unknown kind; a model without dynamic data (naming what is missing).
        """
        if kind not in PLANT_KINDS:
            raise InputError(f"unknown plant {kind!r}; known plants: {', '.join(PLANT_KINDS)}")
        parameters = self.parameters
        if kind == "dynamic" and parameters is None:
            parameters = default_parameters(model)
        return dataclasses.replace(self, kind=kind, parameters=parameters)


def read_plant(table: Table | None, model: Any, base: Path, dt: float,
               duration: float) -> PlantSpec:
    """Read ``[plant]`` (None: a kinematic plant with the default dynamic settings).

    Args:
        table: The ``[plant]`` table, or None.
        model: The scenario's model (its default parameter set, its joints).
        base: Folder a relative ``file`` is resolved against.
        dt: The control period [s] (the servo period must divide it).
        duration: The simulated time [s] (a payload is taken within it).

    Raises:
        ConfigError: any invalid field, with its path.
    """
    if table is None:
        return PlantSpec()
    kind = table.take_str("type", "kinematic", choices=PLANT_KINDS) or "kinematic"
    name = table.take_str("parameters")
    file = table.take_str("file")
    if name is not None and file is not None:
        raise ConfigError("give either parameters (a bundled set) or file, not both",
                          table.at("file"))
    parameters: Any = None
    try:
        if file is not None:
            path = Path(file) if Path(file).is_absolute() else (base / file).resolve()
            parameters = dynamics.load_plant_parameters(path)
        elif name is not None:
            parameters = dynamics.plant_parameters(name)
        elif kind == "dynamic":
            parameters = default_parameters(model)
    except UvmsQpError as exc:
        key = "file" if file is not None else "parameters" if name is not None else "type"
        raise ConfigError(str(exc), table.at(key)) from exc
    rate = float(table.take_number("servo_rate", 100.0, positive=True) or 100.0)
    if not _divides(1.0 / rate, dt):
        raise ConfigError(f"the servo period 1/{rate:g} s must divide the control period "
                          f"{dt:g} s (e.g. {1.0 / dt:g} Hz times a whole number)",
                          table.at("servo_rate"))
    step = table.take_number("physics_step", None, minimum=MIN_PHYSICS_STEP)
    if step is not None and not _divides(step, 1.0 / rate):
        raise ConfigError(f"the physics step {step:g} s must divide the servo period "
                          f"{1.0 / rate:g} s", table.at("physics_step"))
    coordination = table.take_bool("coordination", False)
    voltage = table.take_number("supply_voltage", None, positive=True)
    if voltage is not None and voltage not in T200_RATINGS:
        known = ", ".join(f"{v:g}" for v in T200_RATINGS)
        raise ConfigError(f"no published T200 figures at {voltage:g} V (known: {known} V)",
                          table.at("supply_voltage"))
    feedforward = table.take_str("feedforward", "model", choices=FEEDFORWARDS) or "model"
    payload = _read_payload(table.take_table("payload", keys=PAYLOAD_KEYS), duration)
    gains = table.take_table("gains", keys=GAIN_KEYS)
    proportional = integral = None
    if gains is not None:
        proportional = _gains(gains, "proportional")
        integral = _gains(gains, "integral")
        gains.finish()
    table.finish()
    return PlantSpec(kind, parameters, step, rate, coordination, voltage, payload,
                     proportional, integral, feedforward)


def _divides(part: float, whole: float) -> bool:
    """Whether ``whole / part`` is a whole number >= 1 (to a relative 1e-9)."""
    ratio = whole / part
    return round(ratio) >= 1 and abs(ratio - round(ratio)) <= 1e-9 * max(1.0, ratio)


def default_parameters(model: Any) -> Any:
    """The model's default plant parameters.

    Raises:
        ModelError: the vehicle is not spatial (no parameter file can help: the dynamic plant
            needs a free-floating vehicle). PlantDataError: no bundled set for the model (the
            message says how to give one: ``[plant] file = ...``).
    """
    if model.vehicle_kind != "spatial":
        raise ModelError(f"model {model.name!r} has a {model.vehicle_kind} vehicle: the dynamic "
                         "plant needs a spatial (free-floating) one")
    try:
        return dynamics.default_plant_parameters(model)
    except PlantDataError as exc:
        raise PlantDataError(f"{exc}; in a scenario file: [plant] file = \"my_plant.toml\"") \
            from None


def _read_payload(table: Table | None, duration: float) -> Payload | None:
    if table is None:
        return None
    time = table.take_number("time", required=True, nonnegative=True, maximum=duration)
    mass = table.take_number("mass", required=True, positive=True)
    volume = table.take_number("volume", 0.0, nonnegative=True)
    offset = table.take_numbers("offset", [0.0, 0.0, 0.0], size=3)
    table.finish()
    return Payload(float(time or 0.0), float(mass or 0.0), float(volume or 0.0),
                   tuple(offset or (0.0, 0.0, 0.0)))  # type: ignore[arg-type]


def _gains(table: Table, key: str) -> FloatArray | None:
    values = table.take_numbers(key, size=6)
    if values is None:
        return None
    array = np.array(values)
    if np.any(array < 0.0):
        i = int(np.flatnonzero(array < 0.0)[0])
        raise ConfigError(f"expected a gain >= 0, got {array[i]:g}", f"{table.at(key)}[{i}]")
    return array


def read_sensors(table: Table | None) -> Sensors | None:
    """Read ``[sensors]`` (None when absent: the controller measures the true state).

    Raises:
        ConfigError: an unknown key or a negative figure, with its path.
    """
    if table is None:
        return None
    values: dict[str, Any] = {}
    for key in SENSOR_KEYS:
        if key == "seed":
            seed = table.raw("seed")
            if seed is not None:
                if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
                    raise ConfigError(f"expected a non-negative integer, got {seed!r}",
                                      table.at("seed"))
                values["seed"] = seed
            continue
        number = table.take_number(key, None, nonnegative=True)
        if number is not None:
            values[key] = float(number)
    table.finish()
    return Sensors(**values)
