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

__all__ = [
    "Allocation",
    "AllocationError",
    "AllocationRankError",
    "ThrustAllocator",
    "Thruster",
    "ThrusterDynamics",
    "ThrusterLayout",
]
