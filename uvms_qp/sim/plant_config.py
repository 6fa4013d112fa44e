"""The ``[plant]`` and ``[sensors]`` tables of a scenario file, and the plant specification.

``[plant]`` selects what the controller drives (``docs/scenarios.md``, ``docs/dynamics.md``)::

    [plant]
    type = "dynamic"                 # or "kinematic" (the default: the command realised exactly)
    parameters = "bluerov2_heavy"    # a bundled parameter set, or file = "my_rov.toml"
    physics_step = 0.002             # [s] fixed step of the equations of motion
    servo_rate = 100.0               # [Hz] velocity loop, allocation and joint servos
    coordination = true              # arm levels re-solved with the measured vehicle velocity
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
from ..errors import ConfigError, InputError, UvmsQpError
from .config import Table
from .sensors import Sensors

#: Plant kinds.
PLANT_KINDS = ("kinematic", "dynamic")
#: Keys of ``[plant]``.
PLANT_KEYS = ("type", "parameters", "file", "physics_step", "servo_rate", "coordination",
              "supply_voltage", "payload", "gains")
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

    def as_kind(self, kind: str, model: Any) -> PlantSpec:
        """This specification with another kind; a dynamic one gets the model's parameters.

        Raises:
            InputError: an unknown kind; a model without dynamic data (naming what is missing).
        """
        if kind not in PLANT_KINDS:
            raise InputError(f"unknown plant {kind!r}; known plants: {', '.join(PLANT_KINDS)}")
        parameters = self.parameters
        if kind == "dynamic" and parameters is None:
            parameters = dynamics.default_plant_parameters(model)
        return dataclasses.replace(self, kind=kind, parameters=parameters)


def read_plant(table: Table | None, model: Any, base: Path) -> PlantSpec:
    """Read ``[plant]`` (None: a kinematic plant with the default dynamic settings).

    Args:
        table: The ``[plant]`` table, or None.
        model: The scenario's model (its default parameter set, its joints).
        base: Folder a relative ``file`` is resolved against.

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
        else:
            parameters = dynamics.default_plant_parameters(model) if kind == "dynamic" else None
    except UvmsQpError as exc:
        key = "file" if file is not None else "parameters" if name is not None else "type"
        raise ConfigError(str(exc), table.at(key)) from exc
    step = table.take_number("physics_step", None, positive=True)
    rate = float(table.take_number("servo_rate", 100.0, positive=True) or 100.0)
    coordination = table.take_bool("coordination", False)
    voltage = table.take_number("supply_voltage", None, positive=True)
    payload = _read_payload(table.take_table("payload", keys=PAYLOAD_KEYS))
    gains = table.take_table("gains", keys=GAIN_KEYS)
    proportional = integral = None
    if gains is not None:
        proportional = _gains(gains, "proportional")
        integral = _gains(gains, "integral")
        gains.finish()
    table.finish()
    return PlantSpec(kind, parameters, step, rate, coordination, voltage, payload,
                     proportional, integral)


def _read_payload(table: Table | None) -> Payload | None:
    if table is None:
        return None
    time = table.take_number("time", required=True, nonnegative=True)
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
