"""Wang et al. (2017): pseudoinverse and fuzzy multitask gradient projection.

Two schemes for a UVMS whose task is the tool position (3 rows, world frame):

* :class:`WangPseudoinverse`, Wang et al. (2017), Eq. (6): ``zeta = J^+ xdot`` with the
  plain pseudoinverse (vehicle and arm treated alike). The closed-loop reference
  ``xdot = xdot_d + K_e e`` is used here too, so the cases differ only in the redundancy
  resolution.
* :class:`WangFuzzyGradientProjection`, Eq. (23)::

      zeta = J_w^+ (xdot_d + K_e e) + k_H (I - J_w^+ J) (alpha_1 grad delta / |grad delta|
                                                          - alpha_2 grad M / |grad M|)

  with ``w^{-1}`` the motion distribution matrix (Eq. 14, ``w_max``) whose arm block is scaled by
  the joint-limit weights of Eq. (17) (constants ``C_i``), ``delta`` the arm manipulability
  (Eq. 18-19), ``M`` the payload objective (Eq. 20-21), and ``beta``, ``alpha_1``, ``alpha_2``
  from the fuzzy system :func:`uvms_qp.analytic.fuzzy_weights` (this library's reconstruction; the
  paper does not print its rule base). The fuzzy inputs are ``delta / delta_0`` (``delta_0`` the
  manipulability at the first step after :meth:`~uvms_qp.schemes.scheme.Scheme.reset`) and
  ``F / F_max``. The gradient term is applied as printed: it is not scaled by ``w^{-1}``, so it
  can drive a joint past its limit (the joint-limit weights only act on the weighted inverse).
  Outside its limits a joint's weight is evaluated at the limit (weight ~ 0).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..analytic.fuzzy import fuzzy_weights
from ..analytic.gradient_projection import check_projector, multi_objective_gradient_projection
from ..analytic.inverses import pinv
from ..analytic.joint_limits import joint_limit_weights
from ..analytic.motion_distribution import motion_distribution
from ..analytic.task_priority import closed_loop_reference
from ..errors import InputError
from ._kinematics import arm_manipulability, payload_term
from .scheme import Scheme

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State

_SPATIAL_ROWS = (0, 1, 2)
#: Fraction of the joint range kept between an evaluated joint and its limit for Eq. (17).
_LIMIT_MARGIN = 1e-6


class WangPseudoinverse(Scheme):
    """Pseudoinverse redundancy resolution, Wang et al. (2017), Eq. (6).

    Args:
        gain: K_e per axis or scalar [1/s] (paper: 50).
        frame: Tool frame.
        name: Label in results.
    """

    type_name = "wang_pseudoinverse"
    vehicle_kinds = ("spatial", "planar", "fixed")

    def __init__(
        self, *, gain: float | Sequence[float] = 50.0, frame: str = "tool", name: str | None = None
    ) -> None:
        super().__init__(name=name)
        self.gain = _gain(gain)
        if not isinstance(frame, str):
            raise InputError(f"frame: expected a frame name, got {type(frame).__name__}")
        self.frame = frame

    def _bind(self, model: Model) -> None:
        model.frame_id(self.frame)

    def _reference(self, state: State, t: float) -> tuple[FloatArray, FloatArray, float]:
        sample = self.trajectory.sample(t)
        J = state.jacobian(self.frame, rows="position")
        e = np.asarray(sample.position, dtype=np.float64) - state.position(self.frame)
        xr = closed_loop_reference(np.asarray(sample.velocity, dtype=np.float64), e, self.gain)
        return J, xr, float(np.linalg.norm(e))

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        J, xr, err = self._reference(state, t)
        delta, _ = arm_manipulability(state, _SPATIAL_ROWS, self.frame)
        self.info = {"manipulability": delta}
        return pinv(J) @ xr, {"tool": (err, "m")}


class WangFuzzyGradientProjection(WangPseudoinverse):
    """Fuzzy multitask weighted gradient projection, Wang et al. (2017), Eq. (23).

    Args:
        gain: K_e [1/s] (paper: 50).
        gradient_gain: k_H (paper: 0.2) [rad/s per unit normalised gradient].
        w_max: Largest vehicle inverse weight of Eq. (14) (paper: 0.02).
        limit_constants: C_i of Eq. (15)-(17), one per joint (paper: [10, 6, 10, 10, 10]).
        force: Payload force F at the tool [N] (case 1: 0; case 3: 50 % of ``force_max``).
        force_max: Payload capacity F_max [N] (fuzzy input ``F / F_max``).
        projector: Null-space projector of the gradient term, ``"weighted"`` (``I - J_W^+ J``)
            or ``"euclidean"`` (``I - J^+ J``); the paper's ``I - J_w^+ J_w`` allows both
            readings (see :func:`uvms_qp.analytic.multi_objective_gradient_projection`).
        frame: Tool frame.
        name: Label in results.
    """

    type_name = "wang_fuzzy_gradient_projection"

    def __init__(
        self,
        *,
        gain: float | Sequence[float] = 50.0,
        gradient_gain: float = 0.2,
        w_max: float = 0.02,
        limit_constants: Sequence[float] = (10.0, 6.0, 10.0, 10.0, 10.0),
        force: float = 0.0,
        force_max: float = 100.0,
        projector: str = "weighted",
        frame: str = "tool",
        name: str | None = None,
    ) -> None:
        super().__init__(gain=gain, frame=frame, name=name)
        self.projector = check_projector(projector)
        self.gradient_gain = as_scalar(gradient_gain, "gradient_gain", nonnegative=True)
        self.w_max = as_scalar(w_max, "w_max", positive=True)
        if self.w_max > 1.0:
            raise InputError(f"w_max: expected 0 < w_max <= 1, got {self.w_max}")
        self.limit_constants = as_vector(limit_constants, "limit_constants")
        if np.any(self.limit_constants <= 0.0):
            raise InputError("limit_constants: expected positive constants C_i")
        self.force = as_scalar(force, "force", nonnegative=True)
        self.force_max = as_scalar(force_max, "force_max", positive=True)
        self._delta0: float | None = None

    def _bind(self, model: Model) -> None:
        super()._bind(model)
        if self.limit_constants.shape[0] != model.n_joints:
            raise InputError(
                f"{self.name}.limit_constants: expected {model.n_joints} entries (one per joint), "
                f"got {self.limit_constants.shape[0]}"
            )
        lower = np.asarray(model.joint_lower, dtype=np.float64)
        upper = np.asarray(model.joint_upper, dtype=np.float64)
        if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))):
            raise InputError(f"{self.name}: the joint-limit index needs finite joint limits")
        margin = _LIMIT_MARGIN * (upper - lower)
        self._lower, self._upper = lower, upper
        self._inner_lower, self._inner_upper = lower + margin, upper - margin

    def reset(self) -> None:
        """Forget the reference manipulability (taken again at the next step)."""
        super().reset()
        self._delta0 = None

    def set_payload(self, force: float) -> None:
        """Change the payload force F [N] at run time (e.g. an object picked up)."""
        self.force = as_scalar(force, "force", nonnegative=True)

    def _compute(self, state: State, t: float) -> tuple[FloatArray, dict[str, tuple[float, str]]]:
        model = state.model
        J, xr, err = self._reference(state, t)
        delta, grad_delta = arm_manipulability(state, _SPATIAL_ROWS, self.frame)
        if self._delta0 is None:
            self._delta0 = max(delta, 1e-12)
        weights = fuzzy_weights(delta / self._delta0, self.force / self.force_max)
        q = np.clip(state.joints, self._inner_lower, self._inner_upper)
        w_joint = joint_limit_weights(q, self._lower, self._upper, self.limit_constants)
        inverse_weights = motion_distribution(
            weights.beta, model.n_vehicle, model.n_joints, self.w_max, joint_weights=w_joint
        )
        moment, grad_moment = payload_term(state, self.force, self.frame)
        zeta = multi_objective_gradient_projection(
            J,
            xr,
            [grad_delta, grad_moment],
            [weights.alpha_1, -weights.alpha_2],
            self.gradient_gain,
            inverse_weights=inverse_weights,
            projector=self.projector,
        )
        self.info = {
            "manipulability": delta,
            "manipulability_ratio": delta / self._delta0,
            "beta": weights.beta,
            "alpha_1": weights.alpha_1,
            "alpha_2": weights.alpha_2,
            "payload_objective": moment,
        }
        return zeta, {"tool": (err, "m")}


class WangEuclideanProjection(WangFuzzyGradientProjection):
    """Eq. (23) read with the Euclidean projector ``I - J^+ J`` of Eq. (7)-(10).

    The same scheme as :class:`WangFuzzyGradientProjection` with ``projector="euclidean"`` by
    default, under its own name so that one comparison can show both readings of the paper's
    projector side by side.
    """

    type_name = "wang_fuzzy_gradient_projection_euclidean"

    def __init__(
        self,
        *,
        gain: float | Sequence[float] = 50.0,
        gradient_gain: float = 0.2,
        w_max: float = 0.02,
        limit_constants: Sequence[float] = (10.0, 6.0, 10.0, 10.0, 10.0),
        force: float = 0.0,
        force_max: float = 100.0,
        projector: str = "euclidean",
        frame: str = "tool",
        name: str | None = None,
    ) -> None:
        super().__init__(
            gain=gain, gradient_gain=gradient_gain, w_max=w_max, limit_constants=limit_constants,
            force=force, force_max=force_max, projector=projector, frame=frame, name=name,
        )


def _gain(value: Any) -> float | FloatArray:
    if isinstance(value, list | tuple | np.ndarray):
        gains = as_vector(value, "gain", 3)
        if np.any(gains < 0.0):
            raise InputError(f"gain: expected non-negative gains, got {gains.tolist()}")
        return gains
    return as_scalar(value, "gain", nonnegative=True)
