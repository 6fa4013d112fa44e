"""Rigid transforms used to describe mounts and tool offsets.

A transform is a 4x4 homogeneous matrix ``T_a_b`` (pose of frame ``b`` in frame ``a``). Rotations
from roll-pitch-yaw use the Z-Y-X Euler convention of Fossen and SNAME (and of URDF):
``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.

The rotation conversions (quaternion -> matrix, matrix <-> roll-pitch-yaw) are written once, in
plain floats with the floating-point operations of Pinocchio's (Eigen's) own routines, so their
results equal Pinocchio's; the state computes the vehicle pose with them every tick, where a
handful of float operations costs less than building arrays.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validation import as_matrix, as_vector
from ..errors import InputError

FloatArray = NDArray[np.float64]

#: Rotation from ROS body axes FLU (forward, left, up) to marine body axes FRD (forward, right,
#: down): a half turn about the forward axis, ``R_FRD_FLU = diag(1, -1, -1)`` (its own inverse).
R_FRD_FLU: FloatArray = np.diag([1.0, -1.0, -1.0])


def quaternion_to_rotation(x: float, y: float, z: float, w: float) -> tuple[float, ...]:
    """Rotation matrix of a unit quaternion, row-major as 9 floats.

    The same floating-point operations as Eigen's ``Quaternion::toRotationMatrix`` (used by
    Pinocchio), so the result is bit-identical to ``pin.Quaternion(w, x, y, z).toRotationMatrix()``
    without the cost of building Pinocchio objects.
    """
    tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    return (1.0 - (tyy + tzz), txy - twz, txz + twy,
            txy + twz, 1.0 - (txx + tzz), tyz - twx,
            txz - twy, tyz + twx, 1.0 - (txx + tyy))


def rotation_to_rpy(R: Sequence[float]) -> tuple[float, float, float]:
    """Z-Y-X Euler angles ``(roll, pitch, yaw)`` [rad] of a row-major rotation (9 floats).

    ``R = Rz(yaw) Ry(pitch) Rx(roll)`` with pitch in ``[-pi/2, pi/2]``: the operations of
    Pinocchio's ``rpy.matrixToRpy`` (Eigen's ``eulerAngles(2, 1, 0)`` folded into that range), in
    plain floats; the tests check equality with Pinocchio.
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    yaw = math.atan2(r10, r00)
    c2 = math.sqrt(r22 * r22 + r21 * r21)
    if yaw < 0.0:
        yaw += math.pi
        pitch = math.atan2(-r20, -c2)
    else:
        pitch = math.atan2(-r20, c2)
    s1, c1 = math.sin(yaw), math.cos(yaw)
    roll = math.atan2(s1 * r02 - c1 * r12, c1 * r11 - s1 * r01)
    if pitch < -0.5 * math.pi:
        pitch += 2.0 * math.pi
    if pitch > 0.5 * math.pi:
        pitch = math.pi - pitch
        roll = roll + math.pi if roll < 0.0 else roll - math.pi
        yaw -= math.pi
    return roll, pitch, yaw


def rpy_to_rotation(roll: float, pitch: float, yaw: float) -> tuple[float, ...]:
    """``Rz(yaw) Ry(pitch) Rx(roll)`` row-major as 9 floats.

    The operations of Pinocchio's ``rpy.rpyToMatrix`` (a product of three axis-angle quaternions
    turned into a matrix), in plain floats; the tests check equality with Pinocchio.
    """
    cz, sz = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    cy, sy = math.cos(0.5 * pitch), math.sin(0.5 * pitch)
    cx, sx = math.cos(0.5 * roll), math.sin(0.5 * roll)
    # q_z q_y, then (q_z q_y) q_x; each factor has a single non-zero vector component
    aw, ax, ay, az = cz * cy, -(sz * sy), cz * sy, sz * cy
    w = aw * cx - ax * sx
    x = aw * sx + ax * cx
    y = ay * cx + az * sx
    z = az * cx - ay * sx
    return quaternion_to_rotation(x, y, z, w)


def rpy_to_matrix(rpy: Any) -> FloatArray:
    """Rotation matrix of roll-pitch-yaw angles ``[phi, theta, psi]`` [rad], Z-Y-X convention."""
    r = as_vector(rpy, "rpy", 3)
    return np.array(rpy_to_rotation(*r.tolist())).reshape(3, 3)


def matrix_to_rpy(rotation: Any) -> FloatArray:
    """Roll-pitch-yaw ``[phi, theta, psi]`` [rad] of a rotation matrix (Z-Y-X convention).

    Pitch is returned in ``[-pi/2, pi/2]``, roll and yaw in ``[-pi, pi]``.
    """
    return np.array(rotation_to_rpy(as_matrix(rotation, "rotation", 3, 3).ravel().tolist()))


def transform(xyz: Any = (0.0, 0.0, 0.0), rpy: Any = (0.0, 0.0, 0.0)) -> FloatArray:
    """Homogeneous transform from a translation [m] and roll-pitch-yaw angles [rad].

    Args:
        xyz: Origin of the child frame in the parent frame [m].
        rpy: Orientation of the child frame, Z-Y-X Euler angles [rad].

    Returns:
        The 4x4 matrix ``[[R, xyz], [0, 1]]``.
    """
    T = np.eye(4)
    T[:3, :3] = rpy_to_matrix(rpy)
    T[:3, 3] = as_vector(xyz, "xyz", 3)
    return T


def flu_to_frd(T_flu_child: Any) -> FloatArray:
    """Re-express a pose given in a ROS FLU body frame in the marine FRD body frame.

    Both body frames share their origin; only the axes differ, so
    ``T_frd_child = [[R_FRD_FLU, 0], [0, 1]] @ T_flu_child``: the position flips sign in y and z
    and the child's orientation gains a half turn about the forward axis. The child keeps its own
    axes (a ROS arm keeps its URDF frames).

    Args:
        T_flu_child: 4x4 pose of a child frame in the FLU body frame.

    Returns:
        The 4x4 pose of the same child frame in the FRD body frame.
    """
    T = as_transform(T_flu_child, "T_flu_child")
    out = T.copy()
    out[:3, :] = R_FRD_FLU @ T[:3, :]
    return out


def as_transform(value: Any, name: str) -> FloatArray:
    """Validate a rigid transform given as a 4x4 matrix, a mapping or None.

    Args:
        value: None (identity), a 4x4 homogeneous matrix with an orthonormal rotation, or a mapping
            with optional keys ``"xyz"`` [m] and ``"rpy"`` [rad].
        name: Argument name used in error messages.

    Returns:
        A new 4x4 float64 array.

    Raises:
        InputError: not a rigid transform (bad bottom row, non-orthonormal rotation, unknown keys).
        ShapeError: wrong shape.
        NonFiniteError: NaN or inf entries.
    """
    if value is None:
        return np.eye(4)
    if isinstance(value, Mapping):
        unknown = sorted(set(value) - {"xyz", "rpy"})
        if unknown:
            raise InputError(f"{name}: unknown keys {unknown}; expected 'xyz' and/or 'rpy'")
        return transform(value.get("xyz", (0.0, 0.0, 0.0)), value.get("rpy", (0.0, 0.0, 0.0)))
    T = as_matrix(value, name, 4, 4).copy()
    if not np.allclose(T[3], (0.0, 0.0, 0.0, 1.0)):
        raise InputError(f"{name}: bottom row must be [0, 0, 0, 1], got {T[3].tolist()}")
    R = T[:3, :3]
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0.0:
        raise InputError(f"{name}: the 3x3 block is not a rotation matrix")
    return T


def to_se3(T: FloatArray) -> pin.SE3:
    """Pinocchio ``SE3`` of a 4x4 homogeneous matrix (no validation)."""
    return pin.SE3(np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3]))
