"""End-effector (any frame) position / orientation / pose tracking task."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np
import pinocchio as pin

from .._validation import FloatArray, as_vector
from ..errors import InputError, ShapeError
from ..model.selection import compact_index
from ._common import (
    TWIST_AXES,
    as_point,
    as_pose,
    as_rotation,
    check_choice,
    check_frame,
    check_planar_point,
    parse_axes,
    pose_units,
)
from .task import ErrorTask

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_MODE_AXES = {
    "position": ("x", "y", "z"),
    "orientation": ("rx", "ry", "rz"),
    "pose": TWIST_AXES,
}
_PLANAR_AXES = {"position": ["x", "y"], "orientation": ["rz"], "pose": ["x", "y", "rz"]}
_HOLD = ("activation",)
_POINT = (3,)  # the shape of a sampled position or (angular) velocity
_ROTATION = (3, 3)  # the shape of a sampled rotation


def _skew(r: FloatArray) -> FloatArray:
    """``[r]_x`` with ``[r]_x w = r x w``."""
    x, y, z = r.tolist()
    return np.array(((0.0, -z, y), (z, 0.0, -x), (-y, x, 0.0)))


class EndEffectorTask(ErrorTask):
    r"""Track the position, orientation or full pose of a frame, on any subset of world axes.

    Closed-loop inverse kinematics (Soylu et al. (2007), Eq. (16)), in world axes:

    * position rows:  ``J_p zeta = p_dot_d + K (p_d - p)``, error [m], rows [m/s];
    * orientation rows: with ``R_e = R_d R^T`` and ``e_o = log(R_e)`` (SO(3) log map, world axes,
      [rad]) the exact error dynamics are ``e_o_dot = Jlog(R_e)^T omega_d - Jlog(R_e) omega``
      (``Jlog`` = inverse right Jacobian of SO(3)), hence the rows
      ``Jlog(R_e) J_omega zeta = Jlog(R_e)^T omega_d + K e_o`` [rad/s].

    ``J_p``, ``J_omega`` are the frame's position and angular Jacobians over zeta (world axes).
    The selected axes pick rows of ``[e_p; e_o]`` (``x, y, z, rx, ry, rz``). Planar models default
    to ``x, y`` (position), ``rz`` (orientation).

    **Target.** Fixed (``position`` [m] and/or ``rotation`` 3x3 or ``[roll, pitch, yaw]`` [rad],
    or ``target``: a ``pinocchio.SE3``, a 4x4 homogeneous matrix or ``{"xyz", "rpy"}``), a
    trajectory (any object with ``sample(t)`` returning ``position``, ``velocity`` and
    optionally ``rotation``, ``angular_velocity``), or ``hold="activation"``: the frame's pose at
    the first evaluation after :meth:`bind` or :meth:`reset` ("stay where you are now"). Change
    it at run time with :meth:`set_target`, :meth:`track` or :meth:`update`.

    **Reference frame.** All of these are expressed in ``reference`` (default ``"world"``): any
    frame of the model, e.g. ``"vehicle"``, ``"arm_base"`` or a link carrying an object. A target
    in a moving frame is re-evaluated every tick (``p_d = p_r + R_r p_target``,
    ``R_d = R_r R_target``) and its motion enters the rows: they regulate the frame relative to
    the target, ``J_p`` becomes ``J_p - (J_v,r - [p_d - p_r]_x J_omega,r)`` and the orientation
    rows ``Jlog(R_e) J_omega - Jlog(R_e)^T J_omega,r`` (with ``omega_d = omega_r``), so the
    stack knows that moving the reference moves the target. Feed-forward rates of a trajectory
    are rotated into world axes.

    Args:
        frame: Name of the controlled frame (default ``"tool"``).
        mode: ``"position"``, ``"orientation"`` or ``"pose"``.
        axes: Subset of the mode's axes to control (None: all; planar models: the in-plane ones).
        position: Fixed target position (3,) [m] in ``reference``.
        rotation: Fixed target rotation ``R_reference_target`` (3x3) or ``[roll, pitch, yaw]``
            [rad].
        target: Fixed target pose in ``reference`` (SE3, 4x4 or ``{"xyz", "rpy"}``); not with
            ``position`` or ``rotation``.
        trajectory: Object with ``sample(t)`` (see above); overrides the fixed target.
        reference: Frame in which the target is expressed (default ``"world"``).
        hold: ``"activation"`` to hold the pose the frame has at the first evaluation, or None.
        gain: Gain K [1/s], scalar or one per selected axis.
        weight: Weight within the level.
        name: Task name (default ``"end_effector"``).
        activation: Initial activation in [0, 1] (1: in the stack; see
            :class:`~uvms_qp.tasks.Task`).
    """

    type_name = "end_effector"
    error_unit = "m, rad"
    rate_unit = "m/s, rad/s"

    def __init__(
        self,
        frame: str = "tool",
        *,
        mode: Literal["position", "orientation", "pose"] = "position",
        axes: list[str] | None = None,
        position: list[float] | None = None,
        rotation: list[list[float]] | list[float] | None = None,
        target: Any = None,
        trajectory: Any = None,
        reference: str = "world",
        hold: Literal["activation"] | None = None,
        gain: float | list[float] = 1.0,
        weight: float = 1.0,
        name: str | None = None,
        activation: float = 1.0,
    ) -> None:
        super().__init__(name=name, weight=weight, gain=gain, activation=activation)
        if not isinstance(frame, str) or not frame:
            raise InputError(f"{self.name}.frame: expected a frame name, got {frame!r}")
        if not isinstance(reference, str) or not reference:
            raise InputError(f"{self.name}.reference: expected a frame name, got {reference!r}")
        if reference == frame:
            raise InputError(f"{self.name}.reference: {frame!r} is the controlled frame itself; "
                             "a target fixed to the frame it moves is always met")
        self.mode = check_choice(mode, tuple(_MODE_AXES), f"{self.name}.mode")
        self.frame = frame
        self.reference = reference
        self.hold = None if hold is None else check_choice(hold, _HOLD, f"{self.name}.hold")
        self._axes_arg = None if axes is None else self._parse_axes(axes)
        self.axes: list[str] = []
        self._need_p = mode != "orientation"
        self._need_o = mode != "position"
        # the target in the reference frame: position, rotation and feed-forward rates
        self._p_d: FloatArray | None = None
        self._R_d: FloatArray | None = None
        self._v_d: FloatArray | None = None  # None: zero
        self._w_d: FloatArray | None = None  # None: zero
        self._trajectory: Any = None
        self._planar_points: set[str] = set()  # arguments given as (x, y), checked at bind
        self._sel: Any = slice(0, 3)
        self._all_axes = True
        self._simple = False
        self._nv = 0
        given = [k for k, v in (("position", position), ("rotation", rotation),
                                ("target", target), ("trajectory", trajectory)) if v is not None]
        if target is not None and (position is not None or rotation is not None):
            raise InputError(f"{self.name}: give target= (a pose) or position=/rotation=, "
                             "not both")
        if self.hold is not None and given:
            raise InputError(f"{self.name}.hold: the target comes from the state; do not also "
                             f"give {', '.join(given)}")
        if target is not None:
            self.set_target(pose=target)
        elif position is not None or rotation is not None:
            self.set_target(position=position, rotation=rotation)
        if trajectory is not None:
            self.track(trajectory)

    def _parse_axes(self, axes: Any) -> list[str]:
        """Validate ``axes`` for the mode; an axis of another mode says which mode it needs."""
        allowed = _MODE_AXES[self.mode]
        names = [axes] if isinstance(axes, str) else axes
        if isinstance(names, list | tuple):
            for a in names:
                if isinstance(a, str) and a in TWIST_AXES and a not in allowed:
                    needs = ('mode = "orientation" or "pose"' if a.startswith("r")
                             else 'mode = "position" or "pose"')
                    raise InputError(
                        f"{self.name}.axes: axis {a!r} is not controlled in mode {self.mode!r} "
                        f"(known axes: {', '.join(allowed)}); {a!r} needs {needs}")
        return parse_axes(axes, allowed, f"{self.name}.axes")

    # ------------------------------------------------------------------------------------ target
    def set_target(self, position: Any = None, rotation: Any = None, velocity: Any = None,
                   angular_velocity: Any = None, *, pose: Any = None) -> None:
        """Set a fixed target (and optional feed-forward rates) in the reference frame.

        Stops tracking a trajectory and holding.

        Args:
            position: Target position (3,) [m] (2 values ``(x, y)`` only on planar models, where
                z = 0; a ShapeError on the others).
            rotation: Target rotation (3x3, orthonormal) or ``[roll, pitch, yaw]`` [rad].
            velocity: Feed-forward linear velocity (3,) [m/s] (default zero).
            angular_velocity: Feed-forward angular velocity (3,) [rad/s].
            pose: Target pose (``pinocchio.SE3``, 4x4 homogeneous matrix or
                ``{"xyz", "rpy"}``); not with ``position`` or ``rotation``.

        Raises:
            InputError: ``pose`` together with ``position`` or ``rotation``; not a rigid
                transform; not a rotation.
            ShapeError: wrong sizes.
        """
        if pose is not None:
            if position is not None or rotation is not None:
                raise InputError(f"{self.name}: give pose= or position=/rotation=, not both")
            T = as_pose(pose, f"{self.name}.target")
            position, rotation = T[:3, 3], T[:3, :3]
            self._planar_points.discard("position")
        if position is not None:
            self._p_d = self._point(position, "position")
        if rotation is not None:
            self._R_d = as_rotation(rotation, f"{self.name}.rotation")
        self._v_d = None if velocity is None else self._point(velocity, "velocity")
        if velocity is None:
            self._planar_points.discard("velocity")
        self._w_d = (None if angular_velocity is None
                     else as_vector(angular_velocity, f"{self.name}.angular_velocity", 3))
        self._trajectory = None
        self.hold = None

    def track(self, trajectory: Any) -> None:
        """Follow ``trajectory`` (an object with ``sample(t)``, in the reference frame) from now on.

        Raises:
            InputError: no ``sample`` method.
            ShapeError: (once bound) the trajectory's points have 2 coordinates and the model
                is not planar, or its samples are not 3-vectors.
        """
        if not callable(getattr(trajectory, "sample", None)):
            raise InputError(f"{self.name}.trajectory: expected an object with sample(t), "
                             f"got {type(trajectory).__name__}")
        if self.model is not None:
            self._check_trajectory(trajectory, self.model.vehicle_kind)
        self._trajectory = trajectory
        self._planar_points.clear()
        self.hold = None

    def _check_trajectory(self, trajectory: Any, vehicle_kind: str) -> None:
        """Reject a trajectory whose positions do not fit the model.

        The number of coordinates is the trajectory's ``dimension`` attribute when it has one
        (2 for points given as ``(x, y)``, see :mod:`uvms_qp.sim.trajectories`), else the size
        of its position sampled once at its start time.

        Raises:
            ShapeError: 2 coordinates on a non-planar model (as for a 2-value ``position``), or
                a sampled position that is not a 3-vector.
        """
        label = f"{self.name}.trajectory"
        dimension = getattr(trajectory, "dimension", None)
        if dimension is None:
            start = getattr(trajectory, "start_time", 0.0)
            sample = trajectory.sample(start if isinstance(start, int | float) else 0.0)
            position = getattr(sample, "position", None)
            if position is None:
                raise self._not_a_sample(sample)
            dimension = int(np.size(position))
            if dimension == 2:
                check_planar_point(label, vehicle_kind)
            if dimension != 3:
                raise ShapeError(f"{label}: sample(t).position has {dimension} coordinates; "
                                 "expected 3 (x, y, z), with z = 0 on planar models")
        elif dimension == 2:
            check_planar_point(label, vehicle_kind)

    def _point(self, value: Any, key: str) -> FloatArray:
        """Validate a point argument; remember a 2-value one until the model kind is known."""
        kind = None if self.model is None else self.model.vehicle_kind
        p = as_point(value, f"{self.name}.{key}", kind)
        if kind is None and np.size(value) == 2:
            self._planar_points.add(key)
        else:
            self._planar_points.discard(key)
        return p

    @property
    def has_target(self) -> bool:
        """True when a target (fixed, trajectory or held pose) is set for what the mode needs."""
        if self._trajectory is not None or self.hold is not None:
            return True
        return (not self._need_p or self._p_d is not None) and (
            not self._need_o or self._R_d is not None)

    def target(self, t: float, state: State | None = None
               ) -> tuple[FloatArray | None, FloatArray | None]:
        """Target ``(position [m], rotation)`` at time ``t`` [s] (None where not set).

        In the reference frame, or in the world frame when ``state`` is given (the reference
        frame's pose read from it). A held target is None until the first evaluation.
        """
        if self.hold is not None and self._p_d is None and self._R_d is None:
            return None, None
        self._sample(t)
        p, R = self._p_d, self._R_d
        if state is not None and self.reference != "world":
            T = state.pose(self.reference)
            p = None if p is None else T[:3, :3] @ p + T[:3, 3]
            R = None if R is None else T[:3, :3] @ R
        return p, R

    def _sample(self, t: float) -> None:
        """Update the target from the trajectory at ``t`` (or check a fixed one is set)."""
        traj = self._trajectory
        if traj is None:
            if not self.has_target:
                missing = "position" if self._need_p and self._p_d is None else "rotation"
                raise InputError(f"task {self.name!r}: target never set (no {missing} and no "
                                 "trajectory); pass position=/rotation=/target=/trajectory= or "
                                 "hold='activation', or call set_target()/track()")
            return
        s = traj.sample(t)
        try:
            p, v = s.position, s.velocity
        except AttributeError:
            raise self._not_a_sample(s) from None
        p = np.asarray(p, dtype=np.float64)
        if v is not None:
            v = np.asarray(v, dtype=np.float64)
        if p.shape != _POINT or (v is not None and v.shape != _POINT):  # one check per tick
            raise self._sample_shape_error(t, position=p, velocity=v)
        self._p_d, self._v_d = p, v
        if self._need_o:
            rot = getattr(s, "rotation", None)
            if rot is not None:
                rot = np.asarray(rot, dtype=np.float64)
                w = getattr(s, "angular_velocity", None)
                if w is not None:
                    w = np.asarray(w, dtype=np.float64)
                if rot.shape != _ROTATION or (w is not None and w.shape != _POINT):
                    raise self._sample_shape_error(t, rotation=rot, angular_velocity=w)
                self._R_d, self._w_d = rot, w
            elif self._R_d is None:
                raise InputError(f"task {self.name!r}: the trajectory has no orientation and no "
                                 "fixed rotation target is set")
            else:
                self._w_d = None

    def _not_a_sample(self, sample: Any) -> InputError:
        """The error for a trajectory whose ``sample(t)`` has no ``position``/``velocity``."""
        return InputError(
            f"task {self.name!r}: trajectory.sample(t) returned a {type(sample).__name__}; "
            "expected a TrajectorySample (uvms_qp.sim.trajectories) or any object with "
            "attributes position (3,) [m] and velocity (3,) [m/s] or None, and optionally "
            "rotation (3, 3) and angular_velocity (3,) [rad/s]")

    def _sample_shape_error(self, t: float, **values: FloatArray | None) -> ShapeError:
        """The error naming the first of ``values`` (sampled at ``t`` [s]) of the wrong shape."""
        for key, value in values.items():
            expected = _ROTATION if key == "rotation" else _POINT
            if value is not None and value.shape != expected:
                break
        return ShapeError(f"task {self.name!r}: trajectory.sample({t:g}).{key} has shape "
                          f"{value.shape}; expected {expected}")  # type: ignore[union-attr]

    def _capture(self, state: State) -> None:
        """Hold the frame's current pose in the reference frame (``hold="activation"``)."""
        T = (state.pose(self.frame) if self.reference == "world"
             else state.pose_in(self.frame, self.reference))
        self._p_d = np.array(T[:3, 3])
        self._R_d = np.array(T[:3, :3])
        self._v_d = self._w_d = None

    def _reset(self) -> None:
        """Forget a held pose (a new one is taken at the next evaluation)."""
        if self.hold is not None:
            self._p_d = self._R_d = None

    # ----------------------------------------------------------------------------------- binding
    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        check_frame(model, self.reference, f"{self.name}.reference")
        for key in sorted(self._planar_points):
            check_planar_point(f"{self.name}.{key}", model.vehicle_kind)
        if self._trajectory is not None:
            self._check_trajectory(self._trajectory, model.vehicle_kind)
        if self._axes_arg is not None:
            axes = self._axes_arg
        elif model.vehicle_kind == "planar":
            axes = _PLANAR_AXES[self.mode]
        else:
            axes = list(_MODE_AXES[self.mode])
        self.axes = list(axes)
        rows = [TWIST_AXES.index(a) for a in axes]
        offset = 3 if self.mode == "orientation" else 0
        self._all_axes = len(axes) == len(_MODE_AXES[self.mode])
        self._simple = self._all_axes and self.mode == "position" and self.reference == "world"
        self._sel = compact_index([r - offset for r in rows])
        self._nv = model.nv
        self.error_unit, self.rate_unit = pose_units(axes)
        self.reset()
        return len(axes)

    # -------------------------------------------------------------------------------- evaluation
    def error_rows(self, state: State, t: float) -> tuple[FloatArray, FloatArray,
                                                          FloatArray | None]:
        """``(J, e, ff)`` on the selected axes, world axes (see the class docstring)."""
        if self._trajectory is not None:
            self._sample(t)
        elif (self._p_d is None and self._need_p) or (self._R_d is None and self._need_o):
            if self.hold is None:
                self._sample(t)  # raises: no target
            self._capture(state)
        frame = self.frame
        if self._simple:  # world target, every position axis
            e = self._p_d - state.position(frame)  # type: ignore[operator]
            return state.jacobian(frame, "position"), e, self._v_d
        J = state.jacobian(frame)
        if self.reference == "world":
            if self.mode == "position":
                e = self._p_d - state.position(frame)  # type: ignore[operator]
                J, ff = J[:3], self._v_d
            else:
                J, e, ff = self._pose_rows(J, state.pose(frame), self._p_d, self._R_d,
                                           self._v_d, self._w_d, None)
        else:
            J, e, ff = self._relative_rows(state, J)
        if self._all_axes:
            return J, e, ff
        sel = self._sel
        return J[sel], e[sel], None if ff is None else ff[sel]

    def _pose_rows(self, J: FloatArray, T: FloatArray, p_d: Any, R_d: Any, v_d: Any, w_d: Any,
                   J_ref: FloatArray | None) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """Rows of the orientation modes (all axes of the mode) in world axes.

        ``J_ref`` is the reference frame's twist Jacobian (None: the target does not move with
        zeta); ``p_d``, ``R_d``, ``v_d``, ``w_d`` the target and its rates in world axes.
        """
        R_e = R_d @ T[:3, :3].T
        Jlog = pin.Jlog3(R_e)
        e_o = pin.log3(R_e)
        rows = np.empty((6 if self._need_p else 3, self._nv))
        J_o = rows[3:] if self._need_p else rows
        np.dot(Jlog, J[3:], out=J_o)
        if J_ref is not None:
            J_o -= Jlog.T @ J_ref[3:]
        ff_o = None if w_d is None else Jlog.T @ w_d
        if not self._need_p:
            return rows, e_o, ff_o
        rows[:3] = J[:3]
        e = np.concatenate((p_d - T[:3, 3], e_o))
        if v_d is None and ff_o is None:
            return rows, e, None
        ff = np.zeros(6)
        if v_d is not None:
            ff[:3] = v_d
        if ff_o is not None:
            ff[3:] = ff_o
        return rows, e, ff

    def _relative_rows(self, state: State, J: FloatArray
                       ) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """Rows for a target fixed in a moving reference frame (all axes of the mode)."""
        T_r = state.pose(self.reference)
        J_r = state.jacobian(self.reference)
        R_r, p_r = T_r[:3, :3], T_r[:3, 3]
        v_d = None if self._v_d is None else R_r @ self._v_d
        w_d = None if self._w_d is None else R_r @ self._w_d
        p_d = None if self._p_d is None else p_r + R_r @ self._p_d
        if self._need_p:
            # the target point moves with the reference: v = v_r + omega_r x (p_d - p_r)
            J_target = J_r[:3] - _skew(p_d - p_r) @ J_r[3:]  # type: ignore[operator]
        if self.mode == "position":
            return J[:3] - J_target, p_d - state.position(self.frame), v_d  # type: ignore[operator]
        rows, e, ff = self._pose_rows(J, state.pose(self.frame), p_d,
                                      R_r @ self._R_d, v_d, w_d, J_r)  # type: ignore[operator]
        if self._need_p:
            rows[:3] -= J_target
        return rows, e, ff

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "position", "rotation", "target", "trajectory", "hold")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "position":
            self.set_target(position=value, rotation=self._R_d)
        elif key == "rotation":
            self.set_target(position=self._p_d, rotation=value)
        elif key == "target":
            self.set_target(pose=value)
        elif key == "trajectory":
            self.track(value)
        elif key == "hold":
            self.hold = check_choice(value, _HOLD, f"{self.name}.hold")
            self._trajectory = None
            self._p_d = self._R_d = None
        else:
            super()._apply_update(key, value)
