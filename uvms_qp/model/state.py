"""Kinematic state of a model at one configuration: poses and Jacobians over ``zeta``.

Construction runs Pinocchio's forward kinematics, joint Jacobians and frame placements once
(``computeJointJacobians`` + ``updateFramePlacements``); every getter after that is a cheap
read, cached per frame. Returned arrays are read-only views of the cache: copy before modifying.

A control tick reads a handful of numbers per task, where one numpy call costs more than the
arithmetic itself; so the state also gives them as plain floats (:meth:`State.eta_floats`,
:meth:`State.joint_floats`, :meth:`State.eta_jacobian_values`,
:meth:`State.arm_position_floats`), computed once, and keeps values that one consumer derives
for the others of the same tick (:meth:`State.store` / :meth:`State.derived`).

The model's single Pinocchio ``Data`` buffer holds the kinematics of the most recent state; an
older state that needs a frame not yet in its cache recomputes its own kinematics first, so
states never read each other's numbers.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from ..errors import UnknownFrameError, UnknownNameError
from .vehicle import fossen_jacobian_values, spatial_eta_and_rotation

if TYPE_CHECKING:
    from .model import Model

FloatArray = NDArray[np.float64]

_ROWS: dict[str, slice] = {
    "twist": slice(0, 6),
    "position": slice(0, 3),
    "orientation": slice(3, 6),
}
_AXES: dict[str, Any] = {
    "world": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
    "local": pin.ReferenceFrame.LOCAL,
}


def _rows(rows: str) -> slice:
    try:
        return _ROWS[rows]
    except (KeyError, TypeError):
        raise UnknownNameError("row set", rows, _ROWS) from None


class State:
    """Configuration ``q`` of a model with its kinematics.

    Attributes:
        model: The :class:`~uvms_qp.model.model.Model`.
        q: Configuration (read-only, length ``model.nq``).

    Twists are ``[v; omega]``: ``v`` the velocity of the frame origin [m/s], ``omega`` the
    angular velocity [rad/s]. Jacobians map ``zeta`` (length ``model.nv``) to twists, in world
    (NED) axes or in the frame's own axes.
    """

    __slots__ = ("_arm", "_derived", "_eta", "_eta_jacobian", "_eta_jacobian_values",
                 "_eta_list", "_jacobians", "_joint_list", "_poses", "_vehicle_rotation", "model",
                 "q")

    def __init__(self, model: Model, q: Any) -> None:
        """Validate ``q`` and compute the kinematics (see :meth:`Model.check_configuration`)."""
        q = model.check_configuration(q)
        q.setflags(write=False)
        self.model = model
        self.q: FloatArray = q
        self._poses: dict[str, FloatArray] = {}
        self._jacobians: dict[tuple[str, str], FloatArray] = {}
        self._arm: dict[str, FloatArray] = {}
        self._eta: FloatArray | None = None
        self._eta_jacobian: FloatArray | None = None
        self._eta_list: list[float] | None = None
        self._eta_jacobian_values: tuple[float, ...] | None = None
        self._joint_list: list[float] | None = None
        self._vehicle_rotation: tuple[float, ...] = ()
        self._derived: dict[Any, Any] | None = None
        pin.computeJointJacobians(model.pin_model, model._data, q)
        pin.updateFramePlacements(model.pin_model, model._data)
        model._owner = self

    def _sync(self) -> Any:
        """Return the model's Data holding this state's kinematics (recompute if taken)."""
        model = self.model
        if model._owner is not self:
            pin.computeJointJacobians(model.pin_model, model._data, self.q)
            pin.updateFramePlacements(model.pin_model, model._data)
            model._owner = self
        return model._data

    # --- configuration --------------------------------------------------------------------

    @property
    def eta(self) -> FloatArray:
        """Vehicle pose ``[x, y, z, phi, theta, psi]`` / ``[x, y, psi]`` / ``[]`` [m, rad]."""
        if self._eta is None:
            eta = np.array(self.eta_floats(), dtype=np.float64)
            eta.setflags(write=False)
            self._eta = eta
        return self._eta

    def eta_floats(self) -> list[float]:
        """:attr:`eta` as a list of plain floats [m, rad] (cached; do not modify).

        For per-tick code that works on the few pose coordinates one by one.
        """
        eta = self._eta_list
        if eta is None:
            m = self.model
            if m.vehicle_kind == "spatial":  # Vehicle.eta_values, keeping the rotation
                eta, self._vehicle_rotation = spatial_eta_and_rotation(self.q[:7])
            else:
                eta = m.vehicle.eta_values(self.q[: m.nq_vehicle])
            self._eta_list = eta
        return eta

    def joint_floats(self) -> list[float]:
        """:attr:`joints` as a list of plain floats [rad] (cached; do not modify)."""
        joints = self._joint_list
        if joints is None:
            joints = self._joint_list = self.q[self.model.nq_vehicle :].tolist()
        return joints

    def derived(self, key: Any) -> Any:
        """A quantity stored with :meth:`store` at this state, or None.

        Lets several consumers of the same state (e.g. the tasks of one control tick) share a
        value derived from the kinematics (such as the arm's manipulability and its gradient)
        instead of recomputing it. Keys are chosen by the producer (a tuple naming the quantity
        and its parameters).
        """
        derived = self._derived
        return None if derived is None else derived.get(key)

    def store(self, key: Any, value: Any) -> Any:
        """Keep ``value`` under ``key`` for :meth:`derived` at this state; returns ``value``."""
        if self._derived is None:
            self._derived = {}
        self._derived[key] = value
        return value

    @property
    def joints(self) -> FloatArray:
        """Joint angles [rad] (read-only view of ``q``)."""
        return self.q[self.model.nq_vehicle :]

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
            fid = model.frame_id(frame)
            data = model._data if model._owner is self else self._sync()
            T = data.oMf[fid].homogeneous
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
        """Pose ``T_reference_frame`` (4x4) of ``frame`` in the axes of ``reference``."""
        T_wr = self.pose(reference)
        T_wf = self.pose(frame)
        R_rw = T_wr[:3, :3].T
        out = np.eye(4)
        out[:3, :3] = R_rw @ T_wf[:3, :3]
        out[:3, 3] = R_rw @ (T_wf[:3, 3] - T_wr[:3, 3])
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
        try:
            J = self._jacobians.get((frame, axes))
        except TypeError:  # an unhashable frame name or axes
            J = None
            if not isinstance(frame, str):
                raise UnknownFrameError(frame, self.model.frames) from None
        if J is None:
            J = self._frame_jacobian(frame, axes)
        if rows == "twist":
            return J
        return J[_rows(rows)]

    def _frame_jacobian(self, frame: str, axes: str) -> FloatArray:
        try:
            reference = _AXES[axes]
        except (KeyError, TypeError):
            raise UnknownNameError("axis convention", axes, _AXES) from None
        model = self.model
        fid = model.frame_id(frame)
        data = model._data if model._owner is self else self._sync()
        J = pin.getFrameJacobian(model.pin_model, data, fid, reference)
        if model._select is not None:
            J = J[:, model._select]
        J.setflags(write=False)
        self._jacobians[(frame, axes)] = J
        return J

    def arm_jacobian(self, frame: str = "tool", rows: str = "twist") -> FloatArray:
        """Jacobian of a frame's twist over the joint rates only, in ``arm_base`` axes.

        The vehicle is held still: ``[v; omega]_arm_base = J_arm @ joint_rates``, with ``v`` the
        velocity of the frame origin. Used for the arm's manipulability
        (``000_7b5f597fe4e36aa4.txt``, Eq. (18); ``003_229789978cc4b235.txt``, Eq. (18)).

        Args:
            frame: Frame name (default ``"tool"``).
            rows: ``"twist"``, ``"position"`` or ``"orientation"``.

        Returns:
            ``(6 or 3, model.n_joints)`` read-only array.
        """
        try:
            Ja = self._arm.get(frame)
        except TypeError:  # an unhashable frame name
            raise UnknownFrameError(frame, self.model.frames) from None
        if Ja is None:
            Ja = self._arm_jacobian(frame)
        if rows == "twist":
            return Ja
        return Ja[_rows(rows)]

    def arm_position_floats(self, frame: str = "tool") -> list[float]:
        """Origin of ``frame`` in ``arm_base`` coordinates [m], 3 plain floats (cached).

        ``R_wb^T (p_frame - p_arm_base)`` (equal up to rounding), read from the bare arm's
        kinematics that :meth:`arm_jacobian` uses. For per-tick code such as the payload lever
        arm (``003_229789978cc4b235.txt, Eq. (20)``).
        """
        key = ("arm_position", frame)
        p = self.derived(key)
        if p is None:
            m = self.model
            fid = m._arm_frame_ids.get(frame)
            if fid is None:  # a frame the arm does not move: from the world poses
                p = self.pose_in(frame, "arm_base")[:3, 3].tolist()
            else:
                arm, data = m._arm_model, m._arm_data
                if m._arm_owner is not self:
                    pin.computeJointJacobians(arm, data, self.q[m.nq_vehicle :])
                    m._arm_owner = self
                p = pin.updateFramePlacement(arm, data, fid).translation.tolist()
            self.store(key, p)
        return p  # type: ignore[no-any-return]

    def _arm_jacobian(self, frame: str) -> FloatArray:
        m = self.model
        fid = m._arm_frame_ids.get(frame)
        if fid is None:
            m.frame_id(frame)  # raises UnknownFrameError for an unknown name
            Ja = np.zeros((6, m.n_joints))  # a frame the arm does not move
        else:
            # Jacobian of the bare fixed-base arm (world = arm_base), over the joint rates
            arm, data = m._arm_model, m._arm_data
            if m._arm_owner is not self:
                pin.computeJointJacobians(arm, data, self.q[m.nq_vehicle :])
                m._arm_owner = self
            Ja = pin.getFrameJacobian(arm, data, fid, pin.ReferenceFrame.LOCAL_WORLD_ALIGNED)
        Ja.setflags(write=False)
        self._arm[frame] = Ja
        return Ja

    def vehicle_pose_jacobian(self) -> FloatArray:
        """Matrix ``J_eta`` with ``eta_dot = J_eta @ zeta`` (passive rates taken as zero).

        Spatial: Fossen's transformation (``003_229789978cc4b235.txt``, Eq. (2)-(3)) restricted
        to the actuated columns; planar ``[R2(psi), 0; 0, 1]``; joint columns are zero.
        Computed once per state from :meth:`eta_jacobian_values` (the numbers of
        :meth:`~uvms_qp.model.vehicle.Vehicle.pose_jacobian` up to rounding).

        Returns:
            ``(model.eta_size, model.nv)`` read-only array.
        """
        J = self._eta_jacobian
        if J is None:
            m = self.model
            J = np.zeros((m.eta_size, m.nv))
            if m.eta_size:
                values = self.eta_jacobian_values()
                columns = m._eta_columns
                if columns is None:  # every vehicle rate actuated: the block is J_eta itself
                    J.put(m._eta_block, values)
                else:
                    full = np.array(values).reshape(m.eta_size, m.vehicle.nv)
                    J[:, : m.n_vehicle] = full[:, columns]
            J.setflags(write=False)
            self._eta_jacobian = J
        return J

    def eta_jacobian_values(self) -> tuple[float, ...]:
        """Fossen's ``J(eta)`` over all vehicle rates, row-major plain floats (cached).

        :meth:`~uvms_qp.model.vehicle.Vehicle.pose_jacobian_values` at :attr:`eta`:
        ``eta_size x n`` entries with ``n`` the vehicle's full rate count (passive rates
        included; :meth:`vehicle_pose_jacobian` keeps the actuated columns). Empty for a fixed
        base.
        """
        values = self._eta_jacobian_values
        if values is None:
            eta = self.eta_floats()
            if self.model.vehicle_kind == "spatial":
                # Fossen's J with the rotation of the configuration's quaternion (kept by
                # eta_floats; the matrix R(eta) up to rounding) instead of one rebuilt from eta
                values = fossen_jacobian_values(self._vehicle_rotation, eta[3], eta[4])
            else:
                values = self.model.vehicle.pose_jacobian_values(eta)
            self._eta_jacobian_values = values
        return values

    def __repr__(self) -> str:
        return f"<State of {self.model.name!r} q={np.array2string(self.q, precision=4)}>"
