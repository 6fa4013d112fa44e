"""Small helpers shared by the task modules (axis parsing, angle wrapping, rotation checks)."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
import pinocchio as pin

from .._validation import FloatArray, as_matrix, as_vector
from ..errors import InputError, ShapeError
from ..model.transforms import rpy_to_matrix

TWIST_AXES = ("x", "y", "z", "rx", "ry", "rz")
"""Row names of a twist ``[v; omega]``: linear x, y, z [m/s] then angular x, y, z [rad/s]."""


def wrap_angle(angle: float) -> float:
    """Wrap an angle [rad] to ``[-pi, pi)``."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def parse_axes(axes: Any, allowed: Sequence[str], label: str) -> list[str]:
    """Validate a list of axis names (each in ``allowed``, no duplicates) and return it.

    A single string is accepted as one axis (``"z"``) or as a compact list (``"xy"`` -> x, y)
    when every character is an allowed axis.
    """
    if isinstance(axes, str):
        if axes in allowed:
            axes = [axes]
        elif all(c in allowed for c in axes):
            axes = list(axes)
        else:
            raise InputError(f"{label}: unknown axis {axes!r}; known axes: {', '.join(allowed)}")
    if not isinstance(axes, list | tuple) or not axes:
        raise InputError(f"{label}: expected a non-empty list of axis names from "
                         f"{', '.join(allowed)}, got {axes!r}")
    out: list[str] = []
    for a in axes:
        if a not in allowed:
            raise InputError(f"{label}: unknown axis {a!r}; known axes: {', '.join(allowed)}")
        if a in out:
            raise InputError(f"{label}: axis {a!r} given twice")
        out.append(a)
    return out


def as_rotation(value: Any, label: str) -> FloatArray:
    """Validate a rotation: a 3x3 orthonormal matrix with det +1, or ``[roll, pitch, yaw]`` [rad].

    Euler angles follow the Z-Y-X convention: ``R = Rz(yaw) Ry(pitch) Rx(roll)``.

    Raises:
        ShapeError: neither 3 angles nor a 3x3 matrix.
        InputError: a matrix that is not a rotation (orthonormality tolerance 1e-6).
    """
    try:
        ndim = np.ndim(value)
    except ValueError as exc:  # ragged nested lists
        raise ShapeError(f"{label}: expected 3 angles or a 3x3 matrix") from exc
    if ndim <= 1:
        rpy = as_vector(value, label, 3)
        return rpy_to_matrix(rpy)
    R = as_matrix(value, label, 3, 3)
    err = float(np.abs(R.T @ R - np.eye(3)).max())
    if err > 1e-6:
        raise InputError(f"{label}: not a rotation matrix (|R'R - I| = {err:.2e})")
    if np.linalg.det(R) < 0.0:
        raise InputError(f"{label}: not a rotation matrix (det < 0, a reflection)")
    return R


def as_pose(value: Any, label: str) -> FloatArray:
    """Validate a pose: a ``pinocchio.SE3``, a 4x4 homogeneous matrix or ``{"xyz", "rpy"}``.

    Returns:
        A new 4x4 array ``[[R, p], [0, 1]]`` [m].

    Raises:
        ShapeError: not 4x4.
        InputError: a bottom row other than ``[0, 0, 0, 1]``, a 3x3 block that is not a
            rotation (tolerance 1e-6), unknown mapping keys.
        NonFiniteError: NaN or inf entries.
    """
    if isinstance(value, pin.SE3):
        T = np.array(value.homogeneous)
    elif isinstance(value, Mapping):
        unknown = sorted(set(value) - {"xyz", "rpy"})
        if unknown:
            raise InputError(f"{label}: unknown keys {unknown}; expected 'xyz' and/or 'rpy'")
        T = np.eye(4)
        T[:3, :3] = as_rotation(value.get("rpy", (0.0, 0.0, 0.0)), f"{label}.rpy")
        T[:3, 3] = as_vector(value.get("xyz", (0.0, 0.0, 0.0)), f"{label}.xyz", 3)
        return T
    else:
        T = as_matrix(value, label, 4, 4).copy()
    if T[3].tolist() != [0.0, 0.0, 0.0, 1.0]:
        raise InputError(f"{label}: the bottom row of a homogeneous transform must be "
                         f"[0, 0, 0, 1], got {T[3].tolist()}")
    as_rotation(T[:3, :3], label)
    return T


def as_point(value: Any, label: str, vehicle_kind: str | None = None) -> FloatArray:
    """A 3-vector [m] (or [m/s]), world frame; a 2-vector gets ``z = 0`` on planar models only.

    Args:
        value: 3 coordinates ``(x, y, z)``, or 2 coordinates ``(x, y)`` for a planar model.
        label: Name of the argument, used in error messages.
        vehicle_kind: Kind of the model the point is for (``"planar"``, ``"spatial"``,
            ``"fixed"``), or None when it is not known yet (the caller re-checks at bind with
            :func:`check_planar_point`).

    Raises:
        ShapeError: not 2 or 3 coordinates, or 2 coordinates for a non-planar model.
    """
    p = as_vector(value, label)
    if p.shape[0] == 2:
        check_planar_point(label, vehicle_kind)
        p = np.array([p[0], p[1], 0.0])
    if p.shape[0] != 3:
        raise ShapeError(f"{label}: expected 2 or 3 coordinates, got {p.shape[0]}")
    return p


def check_planar_point(label: str, vehicle_kind: str | None) -> None:
    """Reject a 2-coordinate point ``label`` unless the model is planar (or not known yet).

    Raises:
        ShapeError: ``vehicle_kind`` is known and not ``"planar"`` (the z coordinate would be
            silently taken as 0 on a model that moves in 3-D).
    """
    if vehicle_kind is not None and vehicle_kind != "planar":
        raise ShapeError(f"{label}: got 2 coordinates, but the model is {vehicle_kind}; "
                         "give 3 (x, y, z) (2 are allowed only on planar models)")


def check_frame(model: Any, frame: Any, label: str) -> str:
    """Check that ``frame`` names a frame of ``model`` (raises UnknownFrameError otherwise)."""
    if not isinstance(frame, str):
        raise InputError(f"{label}: expected a frame name, got {type(frame).__name__}")
    model.frame_id(frame)  # raises UnknownFrameError listing the known frames
    return frame


def check_choice(value: Any, choices: Sequence[str], label: str) -> str:
    """Return ``value`` if it is one of the strings ``choices``, else raise InputError."""
    if not isinstance(value, str) or value not in choices:
        raise InputError(f"{label}: expected one of {', '.join(map(repr, choices))}, "
                         f"got {value!r}")
    return value


ANGLE_AXES = frozenset({"phi", "theta", "psi"})


def pose_units(axes: Sequence[str]) -> tuple[str, str]:
    """``(error unit, rate unit)`` of rows over the pose axes ``axes``.

    Positions (``x, y, z``) in m and m/s, angles (any other axis: ``rx``..., ``phi``...) in
    rad and rad/s; ``("m, rad", "m/s, rad/s")`` for a mix.
    """
    linear = any(a in _POSITION_AXES for a in axes)
    angular = any(a not in _POSITION_AXES for a in axes)
    error = ", ".join(u for u, on in (("m", linear), ("rad", angular)) if on)
    rate = ", ".join(u for u, on in (("m/s", linear), ("rad/s", angular)) if on)
    return error, rate


_POSITION_AXES = frozenset({"x", "y", "z"})
