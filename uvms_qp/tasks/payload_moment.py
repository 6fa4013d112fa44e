"""Payload moment (Wang et al., 2017): reduce, or bound, the moment a payload exerts via the arm.

One class per kind of rows: reduce, bound.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ._checks import check_barrier_gain, check_flag, check_frame_name
from ._common import check_choice, check_frame
from .slot import TaskSlot
from .task import Task

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class PayloadMomentTask(Task):
    r"""Keep the payload moment ``M(q) = (x_E^2 + y_E^2) F`` small.

    Wang et al. (2017), Eq. (20): ``(x_E, y_E)`` is the position of ``frame`` in the
    arm-base frame [m], ``F`` the (vertical) payload force [N]; ``M`` is in [N m^2] as in the
    paper (the squared lever arm times the force; it grows with the moment the payload exerts
    on the vehicle). Gradient (Eq. (21)):
    ``dM/dq_i = 2 F (x_E dx_E/dq_i + y_E dy_E/dq_i)`` [N m^2/rad], with the position rows of the
    arm Jacobian in arm-base axes. ``PayloadMomentTask(mode=...)`` builds the class of the mode
    (the scenario key ``mode``): ``"reduce"`` (:class:`PayloadMomentReduceTask`, the default)
    or ``"bound"`` (:class:`PayloadMomentBoundTask`).

    ``F`` changes at run time with ``update(force=...)`` (a payload picked up mid-run).

    Args:
        mode: ``"reduce"`` or ``"bound"`` (selects the class).
        force: Payload force ``F`` [N] (>= 0; 0 means no payload).
        frame: Frame carrying the payload (default ``"tool"``).
        gain: ``lambda`` [rad/s per N m^2] (reduce) or the barrier gain [1/s] (bound).
        weight: Weight within the level.
        name: Task name (default ``"payload_moment"``).
    """

    type_name = "payload_moment"
    error_unit = "N m^2"
    rate_unit = "rad/s"
    mode: ClassVar[str] = ""

    def __new__(cls, *args: Any, mode: str | None = None, **kwargs: Any) -> Any:
        """The class of ``mode`` when built as ``PayloadMomentTask(mode=...)``."""
        if cls is PayloadMomentTask:
            cls = cls.for_mode(mode, kwargs.get("name"))
        return super().__new__(cls, *args, mode=mode, **kwargs)

    @classmethod
    def for_mode(cls, mode: str | None, name: str | None = None) -> type[PayloadMomentTask]:
        """The class of ``mode`` (None: ``"reduce"``).

        Raises:
            InputError: an unknown mode (the known ones are listed).
        """
        label = f"{name or cls.type_name}.mode"
        return MODES[check_choice("reduce" if mode is None else mode, tuple(MODES), label)]

    def __init__(self, *, mode: str | None = None, force: float = 0.0, frame: str = "tool",
                 gain: float = 1.0, weight: float = 1.0, name: str | None = None) -> None:
        super().__init__(name=name, weight=weight)
        if mode is not None:
            check_choice(mode, (self.mode,), f"{self.name}.mode")
        self.frame = check_frame_name(frame, f"{self.name}.frame")
        self.force = self._check("force", force)
        self.gain = self._check("gain", gain)

    def _bind(self, model: Model) -> int:
        check_frame(model, self.frame, f"{self.name}.frame")
        if model.n_joints == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        return model.n_joints

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

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "force", "gain")

    def _check(self, key: str, value: Any) -> Any:
        if key == "force":
            return as_scalar(value, f"{self.name}.force", nonnegative=True)
        if key == "gain":
            return as_scalar(value, f"{self.name}.gain", positive=True)
        return super()._check(key, value)


class PayloadMomentReduceTask(PayloadMomentTask):
    r"""Rows ``qdot = -lambda grad M`` over the arm joint rates [rad/s].

    Gradient projection, Wang et al. (2017), Eq. (22)-(23) with the minus sign of the attitude
    objective; ``normalize=True`` divides by ``|grad M|`` as in Eq. (11). With ``F = 0`` the
    rows ask for no arm motion.

    Args:
        normalize: Normalise the gradient.
        mode, force, frame, gain, weight, name: See :class:`PayloadMomentTask`.
    """

    mode = "reduce"

    def __init__(self, *, mode: str | None = None, force: float = 0.0, frame: str = "tool",
                 gain: float = 1.0, normalize: bool = False, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(mode=mode, force=force, frame=frame, gain=gain, weight=weight,
                         name=name)
        self.normalize = check_flag(normalize, f"{self.name}.normalize")
        self._select = np.zeros((0, 0))

    def _bind(self, model: Model) -> int:
        n = super()._bind(model)
        self._select = np.zeros((n, model.nv))  # rows qdot = ... over the joint rates
        self._select[np.arange(n), model.n_vehicle + np.arange(n)] = 1.0
        self._select.setflags(write=False)
        return n

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The rows ``qdot = -lambda grad M`` (normalised if asked)."""
        M, g = self._moment(state)
        slot.error = (M,)
        scale = -self.gain
        if self.normalize:
            norm = math.sqrt(sum(v * v for v in g))
            scale = scale / norm if norm > 1e-12 else 0.0
        sides = [scale * v for v in g]
        return self._select, sides, sides


class PayloadMomentBoundTask(PayloadMomentTask):
    r"""One inequality ``grad M . qdot <= gain (maximum - M)`` [N m^2/s].

    The first-order barrier keeping ``M <= maximum``.

    Args:
        maximum: Bound on ``M`` [N m^2] (required).
        gain: The barrier gain [1/s] (``gain * dt <= 1``).
        mode, force, frame, weight, name: See :class:`PayloadMomentTask`.
    """

    mode = "bound"
    rate_unit = "N m^2/s"

    def __init__(self, *, mode: str | None = None, force: float = 0.0, frame: str = "tool",
                 gain: float = 1.0, maximum: float | None = None, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(mode=mode, force=force, frame=frame, gain=gain, weight=weight,
                         name=name)
        if maximum is None:
            raise InputError(f"{self.name}.maximum: required in mode 'bound'")
        self.maximum = self._check("maximum", maximum)
        self._zeros: list[float] = []  # vehicle columns of the row

    @property
    def equality_rows(self) -> bool:
        """False: an inequality row."""
        return False

    def check_period(self, dt: float) -> None:
        """Refuse ``gain * dt > 1`` (see :func:`~uvms_qp.tasks._checks.check_barrier_gain`)."""
        check_barrier_gain(self.gain, dt, f"{self.name}.gain", "bound row")

    def _bind(self, model: Model) -> int:
        super()._bind(model)
        self._zeros = [0.0] * model.n_vehicle
        return 1

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The bound row."""
        M, g = self._moment(state)
        slot.error = (M,)
        return np.array([self._zeros + g]), -np.inf, self.gain * (self.maximum - M)

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "maximum")

    def _check(self, key: str, value: Any) -> Any:
        if key == "maximum":
            return as_scalar(value, f"{self.name}.maximum", nonnegative=True)
        return super()._check(key, value)


#: The class of each ``mode`` of :class:`PayloadMomentTask`.
MODES: dict[str, type[PayloadMomentTask]] = {
    cls.mode: cls for cls in (PayloadMomentReduceTask, PayloadMomentBoundTask)}
