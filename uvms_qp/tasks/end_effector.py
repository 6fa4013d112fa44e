"""End-effector (any frame) position / orientation / pose tracking task."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

from .._validation import FloatArray
from ..errors import InputError
from ..model.selection import compact_index
from ._checks import check_frame_name
from ._common import (
    TWIST_AXES,
    check_choice,
    check_frame,
    check_planar_point,
    parse_axes,
    pose_units,
)
from ._frame_rows import pose_rows, skew
from .error_task import ErrorTask
from .slot import TaskSlot
from .targets import (
    HeldPose,
    InFrame,
    Target,
    TrajectoryTarget,
    check_trajectory,
    target_from,
)

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_MODE_AXES = {"position": ("x", "y", "z"), "orientation": ("rx", "ry", "rz"), "pose": TWIST_AXES}
_PLANAR_AXES = {"position": ["x", "y"], "orientation": ["rz"], "pose": ["x", "y", "rz"]}
_TARGET_KEYS = ("position", "rotation", "velocity", "angular_velocity", "pose", "target",
                "trajectory", "hold")


class _Held(TaskSlot):
    """A held pose ``(p, R)`` in the reference frame and the target it was held for."""

    __slots__ = ("held", "held_for")

    def clear(self) -> None:
        super().clear()
        self.held: tuple[FloatArray, FloatArray] | None = None
        self.held_for: Any = None


class EndEffectorTask(ErrorTask):
    r"""Track the position, orientation or full pose of a frame, on any subset of world axes.

    Closed-loop inverse kinematics (Soylu et al. (2007), Eq. (16)), in world axes:

    * position rows:  ``J_p zeta = p_dot_d + K (p_d - p)``, error [m], rows [m/s];
    * orientation rows: with ``R_e = R_d R^T`` and ``e_o = log(R_e)`` (SO(3) log map, world axes,
      [rad]) the exact error dynamics are ``e_o_dot = Jlog(R_e)^T omega_d - Jlog(R_e) omega``
      (``Jlog`` = inverse right Jacobian of SO(3)), hence the rows
      ``Jlog(R_e) J_omega zeta = Jlog(R_e)^T omega_d + K e_o`` [rad/s].

    ``J_p``, ``J_omega`` are the frame's position and angular Jacobians over zeta (world axes).
    The mode picks the axes (``x, y, z``, ``rx, ry, rz`` or both; planar models default to
    ``x, y``, ``rz``, ``x, y, rz``); ``axes`` selects a subset of them.

    **Target** (:mod:`uvms_qp.tasks.targets`, changed at run time with :meth:`set_target`, the
    same keys in scenario files): fixed (``position`` [m] and/or ``rotation`` 3x3 or
    ``[roll, pitch, yaw]`` [rad], or ``pose``: a ``pinocchio.SE3``, a 4x4 homogeneous matrix or
    ``{"xyz", "rpy"}``), a ``trajectory`` (``sample(t)``), or ``hold="activation"``: the frame's
    pose at the first evaluation after the controller is built or reset, or the task enters the
    stack ("stay where you are now").

    **Reference frame.** The target is expressed in ``reference`` (default ``"world"``): any
    frame of the model. A target in a moving frame is re-evaluated every tick
    (``p_d = p_r + R_r p_target``, ``R_d = R_r R_target``) and its motion enters the rows:
    ``J_p`` becomes ``J_p - (J_v,r - [p_d - p_r]_x J_omega,r)`` and the orientation rows
    ``Jlog(R_e) J_omega - Jlog(R_e)^T J_omega,r`` (with ``omega_d = omega_r``), so the stack
    knows that moving the reference moves the target. Feed-forward rates of a trajectory are
    rotated into world axes.

    Args:
        frame: Name of the controlled frame (default ``"tool"``).
        mode: ``"position"``, ``"orientation"`` or ``"pose"``.
        axes: Subset of the mode's axes to control (None: all; planar models: the in-plane ones).
        position, rotation, pose, trajectory, hold: The target (see :meth:`set_target`);
            ``target`` is another name of ``pose``.
        reference: Frame in which the target is expressed (default ``"world"``).
        gain: Gain K [1/s], scalar or one per selected axis.
        weight: Weight within the level.
        name: Task name (default: the frame's name).
    """

    type_name = "end_effector"
    error_unit = "m, rad"
    rate_unit = "m/s, rad/s"
    Slot = _Held

    def __init__(self, frame: str = "tool", *,
                 mode: Literal["position", "orientation", "pose"] = "position",
                 axes: list[str] | None = None, position: list[float] | None = None,
                 rotation: list[list[float]] | list[float] | None = None, pose: Any = None,
                 target: Any = None, trajectory: Any = None, reference: str = "world",
                 hold: Literal["activation"] | None = None, gain: float | list[float] = 1.0,
                 weight: float = 1.0, name: str | None = None) -> None:
        frame = check_frame_name(frame, f"{name or frame}.frame")
        super().__init__(name=name if name is not None else frame, weight=weight, gain=gain)
        self.reference = check_frame_name(reference, f"{self.name}.reference")
        if reference == frame:
            raise InputError(f"{self.name}.reference: {frame!r} is the controlled frame itself; "
                             "a target fixed to the frame it moves is always met")
        self.mode = check_choice(mode, tuple(_MODE_AXES), f"{self.name}.mode")
        self.frame = frame
        self._axes_arg = None if axes is None else self._parse_axes(axes)
        self.axes: list[str] = []
        self._need_p = mode != "orientation"
        self._need_o = mode != "position"
        self._sel: Any = slice(0, 3)
        self._all_axes = self._simple = False
        self._nv = 0
        keys = {k: v for k, v in (("position", position), ("rotation", rotation), ("pose", pose),
                                  ("target", target), ("trajectory", trajectory), ("hold", hold))
                if v is not None}
        self.setpoint: Target | None = None
        self.setpoint = self._new_target(keys) if keys else None

    def _parse_axes(self, axes: Any) -> list[str]:
        """Validate ``axes`` for the mode; an axis of another mode says which mode it needs."""
        allowed = _MODE_AXES[self.mode]
        for a in [axes] if isinstance(axes, str) else axes if isinstance(axes, list | tuple) \
                else ():
            if isinstance(a, str) and a in TWIST_AXES and a not in allowed:
                needs = ('mode = "orientation" or "pose"' if a.startswith("r")
                         else 'mode = "position" or "pose"')
                raise InputError(
                    f"{self.name}.axes: axis {a!r} is not controlled in mode {self.mode!r} "
                    f"(known axes: {', '.join(allowed)}); {a!r} needs {needs}")
        return parse_axes(axes, allowed, f"{self.name}.axes")

    # ------------------------------------------------------------------------------------ target
    def set_target(self, position: Any = None, rotation: Any = None, *, pose: Any = None,
                   trajectory: Any = None, hold: str | None = None, velocity: Any = None,
                   angular_velocity: Any = None) -> None:
        """Set the target, in the reference frame; the same keys in scenario files.

        Args:
            position: Target position (3,) [m] (2 values ``(x, y)`` only on planar models, where
                z = 0). A fixed rotation set before is kept.
            rotation: Target rotation (3x3, orthonormal) or ``[roll, pitch, yaw]`` [rad].
            pose: Target pose: a ``pinocchio.SE3``, a 4x4 homogeneous matrix or
                ``{"xyz", "rpy"}``; not with ``position`` or ``rotation``.
            trajectory: An object with ``sample(t)`` (see the class docstring); a fixed
                ``rotation`` given with it serves when its samples have none.
            hold: ``"activation"``: hold the frame's pose at the next evaluation.
            velocity: Feed-forward linear velocity (3,) [m/s] of a fixed target (default zero).
            angular_velocity: Feed-forward angular velocity (3,) [rad/s].

        Raises:
            InputError: no target, or targets that exclude each other; not a rigid transform;
                not a rotation; a trajectory without ``sample``.
            ShapeError: wrong sizes (a 2-value position on a model that is not planar).
        """
        keys = {k: v for k, v in (("position", position), ("rotation", rotation), ("pose", pose),
                                  ("trajectory", trajectory), ("hold", hold),
                                  ("velocity", velocity), ("angular_velocity", angular_velocity))
                if v is not None}
        self.update(**keys)

    def _new_target(self, keys: dict[str, Any]) -> Target:
        """The target of the keys of :meth:`set_target` (validated; nothing assigned)."""
        return target_from(keys, self.name, self.reference, self.model, self.setpoint)

    @property
    def has_target(self) -> bool:
        """True once a target is set (a held one counts: it is taken at the first evaluation)."""
        return self.setpoint is not None

    def frame_pose(self, state: State) -> FloatArray:
        """The controlled frame's pose (4, 4) in the reference frame at ``state`` [m]."""
        return (state.pose(self.frame) if self.reference == "world"
                else state.pose_in(self.frame, self.reference))

    def target(self, t: float, state: State | None = None, slot: TaskSlot | None = None
                  ) -> tuple[FloatArray | None, FloatArray | None]:
        """Target ``(position [m], rotation)`` at time ``t`` [s] (None where not set).

        In the reference frame, or in the world frame when ``state`` is given. A held target
        is the one kept in ``slot`` (None before the slot's first evaluation).
        """
        target = self.setpoint
        if target is None:
            return None, None
        if isinstance(target, InFrame):
            target = target.target
        if isinstance(target, HeldPose):
            held = None if slot is None or slot.held_for is not target else slot.held  # type: ignore[attr-defined]
            p, R = (None, None) if held is None else held
        else:
            p, R, _, _ = target.sample(t, state, slot, self)  # type: ignore[arg-type]
        if state is not None and self.reference != "world":
            T = state.pose(self.reference)
            p = None if p is None else T[:3, :3] @ p + T[:3, 3]
            R = None if R is None else T[:3, :3] @ R
        return p, R

    # ----------------------------------------------------------------------------------- binding
    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        check_frame(model, self.reference, f"{self.name}.reference")
        target = self.setpoint.target if isinstance(self.setpoint, InFrame) else self.setpoint
        for key in getattr(target, "planar", ()):
            check_planar_point(f"{self.name}.{key}", model.vehicle_kind)
        if isinstance(target, TrajectoryTarget):
            check_trajectory(target.trajectory, model.vehicle_kind, self.name)
        axes = (self._axes_arg if self._axes_arg is not None else _PLANAR_AXES[self.mode]
                if model.vehicle_kind == "planar" else list(_MODE_AXES[self.mode]))
        self.axes = list(axes)
        offset = 0 if self._need_p else 3  # orientation rows only: rx is their row 0
        self._all_axes = len(axes) == len(_MODE_AXES[self.mode])
        self._simple = self._all_axes and not self._need_o and self.reference == "world"
        self._sel = compact_index([TWIST_AXES.index(a) - offset for a in axes])
        self._nv = model.nv
        self.error_unit, self.rate_unit = pose_units(axes)
        return len(axes)

    # -------------------------------------------------------------------------------- evaluation
    def error_rows(self, state: State, t: float, slot: TaskSlot
                   ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """``(J, e, ff)`` on the selected axes, world axes (see the class docstring)."""
        target = self.setpoint
        if target is None:
            raise InputError(f"task {self.name!r}: target never set; pass position=/rotation=/"
                             "pose=/trajectory= or hold='activation', or call set_target()")
        p_d, R_d, v_d, w_d = target.sample(t, state, slot, self)
        if (p_d is None and self._need_p) or (R_d is None and self._need_o):
            missing = "position" if p_d is None and self._need_p else "rotation"
            raise InputError(f"task {self.name!r}: target never set (no {missing}); pass "
                             "position=/rotation=/pose=/trajectory= or hold='activation', or "
                             "call set_target()")
        frame = self.frame
        if self._simple:  # world target, every position axis
            return state.jacobian(frame, "position"), p_d - state.position(frame), v_d
        J = state.jacobian(frame)
        if self.reference != "world":
            J, e, ff = self._relative_rows(state, J, p_d, R_d, v_d, w_d)
        elif self._need_o:
            J, e, ff = pose_rows(J, state.pose(frame), p_d, R_d, v_d, w_d, None, self._need_p)
        else:
            J, e, ff = J[:3], p_d - state.position(frame), v_d
        if self._all_axes:
            return J, e, ff
        sel = self._sel
        return J[sel], e[sel], None if ff is None else ff[sel]

    def _relative_rows(self, state: State, J: FloatArray, p_t: Any, R_t: Any, v_t: Any,
                       w_t: Any) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """Rows for a target fixed in a moving reference frame (all axes of the mode)."""
        T_r = state.pose(self.reference)
        J_r = state.jacobian(self.reference)
        R_r, p_r = T_r[:3, :3], T_r[:3, 3]
        v_d = None if v_t is None else R_r @ v_t
        w_d = None if w_t is None else R_r @ w_t
        p_d = None if p_t is None else p_r + R_r @ p_t
        if self._need_p:
            # the target point moves with the reference: v = v_r + omega_r x (p_d - p_r)
            J_target = J_r[:3] - skew(p_d - p_r) @ J_r[3:]  # type: ignore[operator]
            if not self._need_o:
                return J[:3] - J_target, p_d - state.position(self.frame), v_d  # type: ignore[operator]
        rows, e, ff = pose_rows(J, state.pose(self.frame), p_d, R_r @ R_t, v_d, w_d, J_r,
                                self._need_p)
        if self._need_p:
            rows[:3] -= J_target
        return rows, e, ff

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update` (the target keys of :meth:`set_target`)."""
        return (*super().updatable(), *_TARGET_KEYS)

    def _checked(self, params: dict[str, Any]) -> dict[str, Any]:
        values = {k: self._check(k, v) for k, v in params.items() if k not in _TARGET_KEYS}
        keys = {k: v for k, v in params.items() if k in _TARGET_KEYS}
        if keys:
            values["setpoint"] = self._new_target(keys)
        return values
