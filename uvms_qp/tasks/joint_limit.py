"""Joint limits: Wang et al.'s (2017) index as an objective, a weight, or a margin inequality.

One class per kind of rows: gradient, damping, margin.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..analytic.joint_limits import LIMIT_CLEARANCE, index_and_gradient, limit_table
from ..errors import InputError
from ..model.selection import check_joint_list, compact_index, joint_indices
from ._checks import check_barrier_gain, check_flag
from ._common import check_choice
from .slot import TaskSlot
from .task import Task

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class JointLimitTask(Task):
    r"""Keep arm joints away from their limits (the common part of the three kinds of rows).

    ``JointLimitTask(mode=...)`` builds the class of the mode (the scenario key ``mode``):

    * ``"gradient"`` (:class:`JointLimitGradientTask`): rows ``qdot_S = -lambda grad H``;
    * ``"damping"`` (:class:`JointLimitDampingTask`): rows ``qdot_S = 0`` weighted by the
      closeness to the limits;
    * ``"margin"`` (:class:`JointLimitMarginTask`, the default): inequality rows keeping the
      joints a margin inside their limits.

    ``H`` is the index of Wang et al. (2017), Eq. (15)-(16) (see
    :func:`~uvms_qp.analytic.joint_limit_index`), with per-joint strengths ``C_i``; joints
    without finite limits are skipped.

    Args:
        mode: ``"gradient"``, ``"margin"`` or ``"damping"`` (selects the class).
        joints: Joint names (default: all arm joints with finite limits).
        strength: ``C_i`` of Eq. (15), a number or one per selected joint (default 1).
        weight: Weight within the level.
        name: Task name (default ``"joint_limit"``).
    """

    type_name = "joint_limit"
    error_unit = "1"
    rate_unit = "rad/s"
    mode: ClassVar[str] = ""

    def __new__(cls, *args: Any, mode: str | None = None, **kwargs: Any) -> Any:
        """The class of ``mode`` when built as ``JointLimitTask(mode=...)``."""
        if cls is JointLimitTask:
            cls = cls.for_mode(mode, kwargs.get("name"))
        return super().__new__(cls, *args, mode=mode, **kwargs)

    @classmethod
    def for_mode(cls, mode: str | None, name: str | None = None) -> type[JointLimitTask]:
        """The class of ``mode`` (None: ``"margin"``).

        Raises:
            InputError: an unknown mode (the known ones are listed).
        """
        label = f"{name or cls.type_name}.mode"
        return MODES[check_choice("margin" if mode is None else mode, tuple(MODES), label)]

    def __init__(self, *, mode: str | None = None, joints: list[str] | None = None,
                 strength: float | list[float] = 1.0, weight: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(name=name, weight=weight)
        if mode is not None:
            check_choice(mode, (self.mode,), f"{self.name}.mode")
        self.joints = check_joint_list(joints, f"{self.name}.joints")
        if isinstance(strength, list | tuple | np.ndarray):
            self._strength: float | FloatArray = as_vector(strength, f"{self.name}.strength")
            if np.any(self._strength <= 0.0):
                raise InputError(f"{self.name}.strength: expected positive values")
        else:
            self._strength = as_scalar(strength, f"{self.name}.strength", positive=True)
        self._idx = np.zeros(0, dtype=int)
        self._jsel: Any = self._idx
        self._lo = self._hi = np.zeros(0)
        self._A = np.zeros((0, 0))
        self._table: list[tuple[float, float, float, float, float]] = []

    def _bind(self, model: Model) -> int:
        idx = joint_indices(model, self.joints, f"{self.name}.joints")
        lo = np.asarray(model.joint_lower, dtype=float)[idx]
        hi = np.asarray(model.joint_upper, dtype=float)[idx]
        finite = np.isfinite(lo) & np.isfinite(hi)
        if self.joints is not None and not finite.all():
            bad = [self.joints[i] for i in np.flatnonzero(~finite)]
            raise InputError(f"{self.name}.joints: {bad} have no finite limits")
        if isinstance(self._strength, np.ndarray):
            if self._strength.shape[0] != idx.size:
                raise InputError(f"{self.name}.strength: expected {idx.size} values, got "
                                 f"{self._strength.shape[0]}")
            C = self._strength[finite]
        else:
            C = np.full(int(finite.sum()), self._strength)
        idx, lo, hi = idx[finite], lo[finite], hi[finite]
        if idx.size == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no joint with finite limits")
        self._check_room(model, idx, lo, hi)
        self._idx, self._lo, self._hi = idx, lo, hi
        self._jsel = None if idx.tolist() == list(range(model.n_joints)) else compact_index(idx)
        self._table = limit_table(lo, hi, C, LIMIT_CLEARANCE)
        self._A = np.zeros((idx.size, model.nv))
        self._A[np.arange(idx.size), model.n_vehicle + idx] = 1.0
        self._A.setflags(write=False)
        return int(idx.size)

    def _check_room(self, model: Model, idx: Any, lo: FloatArray, hi: FloatArray) -> None:
        """Check the limits leave room for the task (the margin task's margin)."""

    @property
    def joint_indices(self) -> np.ndarray:
        """Indices (into the arm joints) of the regulated joints."""
        return self._idx

    def _joints(self, state: State) -> list[float]:
        """The regulated joint angles [rad] as plain floats."""
        return (state.joints if self._jsel is None else state.joints[self._jsel]).tolist()

    def compute_value(self, state: State) -> tuple[float, FloatArray]:
        """``(H, grad H)`` on the regulated joints at ``state`` (Eq. (15)-(16), saturated).

        Distances to a limit closer than 1 % of the joint's range count as 1 % (see
        :mod:`uvms_qp.analytic.joint_limits`).
        """
        H, grad = index_and_gradient(self._joints(state), self._table)
        return H, np.array(grad)


class JointLimitGradientTask(JointLimitTask):
    r"""Rows ``qdot_S = -lambda grad H`` [rad/s], one per joint with finite limits.

    The gradient-projection use of the index ``H`` of Wang et al. (2017), Eq. (15)-(16); with
    ``normalize=True`` the gradient is divided by its norm (Eq. (11)). For joints at (or beyond)
    a limit, or closer to it than 1 % of their range, the distance to that limit counts as 1 %
    of the range, so the rows stay finite and bounded
    (``|row_i| <= gain / (C_i 1e-4 (q_max,i - q_min,i))``) and keep the direction of the exact
    gradient: they push the joint back toward mid-range. Objective value: ``H`` [1].

    Args:
        gain: ``lambda`` [rad^2/s].
        normalize: Normalise the gradient.
        mode, joints, strength, weight, name: See :class:`JointLimitTask`.
    """

    mode = "gradient"

    def __init__(self, *, mode: str | None = None, joints: list[str] | None = None,
                 gain: float = 1.0, strength: float | list[float] = 1.0,
                 normalize: bool = False, weight: float = 1.0, name: str | None = None) -> None:
        super().__init__(mode=mode, joints=joints, strength=strength, weight=weight, name=name)
        self.gain = self._check("gain", gain)
        self.normalize = check_flag(normalize, f"{self.name}.normalize")

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The gradient rows (per joint in plain floats)."""
        H, g = index_and_gradient(self._joints(state), self._table)
        slot.error = (H,)
        scale = -self.gain
        if self.normalize:
            norm = math.sqrt(sum(x * x for x in g))
            scale = scale / norm if norm > 1e-12 else 0.0
        sides = [scale * x for x in g]
        return self._A, sides, sides

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain")

    def _check(self, key: str, value: Any) -> Any:
        if key == "gain":
            return as_scalar(value, f"{self.name}.gain", positive=True)
        return super()._check(key, value)


class JointLimitDampingTask(JointLimitTask):
    r"""Rows ``qdot_S = 0`` weighted ``weight (1 + |dH/dq_i|)`` [rad/s].

    The inverse of Wang et al. (2017), Eq. (17)'s ``w_i = 1 / (1 + |dH/dq_i|)``: in its level,
    joints close to a limit become expensive to move (Eq. (17) as a task; the weights follow
    the state, in the slot's ``row_weights``). Objective value: ``H`` [1].
    """

    mode = "damping"
    weights_per_tick = True

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """Zero rows; the weights of this state into ``slot.row_weights`` (a new array)."""
        H, g = index_and_gradient(self._joints(state), self._table)
        slot.error = (H,)
        slot.row_weights = np.array([self.weight * (1.0 + abs(x)) for x in g])
        return self._A, 0.0, 0.0


class JointLimitMarginTask(JointLimitTask):
    r"""Inequality rows ``gain (q_min + margin - q) <= qdot <= gain (q_max - margin - q)``.

    The joints are steered to stay ``margin`` [rad] inside their limits (a soft, prioritised
    version of the hard :class:`~uvms_qp.constraints.JointPositionBounds`). Error: the distance
    of the nearest joint to its nearest limit [rad].

    Args:
        gain: The margin gain [1/s] (``gain * dt <= 1``).
        margin: Distance kept inside the limits [rad].
        mode, joints, strength, weight, name: See :class:`JointLimitTask`.
    """

    mode = "margin"
    error_unit = "rad"

    def __init__(self, *, mode: str | None = None, joints: list[str] | None = None,
                 gain: float = 1.0, margin: float = 0.1, strength: float | list[float] = 1.0,
                 weight: float = 1.0, name: str | None = None) -> None:
        super().__init__(mode=mode, joints=joints, strength=strength, weight=weight, name=name)
        self.gain = self._check("gain", gain)
        self.margin = self._check("margin", margin)
        self._band: list[tuple[float, float, float, float]] = []

    @property
    def equality_rows(self) -> bool:
        """False: inequality rows."""
        return False

    def check_period(self, dt: float) -> None:
        """Refuse ``gain * dt > 1`` (see :func:`~uvms_qp.tasks._checks.check_barrier_gain`)."""
        check_barrier_gain(self.gain, dt, f"{self.name}.gain", "margin rows")

    def _check_room(self, model: Model, idx: Any, lo: FloatArray, hi: FloatArray) -> None:
        if np.any(hi - lo <= 2.0 * self.margin):
            j = int(np.flatnonzero(hi - lo <= 2.0 * self.margin)[0])
            raise InputError(f"{self.name}.margin: {self.margin} rad leaves no room inside the "
                             f"limits of joint {model.joint_names[idx[j]]!r}")

    def _derive(self) -> None:
        """The band ``[q_min + margin, q_max - margin]`` and the limits, per joint [rad]."""
        super()._derive()
        self._band = list(zip((self._lo + self.margin).tolist(),
                              (self._hi - self.margin).tolist(),
                              self._lo.tolist(), self._hi.tolist(), strict=True))

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, Any, Any]:
        """The margin band (per joint in plain floats; constants prepared at bind)."""
        k = self.gain
        lower = []
        upper = []
        distance = math.inf  # to the nearest limit [rad]
        for (a, b, lo, hi), x in zip(self._band, self._joints(state), strict=True):
            lower.append((a - x) * k)
            upper.append((b - x) * k)
            d = x - lo if x - lo < hi - x else hi - x
            if d < distance:
                distance = d
        slot.error = (distance,)
        return self._A, lower, upper

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain", "margin")

    def _check(self, key: str, value: Any) -> Any:
        if key == "gain":
            return as_scalar(value, f"{self.name}.gain", positive=True)
        if key == "margin":
            margin = as_scalar(value, f"{self.name}.margin", nonnegative=True)
            if self.model is not None and np.any(self._hi - self._lo <= 2.0 * margin):
                raise InputError(f"{self.name}.margin: {margin} rad leaves no room inside the "
                                 "limits")
            return margin
        return super()._check(key, value)


#: The class of each ``mode`` of :class:`JointLimitTask`.
MODES: dict[str, type[JointLimitTask]] = {
    cls.mode: cls for cls in (JointLimitGradientTask, JointLimitMarginTask, JointLimitDampingTask)}
