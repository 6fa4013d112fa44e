"""Station keeping: hold the vehicle pose (any subset of its coordinates)."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_vector
from ..errors import InputError
from ..model.transforms import matrix_to_rpy
from ._common import ANGLE_AXES, as_pose, check_choice, parse_axes, pose_units
from .error_task import ErrorTask
from .slot import TaskSlot

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_ALL = ("x", "y", "z", "phi", "theta", "psi")
_TWO_PI = 2.0 * math.pi
_ACTUATOR = {"phi": "p", "theta": "q"}


class _Held(TaskSlot):
    """The pose held at the first evaluation (``hold="activation"``)."""

    __slots__ = ("held",)

    def clear(self) -> None:
        super().clear()
        self.held: FloatArray | None = None


class StationKeepingTask(ErrorTask):
    r"""Hold the vehicle pose ``eta`` on selected coordinates at a set point.

    Rows ``J_eta,S zeta = K (eta_d - eta)_S`` over the selected coordinates ``S`` (angles wrapped to
    ``[-pi, pi)``), with ``J_eta`` the vehicle-pose Jacobian (``eta_dot = J_eta zeta``, NED, Z-Y-X
    Euler angles). Error [m, rad], rows [m/s, rad/s].

    The set point is ``target`` (values for the selected coordinates, in order), or, when None:
    ``hold="activation"`` (default) the pose at the first evaluation after construction or
    :meth:`reset`; ``hold="current"`` the pose at every tick, so the rows ask for zero vehicle
    motion, as in Soylu et al. (2007), Section 3 ("the current URV position value is
    entered as the desired position values for the next step").

    Args:
        axes: Coordinates to hold, from ``x, y, z, phi, theta, psi`` (planar ``x, y, psi``);
            default: the whole pose the vehicle controls, ``x, y, z, psi`` plus ``phi`` and
            ``theta`` when roll and pitch are actuated (planar ``x, y, psi``): an actuated
            attitude left free is one a lower-priority wish may tilt. Roll/pitch only if
            actuated.
        target: Set point for the selected coordinates [m, rad], or None (see ``hold``).
        pose: Alternatively the set point as a vehicle pose in the world frame
            (``pinocchio.SE3``, 4x4 homogeneous matrix or ``{"xyz", "rpy"}``); its selected
            coordinates (position, Z-Y-X Euler angles) are held.
        hold: ``"activation"`` or ``"current"`` when no target is given.
        blend: Name of a :class:`~uvms_qp.tasks.ManipulabilityTask` in mode ``"shaping"`` of the
            same stack: the demand is scaled by ``1 - k(w)`` (Soylu et al. (2007),
            Eq. (21): station keeping gives way to singularity avoidance as ``w`` drops).
        gain: Gain K [1/s], scalar or per coordinate.
        weight: Weight within the level.
        name: Task name (default ``"station_keeping"``).
    """

    type_name = "station_keeping"
    Slot = _Held
    error_unit = "m, rad"
    rate_unit = "m/s, rad/s"

    def __init__(self, *, axes: list[str] | None = None, target: list[float] | None = None,
                 pose: Any = None, hold: Literal["activation", "current"] = "activation",
                 blend: str | None = None, gain: float | list[float] = 1.0,
                 weight: float = 1.0, name: str | None = None) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self._axes_arg = None if axes is None else parse_axes(axes, _ALL, f"{self.name}.axes")
        self.hold = check_choice(hold, ("activation", "current"), f"{self.name}.hold")
        if blend is not None and (not isinstance(blend, str) or not blend):
            raise InputError(f"{self.name}.blend: expected a task name, got {blend!r}")
        self.blend = blend
        self._blend_task: Any = None
        self.target: FloatArray | None = None
        self.pose: FloatArray | None = None
        if target is not None or pose is not None:
            values = self._set_point(target, pose)
            self.target, self.pose = values["target"], values["pose"]
        self.axes: list[str] = []
        self._eta_pos: list[int] = []
        self._idx: Any = None
        self._angle_pos: list[int] = []
        self._fixed: FloatArray | None = None  # the set point when it is not held

    def _bind(self, model: Model) -> int:
        known = model.eta_names
        if not known:
            raise InputError(f"{self.name}: model {model.name!r} has a fixed base; station keeping "
                             "needs a vehicle")
        if self._axes_arg is None:
            axes = (["x", "y", "psi"] if model.vehicle_kind == "planar" else
                    ["x", "y", "z", *(a for a in ("phi", "theta")
                                      if _ACTUATOR[a] in model.actuated), "psi"])
        else:
            axes = self._axes_arg
        for a in axes:
            if a not in known:
                raise InputError(f"{self.name}.axes: {a!r} is not a coordinate of the "
                                 f"{model.vehicle_kind} vehicle; known: {', '.join(known)}")
            if a in _ACTUATOR and _ACTUATOR[a] not in model.actuated:
                raise InputError(f"{self.name}.axes: {a!r} is passive on model {model.name!r} "
                                 f"(actuated: {', '.join(model.actuated)})")
        if self.target is not None and self.target.shape[0] != len(axes):
            raise InputError(f"{self.name}.target: expected {len(axes)} values for axes "
                             f"{axes}, got {self.target.shape[0]}")
        self.axes = list(axes)
        self._eta_pos = [known.index(a) for a in axes]
        # None: every coordinate of eta in order (its arrays used as they are, no copy)
        self._idx = (None if self._eta_pos == list(range(len(known)))
                     else np.array(self._eta_pos, dtype=np.intp))
        self._angle_pos = [i for i, a in enumerate(axes) if a in ANGLE_AXES]
        self.error_unit, self.rate_unit = pose_units(axes)
        return len(axes)

    def _derive(self) -> None:
        super()._derive()
        self._fixed = None
        if self.pose is not None and self.model is not None:
            self._fixed = self._pose_eta(self.model, self.pose)[self._eta_pos]
        elif self.target is not None:
            self._fixed = np.array(self.target)

    @staticmethod
    def _pose_eta(model: Model, T: FloatArray) -> FloatArray:
        """``eta`` of a world pose of the vehicle (planar: x, y and the yaw)."""
        if model.vehicle_kind == "spatial":
            return np.concatenate((T[:3, 3], matrix_to_rpy(T[:3, :3])))
        return np.array((T[0, 3], T[1, 3], math.atan2(T[1, 0], T[0, 0])))

    def link(self, tasks: dict[str, Any]) -> None:
        """Find the manipulability task named by ``blend``."""
        if self.blend is None:
            return
        other = tasks.get(self.blend)
        if other is None:
            raise InputError(f"{self.name}.blend: no task named {self.blend!r}; known tasks: "
                             f"{', '.join(tasks)}")
        if not callable(getattr(other, "shaping_factor", None)):
            raise InputError(f"{self.name}.blend: {self.blend!r} is not a manipulability task "
                             "in mode 'shaping'")
        self._blend_task = other

    def set_target(self, target: Any = None, *, pose: Any = None) -> None:
        """Set the held values for the selected coordinates [m, rad], or a vehicle pose.

        The scenario keys are the same (``update = { target = [...] }`` or ``pose``).

        Args:
            target: Values for the selected coordinates, in order.
            pose: Alternatively a world pose of the vehicle (``pinocchio.SE3``, 4x4 or
                ``{"xyz", "rpy"}``); its selected coordinates (position, Z-Y-X Euler angles)
                are held.
        """
        if (target is None) == (pose is None):
            raise InputError(f"{self.name}.set_target: give target= or pose=")
        self.update(**({"target": target} if pose is None else {"pose": pose}))

    def _set_point(self, target: Any, pose: Any) -> dict[str, Any]:
        """The validated set point: values for the axes, or a pose (one of them)."""
        if target is not None and pose is not None:
            raise InputError(f"{self.name}: give target= or pose=, not both")
        if pose is not None:
            return {"target": None, "pose": as_pose(pose, f"{self.name}.pose")}
        n = len(self.axes) if getattr(self, "axes", None) else None
        return {"target": as_vector(target, f"{self.name}.target", n).copy(), "pose": None}

    def error_rows(self, state: State, t: float, slot: TaskSlot
                   ) -> tuple[FloatArray, FloatArray, None]:
        """``(J_eta,S, (eta_d - eta)_S, None)``, angles wrapped [m, rad]."""
        idx = self._idx
        if idx is None:
            eta, J = state.eta, state.vehicle_pose_jacobian()
        else:
            eta, J = state.eta.take(idx), state.vehicle_pose_jacobian().take(idx, axis=0)
        target = self._fixed
        if target is None:
            if self.hold == "current":
                return J, np.zeros(len(self.axes)), None
            target = slot.held  # type: ignore[attr-defined]
            if target is None:
                target = slot.held = eta.copy()  # type: ignore[attr-defined]
        e = target - eta
        for i in self._angle_pos:
            e[i] = (e.item(i) + math.pi) % _TWO_PI - math.pi
        if self._blend_task is not None:
            peers = slot.peers
            e *= 1.0 - self._blend_task.shaping_factor(
                state, None if peers is None else peers.get(self._blend_task))
        return J, e, None

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "target", "pose")

    def _checked(self, params: dict[str, Any]) -> dict[str, Any]:
        values = {k: self._check(k, v) for k, v in params.items() if k not in ("target", "pose")}
        if "target" in params or "pose" in params:
            values.update(self._set_point(params.get("target"), params.get("pose")))
        return values
