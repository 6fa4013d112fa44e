"""Tasks: each turns a model state into rows ``lower <= A zeta <= upper`` over zeta.

``TASK_TYPES`` maps the scenario ``type`` strings to the task classes.
"""

from __future__ import annotations

from .current_alignment import CurrentAlignmentTask
from .end_effector import EndEffectorTask
from .joint_limit import JointLimitTask
from .manipulability import ManipulabilityTask, manipulability_and_gradient
from .payload_moment import PayloadMomentTask
from .posture import PostureTask
from .station_keeping import StationKeepingTask
from .task import ErrorTask, Task
from .vehicle_attitude import VehicleAttitudeTask
from .vehicle_motion import VehicleMotionTask, motion_distribution_weights

TASK_TYPES: dict[str, type[Task]] = {
    cls.type_name: cls
    for cls in (
        EndEffectorTask,
        StationKeepingTask,
        ManipulabilityTask,
        JointLimitTask,
        PayloadMomentTask,
        CurrentAlignmentTask,
        VehicleAttitudeTask,
        PostureTask,
        VehicleMotionTask,
    )
}
"""Scenario ``type`` string -> task class."""

__all__ = [
    "TASK_TYPES",
    "CurrentAlignmentTask",
    "EndEffectorTask",
    "ErrorTask",
    "JointLimitTask",
    "ManipulabilityTask",
    "PayloadMomentTask",
    "PostureTask",
    "StationKeepingTask",
    "Task",
    "VehicleAttitudeTask",
    "VehicleMotionTask",
    "manipulability_and_gradient",
    "motion_distribution_weights",
]
