"""Joint-limit task: Wang et al.'s (2017) index as a gradient objective, or a margin inequality."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..analytic.joint_limits import LIMIT_CLEARANCE, index_and_gradient, limit_table
from ..errors import InputError
from ..model.selection import check_joint_list, compact_index, joint_indices
from ._common import check_choice
from .task import Task, check_barrier_gain

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class JointLimitTask(Task):
    r"""Keep arm joints away from their limits.

    Modes:

    * ``"gradient"``: rows ``qdot_S = -lambda grad H`` (one per joint with finite limits,
      [rad/s]), the gradient-projection use of the index ``H`` of
      Wang et al. (2017), Eq. (15)-(16) (see
      :func:`~uvms_qp.analytic.joint_limit_index`); with
      ``normalize=True`` the gradient is divided by its norm (Eq. (11)). For joints at (or
      beyond) a limit, or closer to it than 1 % of their range, the distance to that limit
      counts as 1 % of the range, so the rows stay finite and bounded
      (``|row_i| <= gain / (C_i 1e-4 (q_max,i - q_min,i))``) and keep the direction of the
      exact gradient: they push the joint back toward mid-range.
    * ``"damping"``: rows ``qdot_S = 0`` whose per-row weights are
      ``weight (1 + |dH/dq_i|)``, the inverse of Eq. (17)'s ``w_i = 1 / (1 + |dH/dq_i|)``: in
      its level, joints close to a limit become expensive to move (Eq. (17) as a task; the
      weights are recomputed every tick).
    * ``"margin"``: inequality rows
      ``gain (q_min + margin - q) <= qdot <= gain (q_max - margin - q)`` [rad/s]: the joints are
      steered to stay ``margin`` [rad] inside their limits (a soft, prioritised version of the
      hard :class:`~uvms_qp.constraints.JointPositionBounds`).

    Joints without finite limits are skipped.

    Args:
        mode: ``"gradient"``, ``"margin"`` or ``"damping"``.
        joints: Joint names (default: all arm joints with finite limits).
        gain: ``lambda`` [rad^2/s] (gradient) or the margin gain [1/s].
        strength: ``C_i`` of Eq. (15), a number or one per selected joint (default 1).
        margin: Distance kept inside the limits [rad] (mode ``"margin"``).
        normalize: Normalise the gradient (mode ``"gradient"``).
        weight: Weight within the level.
        name: Task name (default ``"joint_limit"``).
        activation: Initial activation in [0, 1] (1: in the stack; see
            :class:`~uvms_qp.tasks.Task`).
    """

    type_name = "joint_limit"
    error_unit = "1 | rad"
    rate_unit = "rad/s"

    def __init__(
        self,
        *,
        mode: Literal["gradient", "margin", "damping"] = "margin",
        joints: list[str] | None = None,
        gain: float = 1.0,
        strength: float | list[float] = 1.0,
        margin: float = 0.1,
        normalize: bool = False,
        weight: float = 1.0,
        name: str | None = None,
        activation: float = 1.0,
    ) -> None:
        super().__init__(name=name, weight=weight, activation=activation)
        check_choice(mode, ("gradient", "margin", "damping"), f"{self.name}.mode")
        if not isinstance(normalize, bool):
            raise InputError(f"{self.name}.normalize: expected true or false")
        self.mode = mode
        self.joints = check_joint_list(joints, f"{self.name}.joints")
        self.gain = as_scalar(gain, f"{self.name}.gain", positive=True)
        self.margin = as_scalar(margin, f"{self.name}.margin", nonnegative=True)
        self.normalize = normalize
        if isinstance(strength, list | tuple | np.ndarray):
            self._strength_arg: float | FloatArray = as_vector(strength, f"{self.name}.strength")
            if np.any(self._strength_arg <= 0.0):
                raise InputError(f"{self.name}.strength: expected positive values")
        else:
            self._strength_arg = as_scalar(strength, f"{self.name}.strength", positive=True)
        self._idx = np.zeros(0, dtype=int)
        self._jsel: Any = self._idx
        self._lo = self._hi = self._C = np.zeros(0)
        self._A = np.zeros((0, 0))
        self._lo_list: list[float] = []
        self._hi_list: list[float] = []
        self._lo_m_list: list[float] = []
        self._hi_m_list: list[float] = []
        self._table: list[tuple[float, float, float, float, float]] = []
        self.value = float("nan")

    @property
    def equality_rows(self) -> bool:
        """False in mode ``'margin'`` (an inequality), True otherwise."""
        return self.mode != "margin"

    def check_period(self, dt: float) -> None:
        """In mode ``"margin"``, refuse ``gain * dt > 1`` (see :func:`.check_barrier_gain`)."""
        if self.mode == "margin":
            check_barrier_gain(self.gain, dt, f"{self.name}.gain", "margin rows")

    def _bind(self, model: Model) -> int:
        idx = joint_indices(model, self.joints, f"{self.name}.joints")
        lo = np.asarray(model.joint_lower, dtype=float)[idx]
        hi = np.asarray(model.joint_upper, dtype=float)[idx]
        finite = np.isfinite(lo) & np.isfinite(hi)
        if self.joints is not None and not finite.all():
            bad = [self.joints[i] for i in np.flatnonzero(~finite)]
            raise InputError(f"{self.name}.joints: {bad} have no finite limits")
        if isinstance(self._strength_arg, np.ndarray):
            if self._strength_arg.shape[0] != idx.size:
                raise InputError(f"{self.name}.strength: expected {idx.size} values, got "
                                 f"{self._strength_arg.shape[0]}")
            C = self._strength_arg[finite]
        else:
            C = np.full(int(finite.sum()), self._strength_arg)
        idx, lo, hi = idx[finite], lo[finite], hi[finite]
        if idx.size == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no joint with finite limits")
        if self.mode == "margin" and np.any(hi - lo <= 2.0 * self.margin):
            j = int(np.flatnonzero(hi - lo <= 2.0 * self.margin)[0])
            raise InputError(f"{self.name}.margin: {self.margin} rad leaves no room inside the "
                             f"limits of joint {model.joint_names[idx[j]]!r}")
        self._idx, self._lo, self._hi, self._C = idx, lo, hi, C
        self._jsel = None if idx.tolist() == list(range(model.n_joints)) else compact_index(idx)
        self.error_unit = "rad" if self.mode == "margin" else "1"  # distance or index H
        self._table = limit_table(lo, hi, C, LIMIT_CLEARANCE)
        self._lo_list, self._hi_list = lo.tolist(), hi.tolist()
        self._set_band()
        self._A = np.zeros((idx.size, model.nv))
        self._A[np.arange(idx.size), model.n_vehicle + idx] = 1.0
        self._A.setflags(write=False)
        return int(idx.size)

    def _set_band(self) -> None:
        """The margin band ``[q_min + margin, q_max - margin]`` [rad] (mode ``'margin'``)."""
        self._lo_m_list = (self._lo + self.margin).tolist()
        self._hi_m_list = (self._hi - self.margin).tolist()

    @property
    def joint_indices(self) -> np.ndarray:
        """Indices (into the arm joints) of the regulated joints."""
        return self._idx

    def compute_value(self, state: State) -> tuple[float, FloatArray]:
        """``(H, grad H)`` on the regulated joints at ``state`` (Eq. (15)-(16), saturated).

        Distances to a limit closer than 1 % of the joint's range count as 1 % (see
        :mod:`uvms_qp.analytic.joint_limits`).
        """
        q = state.joints if self._jsel is None else state.joints[self._jsel]
        H, grad = index_and_gradient(q.tolist(), self._table)
        return H, np.array(grad)

    def evaluate(self, state: State, t: float) -> tuple[FloatArray, Any, Any]:
        """The gradient rows or the margin band (see the class docstring).

        Per joint in plain floats (a handful of joints; the constants are prepared at bind).
        """
        q = (state.joints if self._jsel is None else state.joints[self._jsel]).tolist()
        if self.mode == "margin":
            k = self.gain
            lower = []
            upper = []
            distance = math.inf  # to the nearest limit [rad]
            for a, b, lo, hi, x in zip(self._lo_m_list, self._hi_m_list, self._lo_list,
                                       self._hi_list, q, strict=True):
                lower.append((a - x) * k)
                upper.append((b - x) * k)
                d = x - lo if x - lo < hi - x else hi - x
                if d < distance:
                    distance = d
            self._error = (distance,)
            return self._A, lower, upper
        H, g = index_and_gradient(q, self._table)
        self.value = H
        self._error = (H,)
        if self.mode == "damping":
            # a new array every tick: the controller refreshes weights it has not seen
            self.row_weights = np.array([self.weight * (1.0 + abs(x)) for x in g])
            return self._A, 0.0, 0.0
        scale = -self.gain
        if self.normalize:
            norm = math.sqrt(sum(x * x for x in g))
            scale = scale / norm if norm > 1e-12 else 0.0
        sides = [scale * x for x in g]
        return self._A, sides, sides

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "gain", "margin")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "gain":
            self.gain = as_scalar(value, f"{self.name}.gain", positive=True)
        elif key == "margin":
            margin = as_scalar(value, f"{self.name}.margin", nonnegative=True)
            if self.model is not None and np.any(self._hi - self._lo <= 2.0 * margin):
                raise InputError(f"{self.name}.margin: {margin} rad leaves no room inside the "
                                 "limits")
            self.margin = margin
            if self.model is not None:
                self._set_band()
        else:
            super()._apply_update(key, value)
