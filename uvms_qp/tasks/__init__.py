"""Tasks: each turns a model state into rows ``lower <= A zeta <= upper`` over zeta.

A task is a description (parameters, binding, rows); its run-time memory in a controller is a
:class:`TaskSlot`. ``TASK_TYPES`` maps the scenario ``type`` strings to the task classes, and
``TASK_MODES`` the ``mode`` of a type whose modes yield different kinds of rows to their classes.
"""

from __future__ import annotations

from . import joint_limit, manipulability, payload_moment
from .current_alignment import CurrentAlignmentTask
from .end_effector import EndEffectorTask
from .error_task import ErrorTask
from .joint_limit import (
    JointLimitDampingTask,
    JointLimitGradientTask,
    JointLimitMarginTask,
    JointLimitTask,
)
from .manipulability import (
    ManipulabilityAscendTask,
    ManipulabilityFloorTask,
    ManipulabilityShapingTask,
    ManipulabilityTask,
)
from .manipulability_measure import manipulability_and_gradient
from .payload_moment import PayloadMomentBoundTask, PayloadMomentReduceTask, PayloadMomentTask
from .posture import PostureTask
from .slot import TaskSlot
from .station_keeping import StationKeepingTask
from .targets import FixedPose, HeldPose, InFrame, Target, TrajectoryTarget
from .task import Task
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

TASK_MODES: dict[str, dict[str, type[Task]]] = {
    "joint_limit": dict(joint_limit.MODES),
    "manipulability": dict(manipulability.MODES),
    "payload_moment": dict(payload_moment.MODES),
}
"""Scenario ``type`` -> its ``mode`` strings -> the class of that kind of rows."""

__all__ = [
    "TASK_MODES",
    "TASK_TYPES",
    "CurrentAlignmentTask",
    "EndEffectorTask",
    "ErrorTask",
    "FixedPose",
    "HeldPose",
    "InFrame",
    "JointLimitDampingTask",
    "JointLimitGradientTask",
    "JointLimitMarginTask",
    "JointLimitTask",
    "ManipulabilityAscendTask",
    "ManipulabilityFloorTask",
    "ManipulabilityShapingTask",
    "ManipulabilityTask",
    "PayloadMomentBoundTask",
    "PayloadMomentReduceTask",
    "PayloadMomentTask",
    "PostureTask",
    "StationKeepingTask",
    "Target",
    "Task",
    "TaskSlot",
    "TrajectoryTarget",
    "VehicleAttitudeTask",
    "VehicleMotionTask",
    "manipulability_and_gradient",
    "motion_distribution_weights",
]
