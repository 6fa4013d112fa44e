"""The floating vehicle's dynamics: thrusters and the vehicle's body-velocity loop."""

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
    "Allocation",
    "AllocationError",
    "AllocationRankError",
    "ThrustAllocator",
    "Thruster",
    "ThrusterDynamics",
    "ThrusterLayout",
    "VelocityLoop",
    "pole_placement_gains",
]
