"""dos Santos et al. (2006): kinematic constraints by virtual chains.

Two schemes for a planar UVMS tracking a tool pose ``[x_E, y_E, psi_E]`` while the vehicle should
stay at rest with its heading turned toward the current:

* :class:`SantosKinematicConstraint`, built the paper's way (dos Santos et al. (2006),
  Eq. (5)-(8), (14)-(26)): screws of the vehicle's PPPS chain, of the arm joints and of a virtual
  PPPS chain closing the loop at the tool; the Davies circulation law ``N Psi = 0`` with the
  virtual (tool) and vehicle magnitudes imposed (primary, Eq. 25) gives the arm rates
  (secondary, Eq. 26). The vehicle magnitudes are imposed as ``x_dot = y_dot = 0`` and
  ``psi_dot = k_psi (psi_c - psi)``: the vehicle is exactly at rest and turns toward the current.
* :class:`SantosTaskPriority`, the singularity-robust task priority it is compared with, Eq. (28)::

      zeta = J_p^+ xdot_p + (I - J_p^+ J_p) J_s^+ xdot_s,    xdot_s = [0, 0, k_psi (psi_c - psi)]

  with plain pseudoinverses, ``J_p`` the tool's planar pose Jacobian and ``J_s`` the vehicle pose
  Jacobian: the secondary task is only met where it does not conflict, so the vehicle moves.

Both use the same heading law and the same tool reference ``xdot_p = xdot_d + K (x_d - x)``; the
paper's equations are open loop (``K = 0``, the default). The tool heading target is the
trajectory's orientation when it has one, otherwise the heading the tool had at the first step.
Planar screws keep the rows ``(omega_z, v_x, v_y)``; magnitudes of the vehicle and virtual chains
are world rates ``[x_dot, y_dot, psi_dot]``; zeta holds body rates ``[u, v, r]``, mapped by
``J_eta``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..analytic.davies import davies_direct, kinematic_constraint_inverse, planar_uvms_screws
from ..analytic.task_priority import singularity_robust_task_priority
from ..errors import InputError
from .scheme import Scheme

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

#: World twist rows (Pinocchio order [v; omega]) of the planar pose [x_dot, y_dot, psi_dot].
_PLANAR_TWIST_ROWS = (0, 1, 5)
#: Largest Jacobian mismatch [m/rad] accepted between the screw geometry and the model at bind.
_GEOMETRY_TOLERANCE = 1e-9


def _wrap(angle: float) -> float:
    return float((angle + np.pi) % (2.0 * np.pi) - np.pi)


class SantosTaskPriority(Scheme):
    """Singularity-robust task priority, dos Santos et al. (2006), Eq. (28).

    Args:
        heading: Current direction psi_c the vehicle aligns to [rad] (paper: 0.78).
        heading_gain: k_psi of the heading law ``r = k_psi (psi_c - psi)`` [1/s].
        gain: K of the tool reference [1/s] (paper: open loop, 0).
        frame: Tool frame.
        name: Label in results.
    """

    type_name = "santos_sr_task_priority"
    vehicle_kinds = ("planar",)

    def __init__(
        self,
        *,
        heading: float = 0.78,
        heading_gain: float = 0.5,
        gain: float = 0.0,
        frame: str = "tool",
        name: str | None = None,
    ) -> None:
        super().__init__(name=name)
        self.heading = as_scalar(heading, "heading")
        self.heading_gain = as_scalar(heading_gain, "heading_gain", nonnegative=True)
        self.gain = as_scalar(gain, "gain", nonnegative=True)
        if not isinstance(frame, str):
            raise InputError(f"frame: expected a frame name, got {type(frame).__name__}")
        self.frame = frame
        self._tool_heading: float | None = None

    def _bind(self, model: Model) -> None:
        model.frame_id(self.frame)

    def reset(self) -> None:
        """Forget the held tool heading (taken again at the next step)."""
        super().reset()
        self._tool_heading = None

    def tool_pose(self, state: State) -> FloatArray:
        """Planar tool pose ``[x_E, y_E, psi_E]`` [m, m, rad] (world frame)."""
        T = state.pose(self.frame)
        return np.array([T[0, 3], T[1, 3], np.arctan2(T[1, 0], T[0, 0])])

    def tool_reference(self, state: State, t: float) -> tuple[FloatArray, float]:
        """Tool rate reference ``[x_dot, y_dot, psi_dot]_d + K e`` and the position error [m]."""
        pose = self.tool_pose(state)
        if self._tool_heading is None:
            self._tool_heading = float(pose[2])
        sample = self.trajectory.sample(t)
        if sample.rotation is not None:
            target_heading = float(np.arctan2(sample.rotation[1, 0], sample.rotation[0, 0]))
        else:
            target_heading = self._tool_heading
        omega = 0.0 if sample.angular_velocity is None else float(sample.angular_velocity[2])
        error = np.array([
            sample.position[0] - pose[0],
            sample.position[1] - pose[1],
            _wrap(target_heading - pose[2]),
        ])
        feedforward = np.array([sample.velocity[0], sample.velocity[1], omega])
        return feedforward + self.gain * error, float(np.hypot(error[0], error[1]))

    def heading_rate(self, state: State) -> float:
        """Vehicle yaw rate of the heading law ``k_psi (psi_c - psi)`` [rad/s]."""
        return self.heading_gain * _wrap(self.heading - float(state.eta[2]))

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        xp, err = self.tool_reference(state, t)
        Jp = state.jacobian(self.frame)[list(_PLANAR_TWIST_ROWS)]
        Js = state.vehicle_pose_jacobian()
        xs = np.array([0.0, 0.0, self.heading_rate(state)])
        zeta = singularity_robust_task_priority(Jp, xp, Js, xs)
        self.info = {"heading_error": _wrap(self.heading - float(state.eta[2]))}
        return zeta, {"tool": (err, "m")}


class SantosKinematicConstraint(SantosTaskPriority):
    """Kinematic-constraint inverse by the Davies method, dos Santos et al. (2006), Eq. (19)-(26).

    Args:
        heading: Current direction psi_c [rad] (paper: 0.78).
        heading_gain: k_psi of the imposed yaw rate [1/s].
        gain: K of the tool reference [1/s] (paper: open loop, 0).
        link_lengths: Arm link lengths [m] (paper: three 2 m links); checked against the model.
        mount: Arm base in the vehicle frame (x, y) [m] (paper: 2.5 m ahead); checked too.
        frame: Tool frame.
        name: Label in results.
    """

    type_name = "santos_kinematic_constraint"

    def __init__(
        self,
        *,
        heading: float = 0.78,
        heading_gain: float = 0.5,
        gain: float = 0.0,
        link_lengths: Sequence[float] = (2.0, 2.0, 2.0),
        mount: Sequence[float] = (2.5, 0.0),
        frame: str = "tool",
        name: str | None = None,
    ) -> None:
        super().__init__(
            heading=heading, heading_gain=heading_gain, gain=gain, frame=frame, name=name
        )
        self.link_lengths = as_vector(link_lengths, "link_lengths")
        if np.any(self.link_lengths <= 0.0):
            raise InputError(f"link_lengths: expected positive lengths, got {self.link_lengths}")
        self.mount = as_vector(mount, "mount", 2)

    def _bind(self, model: Model) -> None:
        super()._bind(model)
        if model.n_joints != self.link_lengths.shape[0] or model.n_vehicle != 3:
            raise InputError(
                f"{self.name}: the planar Davies loop needs 3 vehicle rates and "
                f"{self.link_lengths.shape[0]} joints (link_lengths); model {model.name!r} has "
                f"{model.n_vehicle} and {model.n_joints}"
            )
        state = model.state(model.home())
        mismatch = float(np.abs(self.screw_jacobian(state) - self._model_jacobian(state)).max())
        if mismatch > _GEOMETRY_TOLERANCE:
            raise InputError(
                f"{self.name}: link_lengths/mount do not describe model {model.name!r} "
                f"(screw and model Jacobians differ by {mismatch:.3g})"
            )

    def screws(self, state: State) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Planar screws ``(vehicle, arm, virtual)`` of the closed loop at ``state`` (Eq. 19)."""
        return planar_uvms_screws(state.eta, state.joints, self.link_lengths, self.mount)

    def screw_jacobian(self, state: State) -> FloatArray:
        """Tool planar twist Jacobian over zeta from the screws (Davies direct, Eq. 21-22).

        Column k is the virtual-chain magnitude ``[x_E_dot, y_E_dot, psi_E_dot]`` produced by a
        unit vehicle world rate or joint rate, mapped to body rates by ``J_eta``; it should equal
        the model's Jacobian rows ``(v_x, v_y, omega_z)``.
        """
        vehicle, arm, virtual = self.screws(state)
        nv, na = vehicle.shape[1], arm.shape[1]
        columns = []
        for k in range(nv + na):
            unit = np.zeros(nv + na)
            unit[k] = 1.0
            columns.append(davies_direct(vehicle, arm, virtual, unit[:nv], unit[nv:]))
        J_world = np.array(columns).T  # over [x_dot, y_dot, psi_dot, q_dot]
        J_eta = state.vehicle_pose_jacobian()
        return np.hstack([J_world[:, :nv] @ J_eta[:, :nv], J_world[:, nv:]])

    def _model_jacobian(self, state: State) -> FloatArray:
        return np.asarray(state.jacobian(self.frame)[list(_PLANAR_TWIST_ROWS)])

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        xp, err = self.tool_reference(state, t)
        r = self.heading_rate(state)
        vehicle, arm, virtual = self.screws(state)
        arm_rates = kinematic_constraint_inverse(vehicle, arm, virtual, xp, [0.0, 0.0, r])
        zeta = np.concatenate([[0.0, 0.0, r], arm_rates])
        self.info = {"heading_error": _wrap(self.heading - float(state.eta[2]))}
        return zeta, {"tool": (err, "m")}
