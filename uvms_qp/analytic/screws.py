"""Screw-based differential kinematics (dos Santos et al. (2006), Eq. (1)-(12)).

A normalised screw is ``$ = [S; S_o x S]`` (Eq. 1): S the unit axis direction and ``S_o`` the
position of a point on the axis, so that a twist ``$ Psi = [omega; V_O]`` (Eq. 2) holds the angular
velocity first and the linear velocity of the body point coincident with the reference origin O
second. (The paper's wording says ``S_o`` points from the axis to the origin; the moment
``S_o x S`` is the standard one only for the position of the axis point, used here.) A prismatic
joint is ``[0; S]``.

Pinocchio orders twists the other way (linear first) and reports the velocity of the frame's
origin: :func:`screw_to_twist_at` converts, so a screw Jacobian can be checked against
``State.jacobian(frame, axes="world")``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._validation import as_matrix, as_scalar, as_vector
from ..errors import InputError, ShapeError
from ._checks import FloatArray, jacobian


def skew(v: Any) -> FloatArray:
    """Skew matrix ``[v x]`` of a 3-vector (dos Santos et al. (2006), Eq. (3)'s W)."""
    x, y, z = as_vector(v, "v", 3)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def _unit(axis: Any, name: str) -> FloatArray:
    a = as_vector(axis, name, 3)
    norm = float(np.linalg.norm(a))
    if norm < 1e-12:
        raise InputError(f"{name}: expected a non-zero axis")
    return a / norm


def revolute_screw(axis: Any, point: Any) -> FloatArray:
    """Normalised screw ``[S; p x S]`` of a revolute joint (pitch 0), Eq. (1).

    Args:
        axis: (3,) axis direction (normalised here).
        point: (3,) any point on the axis [m].

    Returns:
        (6,) screw ``[omega per unit rate; V_O per unit rate]``.
    """
    S = _unit(axis, "axis")
    p = as_vector(point, "point", 3)
    return np.concatenate([S, np.cross(p, S)])


def prismatic_screw(axis: Any) -> FloatArray:
    """Normalised screw ``[0; S]`` of a prismatic joint (infinite pitch)."""
    return np.concatenate([np.zeros(3), _unit(axis, "axis")])


def screw_transform(rotation: Any, position: Any) -> FloatArray:
    """Screw transformation ``iT_j = [[R, 0], [W R, R]]``, Eq. (3).

    Maps a screw expressed in frame j to frame i, where ``R = iR_j`` and ``W = [p x]`` with
    ``p = i p_j`` the origin of j in i [m].

    Returns:
        (6, 6) matrix.
    """
    R = as_matrix(rotation, "rotation", 3, 3)
    W = skew(position)
    T = np.zeros((6, 6))
    T[:3, :3] = R
    T[3:, 3:] = R
    T[3:, :3] = W @ R
    return T


def screw_jacobian(
    axes: Any, points: Sequence[Any] | Any, kinds: Sequence[str] | None = None
) -> FloatArray:
    """Screw Jacobian: the normalised joint screws as columns (Eq. (4), (11)-(12)).

    Args:
        axes: (n, 3) joint axis directions in the reference frame.
        points: (n, 3) a point on each axis [m] (ignored for prismatic joints).
        kinds: n strings ``"revolute"`` / ``"prismatic"``; None means all revolute.

    Returns:
        (6, n) matrix ``[omega; V_O]`` per unit joint rate.
    """
    A = as_matrix(axes, "axes", cols=3)
    n = A.shape[0]
    P = as_matrix(points, "points", n, 3)
    if kinds is None:
        kinds = ["revolute"] * n
    if len(kinds) != n:
        raise ShapeError(f"kinds: expected {n} entries, got {len(kinds)}")
    cols = []
    for i, kind in enumerate(kinds):
        if kind == "revolute":
            cols.append(revolute_screw(A[i], P[i]))
        elif kind == "prismatic":
            cols.append(prismatic_screw(A[i]))
        else:
            raise InputError(f"kinds[{i}]: expected 'revolute' or 'prismatic', got {kind!r}")
    return np.stack(cols, axis=1)


def screw_to_twist_at(J_screw: Any, point: Any) -> FloatArray:
    """Re-express screw columns as ``[v_P; omega]`` twists at a point P (Pinocchio's order).

    ``v_P = V_O + omega x P``: the linear velocity of the body point at P. The result is what
    Pinocchio calls a LOCAL_WORLD_ALIGNED frame Jacobian when P is the frame origin and the
    screws are expressed in world axes.

    Args:
        J_screw: (6, n) screw Jacobian ``[omega; V_O]``.
        point: (3,) point P in the reference frame [m].

    Returns:
        (6, n) Jacobian ``[v_P; omega]``.
    """
    J = jacobian(J_screw, "J_screw")
    if J.shape[0] != 6:
        raise ShapeError(f"J_screw: expected 6 rows, got {J.shape[0]}")
    P = as_vector(point, "point", 3)
    omega = J[:3]
    v = J[3:] - skew(P) @ omega
    return np.vstack([v, omega])


def planar_rows(J_screw: Any) -> FloatArray:
    """Planar components ``(omega_z, v_x, v_y)`` of 6-row screws (rows 2, 3, 4).

    For motion in the x-y plane the other three components vanish; the Davies method then works on
    these 3 rows (a 3-joint planar arm gives a square 3 x 3 secondary matrix).
    """
    J = jacobian(J_screw, "J_screw")
    if J.shape[0] != 6:
        raise ShapeError(f"J_screw: expected 6 rows, got {J.shape[0]}")
    return J[[2, 3, 4]]


def planar_chain_points(
    joint_angles: Any,
    link_lengths: Any,
    base_position: Any = (0.0, 0.0),
    base_yaw: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """Joint and tip positions of a planar serial chain of revolute z joints.

    Joint 1 sits at ``base_position`` with the chain heading ``base_yaw``; link i has length
    ``link_lengths[i]`` and the absolute angle ``base_yaw + q_1 + ... + q_i``.

    Args:
        joint_angles: (n,) relative joint angles [rad].
        link_lengths: (n,) link lengths [m].
        base_position: (2,) position of joint 1 [m].
        base_yaw: Heading of the chain base [rad].

    Returns:
        ``(points, angles)``: (n + 1, 3) positions of joints 1..n and of the tip (z = 0) [m], and
        (n,) absolute link angles [rad] (the tip orientation is ``angles[-1]``).
    """
    q = as_vector(joint_angles, "joint_angles")
    lengths = as_vector(link_lengths, "link_lengths", q.shape[0])
    base = as_vector(base_position, "base_position", 2)
    yaw = as_scalar(base_yaw, "base_yaw")
    angles = yaw + np.cumsum(q)
    steps = np.stack([lengths * np.cos(angles), lengths * np.sin(angles)], axis=1)
    xy = np.vstack([base, base + np.cumsum(steps, axis=0)])
    return np.hstack([xy, np.zeros((xy.shape[0], 1))]), angles


def planar_chain_screws(
    joint_angles: Any,
    link_lengths: Any,
    base_position: Any = (0.0, 0.0),
    base_yaw: float = 0.0,
) -> FloatArray:
    """Screw Jacobian of a planar chain of revolute z joints (dos Santos et al. (2006), Eq. (4)).

    Returns:
        (6, n) normalised screws ``[0, 0, 1; y_i, -x_i, 0]`` at the joint points, in the reference
        (world) frame.
    """
    points, _ = planar_chain_points(joint_angles, link_lengths, base_position, base_yaw)
    n = points.shape[0] - 1
    return screw_jacobian(np.tile([0.0, 0.0, 1.0], (n, 1)), points[:n])
