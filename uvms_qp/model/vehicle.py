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
from .transforms import quaternion_to_rotation, rotation_to_rpy, rpy_to_rotation

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
        pitch (Wang et al. (2017), Section "Simulation setup").
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
            R = np.array(rpy_to_rotation(*eta[3:6].tolist())).reshape(3, 3)
            return np.concatenate((eta[:3], pin.Quaternion(R).coeffs()))
        if self.kind == "planar":
            return np.array([eta[0], eta[1], math.cos(eta[2]), math.sin(eta[2])])
        return np.zeros(0)

    def pose(self, qv: Sequence[float]) -> tuple[list[float], tuple[float, ...]]:
        """``eta`` [m, rad] and ``R_world_body`` (9 row-major floats) of a vehicle configuration.

        Spatial: the rotation of the unit quaternion ``qv[3:7]`` and its Z-Y-X Euler angles
        (:func:`~uvms_qp.model.transforms.quaternion_to_rotation`,
        :func:`~uvms_qp.model.transforms.rotation_to_rpy`); planar: ``[x, y, atan2(s, c)]``
        (the rotation is not needed: empty); fixed: both empty.
        """
        if self.kind == "spatial":
            x, y, z, qx, qy, qz, qw = qv
            R = quaternion_to_rotation(qx, qy, qz, qw)
            return [x, y, z, *rotation_to_rpy(R)], R
        if self.kind == "planar":
            x, y, c, s = qv
            return [x, y, math.atan2(s, c)], ()
        return [], ()

    def eta_from_q(self, qv: FloatArray) -> FloatArray:
        """Vehicle pose ``eta`` [m, rad] of the vehicle configuration ``qv`` (see :meth:`pose`)."""
        return np.array(self.pose(np.asarray(qv, dtype=np.float64).tolist())[0])

    @property
    def pose_jacobian_pattern(self) -> tuple[tuple[int, int], ...]:
        """``(row, column)`` of the entries of :meth:`pose_jacobian` that can be non-zero."""
        if self.kind == "spatial":
            return tuple((r, c) for block in (0, 3) for r in range(block, block + 3)
                         for c in range(block, block + 3))
        if self.kind == "planar":
            return ((0, 0), (0, 1), (1, 0), (1, 1), (2, 2))
        return ()

    def pose_jacobian_entries(self, eta: Sequence[float], rotation: Sequence[float]
                              ) -> list[float]:
        """The entries of :attr:`pose_jacobian_pattern` at ``eta`` [m, rad] (plain floats).

        Spatial (Fossen; Wang et al. (2017), Eq. (2)-(3)):
        ``J = blkdiag(R(Theta), T(Theta))`` with ``R = Rz(psi) Ry(theta) Rx(phi)`` given as
        ``rotation`` (9 row-major floats) and ``T = [[1, s(phi) t(theta), c(phi) t(theta)],
        [0, c(phi), -s(phi)], [0, s(phi)/c(theta), c(phi)/c(theta)]]`` (singular at
        ``theta = +/- pi/2``). Planar: ``J = blkdiag(R2(psi), 1)`` (``rotation`` unused).
        """
        if self.kind == "spatial":
            phi, theta = eta[3], eta[4]
            sphi, cphi = math.sin(phi), math.cos(phi)
            ctheta, ttheta = math.cos(theta), math.tan(theta)
            return [*rotation, 1.0, sphi * ttheta, cphi * ttheta, 0.0, cphi, -sphi,
                    0.0, sphi / ctheta, cphi / ctheta]
        if self.kind == "planar":
            c, s = math.cos(eta[2]), math.sin(eta[2])
            return [c, -s, s, c, 1.0]
        return []

    def pose_jacobian(self, eta: Any) -> FloatArray:
        """Full kinematic transformation ``eta_dot = J(eta) @ v`` over all vehicle DOFs.

        See :meth:`pose_jacobian_entries` (the rotation built from ``eta``).

        Args:
            eta: Vehicle pose [m, rad].

        Returns:
            ``(eta_size, nv_vehicle)`` matrix.
        """
        values = np.asarray(eta, dtype=np.float64).tolist()
        R = rpy_to_rotation(*values[3:6]) if self.kind == "spatial" else ()
        J = np.zeros((self.eta_size, self.nv))
        for (r, c), v in zip(self.pose_jacobian_pattern, self.pose_jacobian_entries(values, R),
                             strict=True):
            J[r, c] = v
        return J


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
