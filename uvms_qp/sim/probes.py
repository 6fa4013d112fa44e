"""Quantities recorded at every simulated state, measured independently of the controller.

- Manipulability: the measure of the stack's manipulability task (``task.compute_value(state)``,
  same frame and rows), otherwise Yoshikawa's measure ``w = sqrt(det(J J^T))``
  (Soylu et al. (2007), Eq. (18)) of the tool's arm Jacobian in the arm-base frame,
  restricted to the rows a default :class:`~uvms_qp.tasks.ManipulabilityTask` uses (``x, y`` for
  planar vehicles, whose ``z`` row is zero; ``x, y, z`` otherwise).
  Its unit (the task's, else ``m^k`` for k position rows) and, for a task in mode ``"floor"``,
  the floor at each state.
- Payload moment: ``M = (x_E^2 + y_E^2) F`` with ``(x_E, y_E)`` the tool position in the arm-base
  frame [m] and ``F`` the payload force [N] currently set on the payload task
  (Wang et al. (2017), Eq. (20); [N m^2] as in the paper), through the task's
  ``compute_value(state)``.
- Tool tracking: the tracked task's frame pose and its target (``task.target(t, slot=...)``).
- Heading: the target heading of a current-alignment task (``heading + offset``), else the
  scenario current's direction.
- Task errors: the norm of the error ``e = x_d - x`` of every regulated task (each
  :class:`~uvms_qp.tasks.ErrorTask` of the stack, ``task.compute_error(state, t, slot)``) [its
  ``error_unit``], whatever scheme commands the run: the settling times come from them.

A task's run-time memory (a held target) is read from the slots of the controller that runs the
stack (``Controller.slot(name)``), so a held target is the one the controller holds; a scheme
without slots (the papers' closed forms) is measured with the probes' own slots.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray
from ..tasks import ErrorTask
from ..tasks.manipulability_measure import default_rows

if TYPE_CHECKING:  # pragma: no cover
    from ..stack import Stack
    from ..tasks import TaskSlot
    from .scenario import Scenario


def yoshikawa(J: FloatArray) -> float:
    """Yoshikawa's manipulability ``sqrt(det(J J^T))`` of a (k, n) Jacobian (k <= n)."""
    value = float(np.linalg.det(J @ J.T))
    return float(np.sqrt(max(value, 0.0)))


def _has_value(type_name: str) -> Any:
    def predicate(task: Any) -> bool:
        return getattr(task, "type_name", "") == type_name and callable(
            getattr(task, "compute_value", None)
        )

    return predicate


def _find_task(stack: Stack, predicate: Any) -> Any:
    for task in stack.tasks:
        if predicate(task):
            return task
    return None


class Probes:
    """Record per-state quantities into preallocated arrays.

    Args:
        scenario: The scenario being run.
        stack: The run's stack (its tasks give the target, the measures and the payload force).
        size: Number of states to record (steps + 1).
        slot: The run-time memory of a task by name in the controller of the run
            (``Controller.slot``), or None: the probes keep their own.
    """

    def __init__(self, scenario: Scenario, stack: Stack, size: int,
                 slot: Callable[[str], TaskSlot] | None = None) -> None:
        model = scenario.model
        self.model = model
        self.tracked = stack.task(scenario.tracking) if scenario.tracking else None
        self.frame = str(getattr(self.tracked, "frame", "tool")) if self.tracked else "tool"
        self.manipulability_task = _find_task(stack, _has_value("manipulability"))
        self.payload_task = _find_task(stack, _has_value("payload_moment"))
        alignment = _find_task(
            stack, lambda t: getattr(t, "type_name", "") == "current_alignment"
        )
        heading: float | None = None
        if alignment is not None and getattr(alignment, "heading", None) is not None:
            heading = float(alignment.heading) + float(getattr(alignment, "offset", 0.0))
        elif scenario.current is not None:
            heading = scenario.current.heading
        self.heading = heading
        self.manipulability_rows = default_rows(model)
        task = self.manipulability_task
        rows = len(self.manipulability_rows)
        self.manipulability_unit = str(getattr(task, "error_unit", "")) if task else (
            "m" if rows == 1 else f"m^{rows}")
        has_floor = task is not None and hasattr(task, "minimum")
        self.manipulability_floor = np.full(size, np.nan) if has_floor else None
        self.has_yaw = getattr(model, "vehicle_kind", "fixed") != "fixed"
        self.eta = np.zeros((size, int(model.eta_size)))
        self.joints = np.zeros((size, int(model.n_joints)))
        self.vehicle_position = np.zeros((size, 3))
        self.ee_position = np.zeros((size, 3))
        self.ee_rotation = np.zeros((size, 3, 3))
        self.target_position = np.full((size, 3), np.nan)
        self.manipulability = np.zeros(size)
        has_payload = self.payload_task is not None
        self.payload_objective = np.zeros(size) if has_payload else None
        self.payload_moment = np.zeros(size) if has_payload else None
        if slot is None:
            own = {t.name: t.new_slot() for t in stack.tasks}
            slot = own.__getitem__
        self.slot = slot
        self.regulated = [t for t in stack.tasks if isinstance(t, ErrorTask)]
        self.task_errors = {t.name: np.full(size, np.nan) for t in self.regulated}
        self.task_error_units = {t.name: str(t.error_unit) for t in self.regulated}

    def record(self, k: int, state: Any, t: float) -> None:
        """Record state ``k`` at time ``t`` [s]."""
        self.eta[k] = state.eta
        self.joints[k] = state.joints
        self.vehicle_position[k] = state.position("vehicle")
        T = state.pose(self.frame)
        self.ee_position[k] = T[:3, 3]
        self.ee_rotation[k] = T[:3, :3]
        if self.tracked is not None:
            target = getattr(self.tracked, "target", None)
            if callable(target):
                position = target(t, slot=self.slot(self.tracked.name))[0]
                if position is not None:
                    self.target_position[k] = position
        if self.manipulability_task is not None:
            self.manipulability[k] = float(self.manipulability_task.compute_value(state)[0])
            if self.manipulability_floor is not None:
                self.manipulability_floor[k] = self.manipulability_task.minimum
        else:
            J = state.arm_jacobian("tool")[self.manipulability_rows]
            self.manipulability[k] = yoshikawa(J)
        if self.payload_objective is not None and self.payload_moment is not None:
            # Eq. (20) objective (x_E^2 + y_E^2) F [N m^2], and the physical moment F |(x_E, y_E)|
            # [N m] = sqrt(objective * F).
            objective = float(self.payload_task.compute_value(state)[0])
            self.payload_objective[k] = objective
            self.payload_moment[k] = float(np.sqrt(max(objective, 0.0) * self.payload_task.force))
        for task in self.regulated:
            e = task.compute_error(state, t, self.slot(task.name))
            self.task_errors[task.name][k] = float(np.sqrt(e @ e))

    def truncate(self, count: int) -> None:
        """Keep the first ``count`` states of every series (a run that ended early)."""
        for name, value in list(vars(self).items()):
            if isinstance(value, np.ndarray) and value.ndim and value.shape[0] > count:
                setattr(self, name, value[:count])
        self.task_errors = {name: series[:count] for name, series in self.task_errors.items()}

    def arrays(self) -> dict[str, Any]:
        """The recorded arrays by name (``yaw`` and the payload series only when defined)."""
        data: dict[str, Any] = {
            "eta": self.eta,
            "joints": self.joints,
            "vehicle_position": self.vehicle_position,
            "ee_position": self.ee_position,
            "ee_rotation": self.ee_rotation,
            "target_position": self.target_position,
            "manipulability": self.manipulability,
        }
        if self.has_yaw and self.eta.shape[1]:
            data["yaw"] = self.eta[:, -1].copy()
        if self.manipulability_floor is not None:
            data["manipulability_floor"] = self.manipulability_floor
        if self.payload_moment is not None:
            data["payload_moment"] = self.payload_moment
            data["payload_objective"] = self.payload_objective
        return data
