"""Vehicle descriptions: planar, spatial free-floating, or a fixed base.

The vehicle is the root of the kinematic tree, a Pinocchio joint between the world (NED) and the
vehicle body frame (FRD):

- ``"spatial"``: ``JointModelFreeFlyer``; configuration ``[x, y, z, qx, qy, qz, qw]`` (position
  [m] and unit quaternion of ``R_world_body``), velocity ``nu = [u, v, w, p, q, r]`` in body axes.
- ``"planar"``: ``JointModelPlanar`` in the world x-y plane, rotating about world z;
  configuration ``[x, y, cos(psi), sin(psi)]``, velocity ``[u, v, r]`` in body axes.
- ``"fixed"``: no joint; the vehicle frame is the world frame (a bare arm).

Pinocchio's free-flyer and planar velocities are body-frame velocities, i.e. exactly ``nu``.
A vehicle may actuate only some of its DOFs: the others are passive (they stay in the
configuration but are not decision variables, and ``integrate`` keeps their rates at zero).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validation import as_vector
from ..errors import InputError, ModelError

FloatArray = NDArray[np.float64]
VehicleKind = Literal["planar", "spatial", "fixed"]

#: Body velocity names in ``nu`` order (Fossen/SNAME).
NU_NAMES: tuple[str, ...] = ("u", "v", "w", "p", "q", "r")
#: Velocity names of each vehicle kind, in Pinocchio's velocity order.
DOF_NAMES: dict[str, tuple[str, ...]] = {
    "spatial": NU_NAMES,
    "planar": ("u", "v", "r"),
    "fixed": (),
}
#: Pose names of each vehicle kind (``eta``).
ETA_NAMES: dict[str, tuple[str, ...]] = {
    "spatial": ("x", "y", "z", "phi", "theta", "psi"),
    "planar": ("x", "y", "psi"),
    "fixed": (),
}
_NQ = {"spatial": 7, "planar": 4, "fixed": 0}


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


def spatial_eta_and_rotation(qv: Any) -> tuple[list[float], tuple[float, ...]]:
    """``eta`` [m, rad] and the rotation of a free-flyer configuration.

    ``qv = [x, y, z, qx, qy, qz, qw]``; the rotation is 9 row-major floats, and both follow
    Pinocchio's operations (:func:`quaternion_to_rotation`, :func:`rotation_to_rpy`).
    """
    x, y, z, qx, qy, qz, qw = qv.tolist() if isinstance(qv, np.ndarray) else qv
    R = quaternion_to_rotation(qx, qy, qz, qw)
    return [x, y, z, *rotation_to_rpy(R)], R


def fossen_jacobian_values(R: Sequence[float], phi: float, theta: float) -> tuple[float, ...]:
    """Fossen's ``J = blkdiag(R, T(phi, theta))`` (6 x 6), row-major floats.

    ``003_229789978cc4b235.txt``, Eq. (2)-(3): ``R`` the body-to-world rotation (9 row-major
    floats), ``T = [[1, s(phi) t(theta), c(phi) t(theta)], [0, c(phi), -s(phi)],
    [0, s(phi)/c(theta), c(phi)/c(theta)]]`` [rad].
    """
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = R
    sphi, cphi = math.sin(phi), math.cos(phi)
    ctheta, ttheta = math.cos(theta), math.tan(theta)
    return (r00, r01, r02, 0.0, 0.0, 0.0,
            r10, r11, r12, 0.0, 0.0, 0.0,
            r20, r21, r22, 0.0, 0.0, 0.0,
            0.0, 0.0, 0.0, 1.0, sphi * ttheta, cphi * ttheta,
            0.0, 0.0, 0.0, 0.0, cphi, -sphi,
            0.0, 0.0, 0.0, 0.0, sphi / ctheta, cphi / ctheta)


@dataclass(frozen=True)
class Vehicle:
    """A vehicle kind with its actuated DOFs and optional rate limits.

    Attributes:
        kind: ``"planar"``, ``"spatial"`` or ``"fixed"``.
        actuated: Names of actuated body rates (subset of ``("u","v","w","p","q","r")`` for
            spatial, of ``("u","v","r")`` for planar), stored in ``nu`` order. None = all.
        rate_limit: Symmetric limit per actuated rate [m/s or rad/s] (``inf`` = none). None = all
            unlimited.

    Example:
        ``Vehicle("spatial", actuated=("u", "v", "w", "r"))`` is a 4-DOF ROV with passive roll and
        pitch (paper ``003_229789978cc4b235.txt``, Section "Simulation setup").
    """

    kind: VehicleKind = "spatial"
    actuated: tuple[str, ...] | None = None
    rate_limit: tuple[float, ...] | None = field(default=None)

    def __post_init__(self) -> None:
        if self.kind not in DOF_NAMES:
            raise InputError(
                f"vehicle kind: unknown {self.kind!r}; known kinds: planar, spatial, fixed"
            )
        dofs = DOF_NAMES[self.kind]
        names = dofs if self.actuated is None else tuple(self.actuated)
        for n in names:
            if n not in dofs:
                raise InputError(
                    f"vehicle actuated: unknown {self.kind} DOF {n!r}; known: {', '.join(dofs)}"
                )
        if len(set(names)) != len(names):
            raise InputError(f"vehicle actuated: repeated DOF in {names}")
        ordered = tuple(n for n in dofs if n in names)
        object.__setattr__(self, "actuated", ordered)
        if self.rate_limit is None:
            limit = (math.inf,) * len(ordered)
        else:
            vec = as_vector(self.rate_limit, "vehicle rate_limit", len(ordered), allow_inf=True)
            if np.any(vec <= 0.0):
                raise InputError(f"vehicle rate_limit: must be positive, got {vec.tolist()}")
            limit = tuple(float(x) for x in vec)
        object.__setattr__(self, "rate_limit", limit)

    @property
    def dofs(self) -> tuple[str, ...]:
        """All velocity DOF names of this kind, in Pinocchio velocity order."""
        return DOF_NAMES[self.kind]

    @property
    def passive(self) -> tuple[str, ...]:
        """Velocity DOFs that are not actuated."""
        actuated = self.actuated or ()
        return tuple(n for n in self.dofs if n not in actuated)

    @property
    def nq(self) -> int:
        """Size of the vehicle part of the Pinocchio configuration."""
        return _NQ[self.kind]

    @property
    def nv(self) -> int:
        """Number of vehicle velocity DOFs (actuated and passive)."""
        return len(self.dofs)

    @property
    def eta_size(self) -> int:
        """Length of the vehicle pose ``eta`` (6 spatial, 3 planar, 0 fixed)."""
        return len(ETA_NAMES[self.kind])

    @property
    def actuated_indices(self) -> tuple[int, ...]:
        """Indices of the actuated DOFs in the vehicle velocity vector."""
        return tuple(self.dofs.index(n) for n in self.actuated or ())

    def pin_joint(self) -> pin.JointModel | None:
        """The Pinocchio joint model of this vehicle (None for a fixed base)."""
        if self.kind == "spatial":
            return pin.JointModelFreeFlyer()
        if self.kind == "planar":
            return pin.JointModelPlanar()
        return None

    # --- pose <-> configuration ------------------------------------------------------------

    def q_from_eta(self, eta: FloatArray) -> FloatArray:
        """Vehicle configuration from a pose ``eta`` (validated by the caller)."""
        if self.kind == "spatial":
            quat = pin.Quaternion(pin.rpy.rpyToMatrix(eta[3], eta[4], eta[5]))
            return np.concatenate((eta[:3], quat.coeffs()))
        if self.kind == "planar":
            return np.array([eta[0], eta[1], math.cos(eta[2]), math.sin(eta[2])])
        return np.zeros(0)

    def eta_from_q(self, qv: FloatArray) -> FloatArray:
        """Vehicle pose ``eta`` from the vehicle configuration (angles in [rad])."""
        return np.array(self.eta_values(qv))

    def eta_values(self, qv: Any) -> list[float]:
        """:meth:`eta_from_q` as a list of floats (no array; for the per-tick state update).

        Spatial: the rotation of the unit quaternion and its Z-Y-X Euler angles, computed with
        the same floating-point operations as Pinocchio (:func:`quaternion_to_rotation`,
        :func:`rotation_to_rpy`).
        """
        if self.kind == "spatial":
            return spatial_eta_and_rotation(qv)[0]
        if self.kind == "planar":
            x, y, c, s = qv.tolist() if isinstance(qv, np.ndarray) else qv
            return [x, y, math.atan2(s, c)]
        return []

    def pose_jacobian(self, eta: FloatArray) -> FloatArray:
        """Full kinematic transformation ``eta_dot = J(eta) @ v`` over all vehicle DOFs.

        Spatial (Fossen; ``003_229789978cc4b235.txt``, Eq. (2)-(3)):
        ``J = blkdiag(R(Theta), T(Theta))`` with ``R = Rz(psi) Ry(theta) Rx(phi)`` and
        ``T = [[1, s(phi) t(theta), c(phi) t(theta)], [0, c(phi), -s(phi)],
        [0, s(phi)/c(theta), c(phi)/c(theta)]]`` (singular at ``theta = +/- pi/2``).
        Planar: ``J = blkdiag(R2(psi), 1)``.

        Args:
            eta: Vehicle pose [m, rad].

        Returns:
            ``(eta_size, nv_vehicle)`` matrix.
        """
        return np.array(self.pose_jacobian_values(eta)).reshape(self.eta_size, self.nv)

    def pose_jacobian_values(self, eta: Any) -> tuple[float, ...]:
        """:meth:`pose_jacobian` as a flat row-major tuple of floats (for the state update).

        The rotation block is built with the operations of Pinocchio's ``rpy.rpyToMatrix``
        (:func:`rpy_to_rotation`), so the numbers equal those of a Pinocchio-built matrix.
        """
        if self.kind == "spatial":
            angles = eta[3:6]
            phi, theta, psi = (angles.tolist() if isinstance(angles, np.ndarray)
                               else (float(a) for a in angles))
            return fossen_jacobian_values(rpy_to_rotation(phi, theta, psi), phi, theta)
        if self.kind == "planar":
            c, s = math.cos(eta[2]), math.sin(eta[2])
            return (c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
        return ()


def resolve_vehicle(value: Any) -> Vehicle:
    """Accept a :class:`Vehicle` or a kind string (all DOFs actuated, no rate limits).

    Raises:
        InputError: unknown kind or wrong type.
    """
    if isinstance(value, Vehicle):
        return value
    if isinstance(value, str):
        return Vehicle(value)  # type: ignore[arg-type]
    raise InputError(
        f"vehicle: expected a Vehicle or one of 'planar', 'spatial', 'fixed', got {value!r}"
    )


def check_joint_names(names: Sequence[str], reserved: Sequence[str]) -> tuple[str, ...]:
    """Reject joint names that collide with vehicle DOF names or each other.

    Raises:
        ModelError: a duplicate or reserved name.
    """
    out = tuple(names)
    if len(set(out)) != len(out):
        raise ModelError(f"joint names must be unique, got {list(out)}")
    clash = [n for n in out if n in reserved]
    if clash:
        raise ModelError(f"joint names {clash} clash with vehicle DOF names {list(reserved)}")
    return out
