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
    as_rotation,
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


class EndEffectorTask(ErrorTask):
    r"""Track the position, orientation or full pose of a frame, on any subset of world axes.

    Closed-loop inverse kinematics (``000_7b5f597fe4e36aa4.txt, Eq. (16)``), in world axes:

    * position rows:  ``J_p zeta = p_dot_d + K (p_d - p)``, error [m], rows [m/s];
    * orientation rows: with ``R_e = R_d R^T`` and ``e_o = log(R_e)`` (SO(3) log map, world axes,
      [rad]) the exact error dynamics are ``e_o_dot = Jlog(R_e)^T omega_d - Jlog(R_e) omega``
      (``Jlog`` = inverse right Jacobian of SO(3)), hence the rows
      ``Jlog(R_e) J_omega zeta = Jlog(R_e)^T omega_d + K e_o`` [rad/s].

    ``J_p``, ``J_omega`` are the frame's position and angular Jacobians over zeta (world axes).
    The selected axes pick rows of ``[e_p; e_o]`` (``x, y, z, rx, ry, rz``). Planar models default
    to ``x, y`` (position), ``rz`` (orientation).

    The target is either fixed (``position`` [m], ``rotation`` 3x3 or ``[roll, pitch, yaw]``
    [rad]) or a trajectory (any object with ``sample(t)`` returning ``position``, ``velocity``
    and optionally ``rotation``, ``angular_velocity``, world frame); change it at run time with
    :meth:`set_target` or :meth:`track`.

    Args:
        frame: Name of the controlled frame (default ``"tool"``).
        mode: ``"position"``, ``"orientation"`` or ``"pose"``.
        axes: Subset of the mode's axes to control (None: all; planar models: the in-plane ones).
        position: Fixed target position (3,) [m], world frame.
        rotation: Fixed target rotation ``R_world_frame`` (3x3) or ``[roll, pitch, yaw]`` [rad].
        trajectory: Object with ``sample(t)`` (see above); overrides the fixed target.
        gain: Gain K [1/s], scalar or one per selected axis.
        weight: Weight within the level.
        name: Task name (default ``"end_effector"``).
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
        trajectory: Any = None,
        gain: float | list[float] = 1.0,
        weight: float = 1.0,
        name: str | None = None,
    ) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        if not isinstance(frame, str) or not frame:
            raise InputError(f"{self.name}.frame: expected a frame name, got {frame!r}")
        if mode not in _MODE_AXES:
            raise InputError(f"{self.name}.mode: expected one of {', '.join(_MODE_AXES)}, "
                             f"got {mode!r}")
        self.frame = frame
        self.mode = mode
        self._axes_arg = None if axes is None else self._parse_axes(axes)
        self.axes: list[str] = []
        self._p_d: FloatArray | None = None
        self._R_d: FloatArray | None = None
        self._v_d = np.zeros(3)
        self._w_d = np.zeros(3)
        self._w_zero = True  # omega_d is zero (no feed-forward product)
        self._trajectory: Any = None
        self._planar_points: set[str] = set()  # arguments given as (x, y), checked at bind
        self._sel = np.arange(0)
        self._need_p = mode != "orientation"
        self._need_o = mode != "position"
        self._Jlog = np.eye(3)
        self._sel_list: list[int] = []
        self._all_axes = False
        self._work = np.zeros((6, 0))
        if position is not None or rotation is not None:
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
                   angular_velocity: Any = None) -> None:
        """Set a fixed target (and optional feed-forward rates); stops tracking a trajectory.

        Args:
            position: Target position (3,) [m], world frame (2 values ``(x, y)`` only on
                planar models, where z = 0; a ShapeError on the others).
            rotation: Target rotation (3x3, orthonormal) or ``[roll, pitch, yaw]`` [rad].
            velocity: Feed-forward linear velocity (3,) [m/s] (default zero).
            angular_velocity: Feed-forward angular velocity (3,) [rad/s], world axes.
        """
        if position is not None:
            self._p_d = self._point(position, "position")
        if rotation is not None:
            self._R_d = as_rotation(rotation, f"{self.name}.rotation")
        self._v_d = np.zeros(3) if velocity is None else self._point(velocity, "velocity")
        if velocity is None:
            self._planar_points.discard("velocity")
        self._w_d = (np.zeros(3) if angular_velocity is None
                     else as_vector(angular_velocity, f"{self.name}.angular_velocity", 3))
        self._w_zero = not self._w_d.any()
        self._trajectory = None

    def track(self, trajectory: Any) -> None:
        """Follow ``trajectory`` (an object with ``sample(t)``) from now on.

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
            position = trajectory.sample(start if isinstance(start, int | float) else 0.0).position
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
        """True when a target (fixed or trajectory) is set for what the mode needs."""
        if self._trajectory is not None:
            return True
        return (not self._need_p or self._p_d is not None) and (
            not self._need_o or self._R_d is not None)

    def target(self, t: float) -> tuple[FloatArray | None, FloatArray | None]:
        """Target ``(position [m], rotation)`` at time ``t`` [s] (None where not set)."""
        self._sample(t)
        return self._p_d, self._R_d

    def _sample(self, t: float) -> None:
        traj = self._trajectory
        if traj is None:
            if not self.has_target:
                missing = "position" if self._need_p and self._p_d is None else "rotation"
                raise InputError(f"task {self.name!r}: target never set (no {missing} and no "
                                 "trajectory); pass position=/rotation=/trajectory= or call "
                                 "set_target()/track()")
            return
        s = traj.sample(t)
        self._p_d = s.position
        self._v_d = s.velocity
        if self._need_o:
            rot = getattr(s, "rotation", None)
            if rot is not None:
                self._R_d = rot
                w = getattr(s, "angular_velocity", None)
                self._w_d = np.zeros(3) if w is None else w
                self._w_zero = w is None
            elif self._R_d is None:
                raise InputError(f"task {self.name!r}: the trajectory has no orientation and no "
                                 "fixed rotation target is set")
            else:
                self._w_d = np.zeros(3)
                self._w_zero = True

    # ----------------------------------------------------------------------------------- binding
    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        for key in sorted(self._planar_points):
            check_planar_point(f"{self.name}.{key}", model.vehicle_kind)
        if self._trajectory is not None:
            self._check_trajectory(self._trajectory, model.vehicle_kind)
        if self._axes_arg is not None:
            axes = self._axes_arg
        elif model.vehicle_kind == "planar":
            axes = {"position": ["x", "y"], "orientation": ["rz"], "pose": ["x", "y", "rz"]}[
                self.mode]
        else:
            axes = list(_MODE_AXES[self.mode])
        self.axes = axes
        sel = np.array([TWIST_AXES.index(a) for a in axes], dtype=int)
        self._sel = compact_index(sel)
        self._sel_local = compact_index(sel - 3) if self.mode == "orientation" else self._sel
        self._all_position = self.mode == "position" and len(axes) == 3
        self._sel_list = sel.tolist()
        self._all_axes = self._sel_list == [TWIST_AXES.index(a) for a in _MODE_AXES[self.mode]]
        self.error_unit, self.rate_unit = pose_units(axes)
        self._work = np.zeros((6, model.nv))  # [J_p; Jlog J_omega] of the orientation modes
        return len(axes)

    # ---------------------------------------------------------------------------------- hot path
    def fill(self, state: State, t: float, A: FloatArray, lower: FloatArray,
             upper: FloatArray) -> None:
        """Write ``J zeta = x_dot_d + K e`` (see the class docstring).

        Fuses :meth:`compute_error`, :meth:`compute_jacobian` and :meth:`compute_feedforward`
        (the same operations). Position mode stays with arrays (its 3-vectors already are);
        the orientation modes take the error and feed-forward of the selected axes as plain
        floats (at most six) and the rows ``Jlog(R_e) J_omega`` from one product, written
        straight into ``A`` when every axis of the mode is kept (else through a work block
        and one selection).
        """
        if not self._fused:
            super().fill(state, t, A, lower, upper)
            return
        self._sample(t)
        frame = self.frame
        J = state.jacobian(frame)
        if self.mode == "position":
            e = self._p_d - state.position(frame)  # type: ignore[operator]
            if self._all_position:
                A[:] = J[:3]
                self._set_sides(e, self._v_d, lower, upper)
                return
            sel = self._sel
            A[:] = J[sel]
            self._set_sides(e[sel], np.take(self._v_d, sel) if not isinstance(sel, slice)
                            else np.asarray(self._v_d)[sel], lower, upper)
            return
        T = state.pose(frame)
        R_e = self._R_d @ T[:3, :3].T  # type: ignore[operator]
        Jlog = pin.Jlog3(R_e)
        self._Jlog = Jlog
        e6 = [0.0, 0.0, 0.0, *pin.log3(R_e).tolist()]
        # Jlog^T omega_d; a fixed target (omega_d = 0) skips the product
        ff6 = [0.0] * 6 if self._w_zero else [0.0, 0.0, 0.0, *(Jlog.T @ self._w_d).tolist()]
        # every axis of the mode in order: the rows go straight into A (no work block)
        work = A if self._all_axes and A.flags.c_contiguous else self._work
        if self._need_p:
            e6[:3] = (self._p_d - T[:3, 3]).tolist()  # type: ignore[operator]
            ff6[:3] = np.asarray(self._v_d).tolist()
            work[:3] = J[:3]
        np.dot(Jlog, J[3:], out=work[3:] if self._need_p or work is not A else A)
        if work is not A:
            A[:] = work[self._sel]
        self._set_sides_floats([e6[i] for i in self._sel_list], lower, upper,
                               [ff6[i] for i in self._sel_list])

    # -------------------------------------------------------------------------------- evaluation
    def compute_error(self, state: State, t: float) -> FloatArray:
        """Error ``[p_d - p; log(R_d R^T)]`` on the selected axes [m, rad], world axes."""
        self._sample(t)
        e6 = np.empty(6)
        if self._need_p:
            e6[:3] = self._p_d - state.position(self.frame)  # type: ignore[operator]
        if self._need_o:
            R_e = self._R_d @ state.rotation(self.frame).T  # type: ignore[operator]
            e6[3:] = pin.log3(R_e)
            self._Jlog = pin.Jlog3(R_e)
        return e6[self._sel]

    def compute_jacobian(self, state: State, t: float) -> FloatArray:
        """Jacobian of the regulated quantity over zeta on the selected axes.

        Position rows ``J_p``; orientation rows ``Jlog(R_e) J_omega`` (uses the ``R_e`` of the
        last :meth:`compute_error` call at the same state).
        """
        if self.mode == "position":
            return state.jacobian(self.frame, rows="position")[self._sel]
        if self.mode == "orientation":
            return (self._Jlog @ state.jacobian(self.frame, rows="orientation"))[self._sel_local]
        J = state.jacobian(self.frame, rows="twist").copy()
        J[3:] = self._Jlog @ J[3:]
        return J[self._sel]

    def compute_feedforward(self, state: State, t: float) -> FloatArray:
        """Feed-forward ``[p_dot_d; Jlog(R_e)^T omega_d]`` on the selected axes."""
        ff = np.empty(6)
        ff[:3] = self._v_d
        ff[3:] = self._Jlog.T @ self._w_d if self._need_o else 0.0
        return ff[self._sel]

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "position", "rotation", "trajectory")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "position":
            self._p_d = self._point(value, "position")
            self._v_d = np.zeros(3)
            self._planar_points.discard("velocity")
            self._trajectory = None
        elif key == "rotation":
            self._R_d = as_rotation(value, f"{self.name}.rotation")
            self._w_d = np.zeros(3)
            self._w_zero = True
            self._trajectory = None
        elif key == "trajectory":
            self.track(value)
        else:
            super()._apply_update(key, value)
