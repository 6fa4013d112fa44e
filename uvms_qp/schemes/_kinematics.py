"""Kinematic quantities the paper schemes read from a model state (internal).

Thin adapters from a :class:`~uvms_qp.model.State` to the library's formulas: the arm
manipulability and its exact gradient (Soylu et al. (2007), Eq. (18)-(19),
Wang et al. (2017), Eq. (18)-(19); computed by
:func:`uvms_qp.tasks.manipulability_and_gradient`) and Wang et al.'s (2017) payload objective
(Eq. (20)-(21), :mod:`uvms_qp.analytic.payload`). Gradients are returned over zeta, with zeros on
the vehicle columns: neither quantity depends on the vehicle pose.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._validation import FloatArray
from ..analytic.payload import payload_objective, payload_objective_gradient
from ..tasks.manipulability import manipulability_and_gradient

if TYPE_CHECKING:  # pragma: no cover
    from ..model import State


def arm_manipulability(
    state: State, rows: tuple[int, ...], frame: str = "tool"
) -> tuple[float, FloatArray]:
    """Manipulability of the arm's position Jacobian and its gradient over zeta.

    ``rho = sqrt(det(J J^T))`` with ``J`` the world-axes position rows ``rows`` of ``frame`` over
    the arm-joint columns (Soylu et al. (2007), Eq. (18); there it equals the measure of the
    collective Jacobian ``J_a = [J_p; J_s]``, see :func:`uvms_qp.analytic.manipulability`).

    Args:
        state: Model state.
        rows: Position rows kept (``(0, 1)`` for a planar task, ``(0, 1, 2)`` spatial).
        frame: Tool frame name.

    Returns:
        ``(rho, gradient)``; the gradient has length ``nv`` [units of rho per rad].
    """
    model = state.model
    nveh = model.n_vehicle
    J6 = state.jacobian(frame)[:, nveh:]
    rho, grad = manipulability_and_gradient(J6, np.asarray(rows, dtype=int))
    gradient = np.zeros(model.nv)
    gradient[nveh:] = grad
    return float(rho), gradient


def tool_in_base(state: State, frame: str = "tool") -> FloatArray:
    """Tool position in the arm base frame Sigma_0 (3,) [m]."""
    return state.pose_in(frame, "arm_base")[:3, 3]


def payload_term(state: State, force: float, frame: str = "tool") -> tuple[float, FloatArray]:
    """Payload objective ``M = (x_E^2 + y_E^2) F`` and its gradient over zeta.

    Wang et al. (2017), Eq. (20)-(21), with ``x_E``, ``y_E`` the tool coordinates in
    the arm base frame and ``F`` [N] the load at the tool.

    Returns:
        ``(M [N m^2], gradient [N m^2 / rad])``.
    """
    model = state.model
    p = tool_in_base(state, frame)
    gradient = np.zeros(model.nv)
    if force == 0.0:
        return 0.0, gradient
    Jb = state.arm_jacobian(frame, rows="position")
    gradient[model.n_vehicle :] = payload_objective_gradient(p, Jb, force)
    return payload_objective(p, force), gradient
