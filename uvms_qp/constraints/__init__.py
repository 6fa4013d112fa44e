"""Hard constraints: box bounds and inequality rows on zeta that hold at every level.

``CONSTRAINT_TYPES`` maps the scenario ``type`` strings to the constraint classes.
"""

from __future__ import annotations

from .command_rate_bounds import CommandRateBounds
from .constraint import Constraint, intersect_boxes
from .joint_position_bounds import JointPositionBounds
from .joint_velocity_bounds import JointVelocityBounds
from .linear_inequality import LinearInequality
from .vehicle_rate_bounds import VehicleRateBounds

CONSTRAINT_TYPES: dict[str, type[Constraint]] = {
    cls.type_name: cls
    for cls in (JointPositionBounds, JointVelocityBounds, VehicleRateBounds, CommandRateBounds,
                LinearInequality)
}
"""Scenario ``type`` string -> constraint class."""

__all__ = [
    "CONSTRAINT_TYPES",
    "CommandRateBounds",
    "Constraint",
    "JointPositionBounds",
    "JointVelocityBounds",
    "LinearInequality",
    "VehicleRateBounds",
    "intersect_boxes",
]
