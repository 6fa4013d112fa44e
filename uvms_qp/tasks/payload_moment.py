"""Payload moment (Wang et al., 2017): reduce, or bound, the moment a payload exerts via the arm."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ._common import check_choice, check_frame
from .task import Task, check_barrier_gain

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class PayloadMomentTask(Task):
    r"""Keep the payload moment ``M(q) = (x_E^2 + y_E^2) F`` small.

    Wang et al. (2017), Eq. (20): ``(x_E, y_E)`` is the position of ``frame`` in the
    arm-base frame [m], ``F`` the (vertical) payload force [N]; ``M`` is in [N m^2] as in the
    paper (the squared lever arm times the force; it grows with the moment the payload exerts
    on the vehicle). Gradient (Eq. (21)):
    ``dM/dq_i = 2 F (x_E dx_E/dq_i + y_E dy_E/dq_i)`` [N m^2/rad], with the position rows of the
    arm Jacobian in arm-base axes. Modes:

    * ``"reduce"``: rows ``qdot = -lambda grad M`` over the arm joint rates (gradient projection,
      Eq. (22)-(23) with the minus sign of the attitude objective; ``normalize=True`` divides by
      ``|grad M|`` as in Eq. (11)). With ``F = 0`` the rows ask for no arm motion.
    * ``"bound"``: one inequality ``grad M . qdot <= gain (maximum - M)`` [N m^2/s], the
      first-order barrier keeping ``M <= maximum``.

    ``F`` changes at run time with ``update(force=...)`` (a payload picked up mid-run).

    Args:
        mode: ``"reduce"`` or ``"bound"``.
        force: Payload force ``F`` [N] (>= 0; 0 means no payload).
        frame: Frame carrying the payload (default ``"tool"``).
        gain: ``lambda`` [rad/s per N m^2] (reduce) or the barrier gain [1/s] (bound).
        maximum: Bound on ``M`` [N m^2] (mode ``"bound"``).
        normalize: Normalise the gradient (mode ``"reduce"``).
        weight: Weight within the level.
        name: Task name (default ``"payload_moment"``).
        activation: Initial activation in [0, 1] (1: in the stack; see
            :class:`~uvms_qp.tasks.Task`).
    """

    type_name = "payload_moment"
    error_unit = "N m^2"
    rate_unit = "rad/s | N m^2/s"

    def __init__(
        self,
        *,
        mode: Literal["reduce", "bound"] = "reduce",
        force: float = 0.0,
        frame: str = "tool",
        gain: float = 1.0,
        maximum: float | None = None,
        normalize: bool = False,
        weight: float = 1.0,
        name: str | None = None,
        activation: float = 1.0,
    ) -> None:
        super().__init__(name=name, weight=weight, activation=activation)
        check_choice(mode, ("reduce", "bound"), f"{self.name}.mode")
        if not isinstance(frame, str) or not frame:
            raise InputError(f"{self.name}.frame: expected a frame name, got {frame!r}")
        if not isinstance(normalize, bool):
            raise InputError(f"{self.name}.normalize: expected true or false")
        self.mode = mode
        self.frame = frame
        self.force = as_scalar(force, f"{self.name}.force", nonnegative=True)
        self.gain = as_scalar(gain, f"{self.name}.gain", positive=True)
        self.maximum = None if maximum is None else as_scalar(maximum, f"{self.name}.maximum",
                                                              nonnegative=True)
        if mode == "bound" and self.maximum is None:
            raise InputError(f"{self.name}.maximum: required in mode 'bound'")
        self.normalize = normalize
        self._zeros: list[float] = []  # vehicle columns of the bound row
        self._select = np.zeros((0, 0))
        self.value = float("nan")

    @property
    def equality_rows(self) -> bool:
        """False in mode ``'bound'`` (an inequality), True otherwise."""
        return self.mode != "bound"

    def check_period(self, dt: float) -> None:
        """In mode ``"bound"``, refuse ``gain * dt > 1`` (see :func:`.check_barrier_gain`)."""
        if self.mode == "bound":
            check_barrier_gain(self.gain, dt, f"{self.name}.gain", "bound row")

    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        if model.n_joints == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        self._zeros = [0.0] * model.n_vehicle
        self.rate_unit = "N m^2/s" if self.mode == "bound" else "rad/s"
        n = model.n_joints
        self._select = np.zeros((n, model.nv))  # rows of the reduce mode: qdot = ...
        self._select[np.arange(n), model.n_vehicle + np.arange(n)] = 1.0
        self._select.setflags(write=False)
        return 1 if self.mode == "bound" else n

    def compute_value(self, state: State) -> tuple[float, FloatArray]:
        """``(M, grad M)`` at ``state`` [N m^2, N m^2/rad] (gradient over the arm joints)."""
        M, grad = self._moment(state)
        return M, np.array(grad)

    def _moment(self, state: State) -> tuple[float, list[float]]:
        """``M`` and ``grad M`` (plain floats, one value per joint).

        ``(x_E, y_E)`` is the frame's origin in arm-base coordinates; the gradient combines the
        first two rows of the arm Jacobian in arm-base axes.
        """
        x, y, _ = state.arm_position(self.frame).tolist()
        F = self.force
        a, b = 2.0 * F * x, 2.0 * F * y
        rx, ry = state.arm_jacobian(self.frame)[:2].tolist()
        grad = []
        for u, v in zip(rx, ry, strict=True):
            grad.append(a * u + b * v)
        return (x * x + y * y) * F, grad

    def evaluate(self, state: State, t: float) -> tuple[FloatArray, Any, Any]:
        """The reduce rows or the bound row (see the class docstring)."""
        M, g = self._moment(state)
        self.value = M
        self._error = (M,)
        if self.mode == "bound":
            return np.array([self._zeros + g]), -np.inf, self.gain * (self.maximum - M)  # type: ignore[operator]
        scale = -self.gain
        if self.normalize:
            norm = math.sqrt(sum(v * v for v in g))
            scale = scale / norm if norm > 1e-12 else 0.0
        sides = [scale * v for v in g]
        return self._select, sides, sides

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "force", "gain", "maximum")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "force":
            self.force = as_scalar(value, f"{self.name}.force", nonnegative=True)
        elif key == "gain":
            self.gain = as_scalar(value, f"{self.name}.gain", positive=True)
        elif key == "maximum":
            self.maximum = as_scalar(value, f"{self.name}.maximum", nonnegative=True)
        else:
            super()._apply_update(key, value)
