"""Payload-moment objective of ``003_229789978cc4b235.txt, Eq. (20)-(21)``."""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import ShapeError
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
