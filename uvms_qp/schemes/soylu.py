"""Soylu et al. (2007): singularity-robust and dexterous task priority.

Two schemes for a planar vehicle-manipulator whose primary task is the tool position
``x_p = [x_e, y_e]`` and whose secondary task holds the vehicle pose ``x_s = [x_v, y_v, psi_v]``:

* :class:`SoyluTaskPriority`, the closed-loop singularity-robust task priority with the weighted
  pseudoinverse, Soylu et al. (2007), Eq. (16)-(17)::

      zeta = J_W^+ (xdot_p + K_p e_p) + (I - J_W^+ J_p) J_s^+ (xdot_s + K_s e_s)

* :class:`SoyluDexterous`, the dexterous task priority of Eq. (21): below the threshold
  ``rho_bar`` the shaping function ``k(rho)`` hands the secondary demand over to the ascent of the
  manipulability (Eq. 18-19), active only while rho is not increasing (sign switch, Eq. 20).

Secondary task (Section 3): "the current URV position value is entered as the desired position
values for the next step": the desired vehicle pose is the pose at the previous tick and
``xdot_s = 0``, so ``K_s e_s`` opposes the vehicle's last displacement. The first tick has
``e_s = 0``. Rates are over zeta (vehicle body rates), with ``J_s = J_eta`` the vehicle pose
Jacobian (``eta_dot = J_eta zeta``); a diagonal W with equal u, v weights is invariant under the
body/world rotation, so ``W = diag(10, 10, 10, 1, 1, 1)`` means the same in both.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..analytic.manipulability import dexterous_task_priority, shaping_function, sign_switch
from ..analytic.task_priority import closed_loop_reference, singularity_robust_task_priority
from ..errors import InputError
from ._kinematics import arm_manipulability
from .scheme import Scheme

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_PLANAR_ROWS = (0, 1)


def _wrap(angle: float) -> float:
    return (angle + np.pi) % (2.0 * np.pi) - np.pi


class SoyluTaskPriority(Scheme):
    """Closed-loop singularity-robust task priority, Soylu et al. (2007), Eq. (16).

    Args:
        weights: Diagonal of W over zeta (paper: ``[10, 10, 10, 1, 1, 1]``) [-].
        tool_gain: K_p per tool axis x, y [1/s] (paper: ``[10, 10]``).
        vehicle_gain: K_s per vehicle coordinate x, y, psi [1/s] (paper: ``[10, 10, 100]``).
        frame: Tool frame.
        name: Label in results.
    """

    type_name = "soylu_sr_task_priority"
    vehicle_kinds = ("planar",)

    def __init__(
        self,
        *,
        weights: Sequence[float] = (10.0, 10.0, 10.0, 1.0, 1.0, 1.0),
        tool_gain: Sequence[float] = (10.0, 10.0),
        vehicle_gain: Sequence[float] = (10.0, 10.0, 100.0),
        frame: str = "tool",
        name: str | None = None,
    ) -> None:
        super().__init__(name=name)
        self.weights = as_vector(weights, "weights")
        if np.any(self.weights <= 0.0):
            raise InputError(f"weights: expected positive entries, got {self.weights.tolist()}")
        self.tool_gain = _nonneg_vector(tool_gain, "tool_gain", 2)
        self.vehicle_gain = _nonneg_vector(vehicle_gain, "vehicle_gain", 3)
        if not isinstance(frame, str):
            raise InputError(f"frame: expected a frame name, got {type(frame).__name__}")
        self.frame = frame
        self._eta_prev: FloatArray | None = None

    def _bind(self, model: Model) -> None:
        model.frame_id(self.frame)
        if self.weights.shape[0] != model.nv:
            raise InputError(
                f"{self.name}.weights: expected {model.nv} entries (one per zeta component "
                f"{', '.join(model.zeta_names)}), got {self.weights.shape[0]}"
            )

    def reset(self) -> None:
        """Forget the previous vehicle pose (the next step holds the pose it starts from)."""
        super().reset()
        self._eta_prev = None

    def _references(self, state: State, t: float) -> tuple[FloatArray, FloatArray, FloatArray,
                                                           FloatArray, float, float]:
        """Return ``J_p, x_p, J_s, x_s`` and the tool / vehicle error norms."""
        sample = self.trajectory.sample(t)
        Jp = state.jacobian(self.frame, rows="position")[: len(_PLANAR_ROWS)]
        e_p = np.asarray(sample.position[:2]) - state.position(self.frame)[:2]
        xp = closed_loop_reference(np.asarray(sample.velocity[:2]), e_p, self.tool_gain)
        eta = np.array(state.eta, dtype=np.float64)
        held = eta if self._eta_prev is None else self._eta_prev
        e_s = held - eta
        e_s[2] = _wrap(e_s[2])
        self._eta_prev = eta
        Js = state.vehicle_pose_jacobian()
        xs = closed_loop_reference(np.zeros(3), e_s, self.vehicle_gain)
        return Jp, xp, Js, xs, float(np.linalg.norm(e_p)), float(np.linalg.norm(e_s))

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        Jp, xp, Js, xs, ep, es = self._references(state, t)
        zeta = singularity_robust_task_priority(Jp, xp, Js, xs, self.weights)
        rho, _ = arm_manipulability(state, _PLANAR_ROWS, self.frame)
        self.info = {"manipulability": rho}
        return zeta, {"tool": (ep, "m"), "vehicle_hold": (es, "m, rad")}


class SoyluDexterous(SoyluTaskPriority):
    """Dexterous task priority with shaping function, Soylu et al. (2007), Eq. (21).

    Args:
        weights: Diagonal of W over zeta (paper: ``[10, 10, 10, 1, 1, 1]``).
        tool_gain: K_p [1/s] (paper: ``[10, 10]``).
        vehicle_gain: K_s [1/s] (paper: ``[10, 10, 100]``).
        gain: lambda, step on the manipulability gradient (paper: 10) [1/s per unit of rho/rad].
        rho_bar: Manipulability threshold of the shaping function (paper: 1.3) [m^2].
        frame: Tool frame.
        name: Label in results.
    """

    type_name = "soylu_dexterous"

    def __init__(
        self,
        *,
        weights: Sequence[float] = (10.0, 10.0, 10.0, 1.0, 1.0, 1.0),
        tool_gain: Sequence[float] = (10.0, 10.0),
        vehicle_gain: Sequence[float] = (10.0, 10.0, 100.0),
        gain: float = 10.0,
        rho_bar: float = 1.3,
        frame: str = "tool",
        name: str | None = None,
    ) -> None:
        super().__init__(
            weights=weights, tool_gain=tool_gain, vehicle_gain=vehicle_gain, frame=frame, name=name
        )
        self.gain = as_scalar(gain, "gain", positive=True)
        self.rho_bar = as_scalar(rho_bar, "rho_bar", positive=True)

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        Jp, xp, Js, xs, ep, es = self._references(state, t)
        rho, gradient = arm_manipulability(state, _PLANAR_ROWS, self.frame)
        # Eq. (20): rho_dot predicted with the task-priority (k = 0) rates.
        rho_rate = float(gradient @ singularity_robust_task_priority(Jp, xp, Js, xs, self.weights))
        zeta = dexterous_task_priority(
            Jp, xp, Js, xs, rho, gradient, self.rho_bar, self.gain, self.weights,
            rho_rate=rho_rate,
        )
        self.info = {
            "manipulability": rho,
            "k": float(shaping_function(rho, self.rho_bar)),
            "switch": sign_switch(rho_rate),
        }
        return zeta, {"tool": (ep, "m"), "vehicle_hold": (es, "m, rad")}


def _nonneg_vector(value: Any, name: str, size: int) -> FloatArray:
    vector = as_vector(value, name, size)
    if np.any(vector < 0.0):
        raise InputError(f"{name}: expected non-negative gains, got {vector.tolist()}")
    return vector
