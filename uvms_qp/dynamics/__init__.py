"""The floating UVMS: a hydrodynamic plant under the kinematic controller.

Public names: :class:`FloatingPlant` (equations of motion, integrator), :class:`Payload`,
:class:`BodyParameters`, :class:`PlantParameters` (parameters as data with provenance),
:func:`plant_parameters`, :func:`default_plant_parameters`, :func:`plant_parameter_sets`,
:func:`load_plant_parameters`, the currents :class:`ConstantCurrent`,
:class:`SinusoidalCurrent`, :class:`FunctionCurrent`, and :data:`DEFAULT_STEP`,
:data:`DEFAULT_SERVO_TIME_CONSTANT`; the actuators :class:`Thruster`, :class:`ThrusterLayout`,
:class:`ThrustAllocator` (bounded least-squares allocation), :class:`ThrusterDynamics` (dead band,
lag, power) and the vehicle's body-velocity loop :class:`VelocityLoop`. See ``docs/dynamics.md``.
"""

from __future__ import annotations

from .bundled import (
    alpha5_like_links,
    default_plant_parameters,
    plant_parameter_sets,
    plant_parameters,
)
from .current import ConstantCurrent, Current, FunctionCurrent, SinusoidalCurrent, as_current
from .files import load_plant_parameters
from .parameters import DEFAULT_SERVO_TIME_CONSTANT, BodyParameters, PlantParameters
from .plant import DEFAULT_SPEED_BOUNDS, DEFAULT_STEP, FloatingPlant, Payload
from .thrusters import (
    Allocation,
    AllocationError,
    AllocationRankError,
    ThrustAllocator,
    Thruster,
    ThrusterDynamics,
    ThrusterLayout,
)
from .vehicle_loop import VelocityLoop, pole_placement_gains

__all__ = [
    "DEFAULT_SERVO_TIME_CONSTANT",
    "DEFAULT_SPEED_BOUNDS",
    "DEFAULT_STEP",
    "Allocation",
    "AllocationError",
    "AllocationRankError",
    "BodyParameters",
    "ConstantCurrent",
    "Current",
    "FloatingPlant",
    "FunctionCurrent",
    "Payload",
    "PlantParameters",
    "SinusoidalCurrent",
    "ThrustAllocator",
    "Thruster",
    "ThrusterDynamics",
    "ThrusterLayout",
    "VelocityLoop",
    "alpha5_like_links",
    "as_current",
    "default_plant_parameters",
    "load_plant_parameters",
    "plant_parameter_sets",
    "plant_parameters",
    "pole_placement_gains",
]
