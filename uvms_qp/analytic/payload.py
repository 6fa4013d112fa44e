"""Payload moment: the objective of Wang et al. (2017), Eq. (20)-(21), and the vehicle's tilt.

Wang et al. (2017) minimise ``M = (x_E^2 + y_E^2) F`` so that a vehicle without active roll and
pitch control keeps "small pitch and roll angles"; the paper gives no model of that response.
:func:`vehicle_payload_moment` and :func:`static_tilt` are this library's model of it: the
moment of the load about the vehicle's centre of buoyancy, balanced by the hydrostatic restoring
moment of a submerged vehicle whose centre of gravity lies a distance BG below its centre of
buoyancy (Fossen, Handbook of Marine Craft Hydrodynamics and Motion Control, Wiley 2011,
Section 4.1: with W = B the restoring moments are ``W BG cos(theta) sin(phi)`` in roll and
``W BG sin(theta)`` in pitch; for a submerged body both metacentric heights equal BG).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import InputError, ShapeError
from ._checks import FloatArray, jacobian


def payload_objective(position: Any, force: float) -> float:
    """``M(q) = (x_E^2 + y_E^2) F``, Eq. (20) [N m^2].

    Args:
        position: End-effector position in the arm base frame Sigma_0 [m]; (2,) or (3,) (only x
            and y are used: F acts along the base z axis).
        force: Payload force F [N] along z (gravity minus buoyancy).

    Returns:
        M. Note the units: Eq. (20) squares the lever arm, so M is not itself a moment; the
        moment is :func:`payload_moment`.
    """
    p = as_vector(position, "position")
    if p.shape[0] not in (2, 3):
        raise ShapeError(f"position: expected length 2 or 3, got {p.shape[0]}")
    F = as_scalar(force, "force")
    return float((p[0] ** 2 + p[1] ** 2) * F)


def payload_moment(position: Any, force: float) -> float:
    """Moment of the payload about the base z axis ``F sqrt(x_E^2 + y_E^2)`` [N m].

    The physical quantity Eq. (20) stands for (its minimiser is the same for F > 0); use it for
    the ``payload_moment_max`` metric.
    """
    p = as_vector(position, "position")
    F = as_scalar(force, "force")
    return float(abs(F) * np.hypot(p[0], p[1]))


def payload_objective_gradient(position: Any, position_jacobian: Any, force: float) -> FloatArray:
    """``dM/dq_i = 2 x_E dx_E/dq_i F + 2 y_E dy_E/dq_i F``, Eq. (21) [N m^2 / rad].

    Args:
        position: End-effector position in Sigma_0 [m], (2,) or (3,).
        position_jacobian: (2 or 3, n) Jacobian of that position in Sigma_0 axes [m/rad]; only its
            x and y rows are used.
        force: Payload force F [N].

    Returns:
        (n,) gradient over the arm joints.
    """
    p = as_vector(position, "position")
    J = jacobian(position_jacobian, "position_jacobian")
    if J.shape[0] < 2 or J.shape[0] != p.shape[0]:
        raise ShapeError(
            f"position_jacobian: expected {p.shape[0]} rows matching position, got {J.shape[0]}"
        )
    F = as_scalar(force, "force")
    return 2.0 * F * (p[0] * J[0] + p[1] * J[1])


def vehicle_payload_moment(offset: Any, force: float) -> FloatArray:
    """Roll and pitch moments of a vertical load on a level vehicle ``(m_x, m_y)`` [N m].

    The load ``F`` acts along the body z axis (down; the vehicle is level), at ``offset`` from the
    point the vehicle turns about (its centre of buoyancy, taken as the vehicle origin):
    ``m = r x (0, 0, F) = (r_y F, -r_x F, 0)`` in body axes (x forward, y starboard, z down). A
    load ahead of the centre (``r_x > 0``) pushes the nose down (``m_y < 0``).

    Args:
        offset: (3,) point of application in the vehicle frame [m] (only x and y are used).
        force: Load F [N], positive down (weight minus buoyancy of the payload).

    Returns:
        (2,) ``[m_x, m_y]`` [N m].
    """
    r = as_vector(offset, "offset", 3)
    F = as_scalar(force, "force")
    return np.array([r[1] * F, -r[0] * F])


def static_tilt(moment: Any, weight: float, metacentric_height: Any) -> FloatArray:
    """Static roll and pitch ``(phi, theta)`` [rad] that balance a moment on a submerged vehicle.

    Equilibrium of the hydrostatic restoring moment with an external moment ``(m_x, m_y)`` (body
    axes, e.g. :func:`vehicle_payload_moment`)::

        W GM_L sin(theta) = m_y,      W GM_T cos(theta) sin(phi) = m_x

    with ``W`` the weight (= buoyancy) and ``GM_T``, ``GM_L`` the transverse and longitudinal
    metacentric heights (both BG for a submerged vehicle). For small angles the tilt is the moment
    over the restoring stiffness ``W GM``.

    Args:
        moment: (2,) ``[m_x, m_y]`` [N m].
        weight: W [N], positive.
        metacentric_height: GM [m], positive; a scalar (submerged: BG) or ``(GM_T, GM_L)``.

    Returns:
        (2,) ``[phi, theta]`` [rad].

    Raises:
        InputError: a moment larger than the restoring moment can balance (no upright
            equilibrium: the vehicle would capsize), or non-positive W or GM.
    """
    m = as_vector(moment, "moment", 2)
    W = as_scalar(weight, "weight", positive=True)
    gm = np.atleast_1d(np.asarray(metacentric_height, dtype=np.float64))
    gm = as_vector(np.repeat(gm, 2) if gm.size == 1 else gm, "metacentric_height", 2)
    if np.any(gm <= 0.0):
        raise InputError(f"metacentric_height: expected positive heights, got {gm.tolist()}")
    k_roll, k_pitch = W * gm
    sin_theta = m[1] / k_pitch
    if abs(sin_theta) >= 1.0:
        raise InputError(
            f"moment: the pitch moment {m[1]:.4g} N m exceeds the restoring moment "
            f"W GM_L = {k_pitch:.4g} N m (no upright equilibrium)"
        )
    theta = float(np.arcsin(sin_theta))
    sin_phi = m[0] / (k_roll * np.cos(theta))
    if abs(sin_phi) >= 1.0:
        raise InputError(
            f"moment: the roll moment {m[0]:.4g} N m exceeds the restoring moment "
            f"W GM_T cos(theta) = {k_roll * np.cos(theta):.4g} N m (no upright equilibrium)"
        )
    return np.array([float(np.arcsin(sin_phi)), theta])
