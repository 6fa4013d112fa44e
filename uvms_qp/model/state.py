"""Kinematic state of a model at one configuration: poses and Jacobians over ``zeta``.

Construction runs Pinocchio's forward kinematics and joint Jacobians once
(``computeJointJacobians``) into Pinocchio buffers the state owns for its lifetime; a getter
then places the frame it is asked for (``updateFramePlacement``, ``getFrameJacobian``) and
caches the result per frame. The buffers come
from a small pool the model keeps and go back to it when the state is collected, so a new state
allocates no Pinocchio ``Data`` (building one costs far more than the kinematics). Each state
reads only its own buffers: states of one model can be used in any order.

Every quantity has one form, a read-only numpy array (copy before modifying).
"""

from __future__ import annotations

import itertools
from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import UnknownFrameError, UnknownNameError

if TYPE_CHECKING:
    from .model import Model

FloatArray = NDArray[np.float64]

_ROWS: dict[str, slice] = {
    "twist": slice(0, 6),
    "position": slice(0, 3),
    "orientation": slice(3, 6),
}
_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_AXES: dict[str, Any] = {"world": _LWA, "local": pin.ReferenceFrame.LOCAL}
#: Pinocchio buffers a model keeps for reuse (more live states simply make more).
POOL_SIZE = 8
_serials = itertools.count()


def _rows(J: FloatArray, rows: str) -> FloatArray:
    try:
        return J[_ROWS[rows]]
    except (KeyError, TypeError):
        raise UnknownNameError("row set", rows, _ROWS) from None


class State:
    """Configuration ``q`` of a model with its kinematics.

    Attributes:
        model: The :class:`~uvms_qp.model.model.Model`.
        q: Configuration (read-only, length ``model.nq``).
        joints: Joint angles [rad] (read-only view of ``q``, length ``model.n_joints``).
        serial: A number no other state of this process has (for per-state caches of
            consumers, e.g. a task whose value another task reads in the same tick).
        velocity: The measured vehicle body velocity ``nu = [u, v, w, p, q, r]`` (6,)
            [m/s, rad/s], FRD body axes (read-only), when the state comes from a plant that
            measures it (a floating vehicle); None otherwise (a kinematic run, where the
            command is the velocity).

    Twists are ``[v; omega]``: ``v`` the velocity of the frame origin [m/s], ``omega`` the
    angular velocity [rad/s]. Jacobians map ``zeta`` (length ``model.nv``) to twists, in world
    (NED) axes or in the frame's own axes.
    """

    __slots__ = ("_arm_data", "_arm_jacobians", "_arm_positions", "_data", "_eta",
                 "_eta_jacobian", "_jacobians", "_poses", "_vehicle_pose", "joints", "model", "q",
                 "serial", "velocity")

    def __init__(self, model: Model, q: Any, velocity: Any = None) -> None:
        """Validate ``q`` and compute the kinematics (see :meth:`Model.check_configuration`).

        ``velocity`` (6,) [m/s, rad/s] is the measured body velocity of a spatial vehicle, or
        None (see the class attributes).
        """
        q = model.check_configuration(q)
        q.setflags(write=False)
        self.model = model
        self.q: FloatArray = q
        self.velocity: FloatArray | None = (
            None if velocity is None else model.check_body_velocity(velocity))
        self.joints: FloatArray = q[model.nq_vehicle:]
        self.serial = next(_serials)
        pool = model._data_pool
        data = pool.pop() if pool else model.pin_model.createData()
        self._data = data
        self._arm_data: Any = None
        self._poses: dict[str, FloatArray] = {}
        self._jacobians: dict[Any, FloatArray] = {}
        self._arm_jacobians: dict[str, FloatArray] = {}
        self._arm_positions: dict[str, FloatArray] = {}
        self._vehicle_pose: tuple[list[float], tuple[float, ...]] | None = None
        self._eta: FloatArray | None = None
        self._eta_jacobian: FloatArray | None = None
        pin.computeJointJacobians(model.pin_model, data, q)

    def __del__(self) -> None:
        """Give the Pinocchio buffers back to the model's pool."""
        try:
            data = self._data
        except AttributeError:  # q was rejected before the buffers were taken
            return
        model = self.model
        if len(model._data_pool) < POOL_SIZE:
            model._data_pool.append(data)
        arm = self._arm_data
        if arm is not None and len(model._arm_pool) < POOL_SIZE:
            model._arm_pool.append(arm)

    # --- vehicle --------------------------------------------------------------------------

    def _vehicle(self) -> tuple[list[float], tuple[float, ...]]:
        """``eta`` and ``R_world_vehicle`` as plain floats (:meth:`Vehicle.pose`), once."""
        pose = self._vehicle_pose
        if pose is None:
            m = self.model
            pose = self._vehicle_pose = m.vehicle.pose(self.q[: m.nq_vehicle].tolist())
        return pose

    @property
    def eta(self) -> FloatArray:
        """Vehicle pose ``[x, y, z, phi, theta, psi]`` / ``[x, y, psi]`` / ``[]`` [m, rad].

        NED position and Z-Y-X Euler angles of ``R_world_vehicle`` (see
        :meth:`~uvms_qp.model.vehicle.Vehicle.pose`).
        """
        eta = self._eta
        if eta is None:
            eta = self._eta = np.array(self._vehicle()[0])
            eta.setflags(write=False)
        return eta

    def vehicle_pose_jacobian(self) -> FloatArray:
        """Matrix ``J_eta`` with ``eta_dot = J_eta @ zeta`` (passive rates taken as zero).

        Spatial: Fossen's transformation (Wang et al. (2017), Eq. (2)-(3),
        :meth:`~uvms_qp.model.vehicle.Vehicle.pose_jacobian_entries`, with the rotation of the
        configuration's quaternion) restricted to the actuated columns; planar
        ``[R2(psi), 0; 0, 1]``; joint columns are zero. Computed once per state.

        Returns:
            ``(model.eta_size, model.nv)`` read-only array.
        """
        J = self._eta_jacobian
        if J is None:
            m = self.model
            J = np.zeros((m.eta_size, m.nv))
            if m.eta_size:
                values = m.vehicle.pose_jacobian_entries(*self._vehicle())
                src = m._eta_src
                J.put(m._eta_dst, values if src is None else [values[i] for i in src])
            J.setflags(write=False)
            self._eta_jacobian = J
        return J

    # --- poses --------------------------------------------------------------------

    def pose(self, frame: str) -> FloatArray:
        """Pose ``T_world_frame`` (4x4, read-only) [m].

        Raises:
            UnknownFrameError: unknown frame (the message lists the known frames).
        """
        try:
            T = self._poses.get(frame)
        except TypeError:  # an unhashable frame name
            raise UnknownFrameError(frame, self.model.frames) from None
        if T is None:
            model = self.model
            fid = model._frame_ids.get(frame)
            if fid is None:
                raise UnknownFrameError(frame, model.frames)
            T = pin.updateFramePlacement(model.pin_model, self._data, fid).homogeneous
            T.setflags(write=False)
            self._poses[frame] = T
        return T

    def position(self, frame: str) -> FloatArray:
        """Origin of ``frame`` in world coordinates (3,) [m]."""
        return self.pose(frame)[:3, 3]

    def rotation(self, frame: str) -> FloatArray:
        """Rotation ``R_world_frame`` (3x3)."""
        return self.pose(frame)[:3, :3]

    def pose_in(self, frame: str, reference: str) -> FloatArray:
        """Pose ``T_reference_frame`` (4x4) of ``frame`` in the axes of ``reference`` [m]."""
        T_wr = self.pose(reference)
        T_wf = self.pose(frame)
        R_rw = T_wr[:3, :3].T
        out = np.eye(4)
        out[:3, :3] = R_rw @ T_wf[:3, :3]
        out[:3, 3] = R_rw @ (T_wf[:3, 3] - T_wr[:3, 3])
        out.setflags(write=False)
        return out

    # --- Jacobians --------------------------------------------------------------------

    def jacobian(self, frame: str, rows: str = "twist", axes: str = "world") -> FloatArray:
        """Jacobian of a frame's twist over ``zeta`` (read-only).

        ``[v; omega] = J @ zeta`` with ``v`` the velocity of the frame origin [m/s] and
        ``omega`` the angular velocity [rad/s], both in world axes (``axes="world"``) or in the
        frame's axes (``axes="local"``). Passive vehicle DOFs contribute no column.

        Args:
            frame: Frame name.
            rows: ``"twist"`` (6 rows), ``"position"`` (first 3) or ``"orientation"`` (last 3).
            axes: ``"world"`` or ``"local"``.

        Returns:
            ``(6 or 3, model.nv)`` array.

        Raises:
            UnknownFrameError: unknown frame.
            UnknownNameError: unknown ``rows`` or ``axes``.
        """
        key: Any = frame if axes == "world" else (frame, axes)
        try:
            J = self._jacobians.get(key)
        except TypeError:  # an unhashable frame name
            raise UnknownFrameError(frame, self.model.frames) from None
        if J is not None and rows == "twist":
            return J
        if J is None:
            try:
                reference = _AXES[axes]
            except (KeyError, TypeError):
                raise UnknownNameError("axis convention", axes, _AXES) from None
            model = self.model
            fid = model._frame_ids.get(frame)
            if fid is None:
                raise UnknownFrameError(frame, model.frames)
            J = pin.getFrameJacobian(model.pin_model, self._data, fid, reference)
            if model._select is not None:
                J = J[:, model._select]
            J.setflags(write=False)
            self._jacobians[key] = J
        if rows == "twist":
            return J
        return J[:3] if rows == "position" else _rows(J, rows)

    # --- the bare arm ------------------------------------------------------------------

    def _arm(self) -> Any:
        """Kinematics of the bare arm (root ``arm_base``) at :attr:`joints`, computed once."""
        data = self._arm_data
        if data is None:
            m = self.model
            pool = m._arm_pool
            data = pool.pop() if pool else m._arm_model.createData()
            pin.computeJointJacobians(m._arm_model, data, self.joints)
            self._arm_data = data
        return data

    def arm_jacobian(self, frame: str = "tool", rows: str = "twist") -> FloatArray:
        """Jacobian of a frame's twist over the joint rates only, in ``arm_base`` axes.

        The vehicle is held still: ``[v; omega]_arm_base = J_arm @ joint_rates``, with ``v`` the
        velocity of the frame origin. Used for the arm's manipulability
        (Soylu et al. (2007), Eq. (18); Wang et al. (2017), Eq. (18)).
        A frame the arm does not move has a zero Jacobian.

        Args:
            frame: Frame name (default ``"tool"``).
            rows: ``"twist"``, ``"position"`` or ``"orientation"``.

        Returns:
            ``(6 or 3, model.n_joints)`` read-only array.
        """
        try:
            Ja = self._arm_jacobians.get(frame)
        except TypeError:  # an unhashable frame name
            raise UnknownFrameError(frame, self.model.frames) from None
        if Ja is None:
            m = self.model
            fid = m._arm_frame_ids.get(frame)
            if fid is None:
                m.frame_id(frame)  # raises UnknownFrameError for an unknown name
                Ja = np.zeros((6, m.n_joints))
            else:  # world = arm_base on the bare arm
                Ja = pin.getFrameJacobian(m._arm_model, self._arm(), fid, _LWA)
            Ja.setflags(write=False)
            self._arm_jacobians[frame] = Ja
        return Ja if rows == "twist" else _rows(Ja, rows)

    def arm_position(self, frame: str = "tool") -> FloatArray:
        """Origin of ``frame`` in ``arm_base`` coordinates (3,) [m] (read-only).

        ``R_wb^T (p_frame - p_arm_base)`` (up to rounding), read from the bare arm's kinematics
        that :meth:`arm_jacobian` uses; e.g. the payload lever arm
        (Wang et al. (2017), Eq. (20)).
        """
        try:
            p = self._arm_positions.get(frame)
        except TypeError:  # an unhashable frame name
            raise UnknownFrameError(frame, self.model.frames) from None
        if p is None:
            m = self.model
            fid = m._arm_frame_ids.get(frame)
            if fid is None:  # a frame the arm does not move: from the world poses
                p = self.pose_in(frame, "arm_base")[:3, 3]
            else:
                p = pin.updateFramePlacement(m._arm_model, self._arm(), fid).homogeneous[:3, 3]
                p.setflags(write=False)
            self._arm_positions[frame] = p
        return p

    def __repr__(self) -> str:
        return f"<State of {self.model.name!r} q={np.array2string(self.q, precision=4)}>"
