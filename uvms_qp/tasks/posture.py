"""Arm posture: drive (some) arm joints toward a reference posture."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_vector
from ..errors import InputError
from ..model.selection import check_joint_list, compact_index, joint_indices
from ._common import check_choice
from .error_task import ErrorTask
from .slot import TaskSlot

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class _Held(TaskSlot):
    """The posture held at the first evaluation (``reference="activation"``)."""

    __slots__ = ("held",)

    def clear(self) -> None:
        super().clear()
        self.held: FloatArray | None = None


class PostureTask(ErrorTask):
    r"""Drive arm joints toward a reference posture ``q_ref`` [rad].

    Rows ``S zeta = K (q_ref - q)_S`` where ``S`` selects the joint-rate columns of zeta of the
    chosen joints; error [rad], rows [rad/s].

    Args:
        posture: Reference angles for the selected joints [rad], or None to use ``reference``.
        reference: When ``posture`` is None: ``"activation"`` (the posture at the first
            evaluation after construction/reset) or ``"middle"`` (middle of the joint limits).
        joints: Names of the joints to regulate (default: all arm joints).
        gain: Gain K [1/s], scalar or per joint.
        weight: Weight within the level.
        name: Task name (default ``"posture"``).
    """

    type_name = "posture"
    Slot = _Held
    error_unit = "rad"
    rate_unit = "rad/s"

    def __init__(self, *, posture: list[float] | None = None,
                 reference: Literal["activation", "middle"] = "activation",
                 joints: list[str] | None = None, gain: float | list[float] = 1.0,
                 weight: float = 1.0, name: str | None = None) -> None:
        super().__init__(name=name, weight=weight, gain=gain)
        self.reference = check_choice(reference, ("activation", "middle"),
                                      f"{self.name}.reference")
        self.joints = check_joint_list(joints, f"{self.name}.joints")
        self._idx = np.zeros(0, dtype=int)
        self.posture: FloatArray | None = None if posture is None else self._check(
            "posture", posture)
        self._jsel: Any = self._idx
        self._middle: FloatArray | None = None
        self._fixed: FloatArray | None = None  # the reference when it is not held
        self._A = np.zeros((0, 0))

    def _bind(self, model: Model) -> int:
        idx = joint_indices(model, self.joints, f"{self.name}.joints")
        if idx.size == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        if self.posture is not None and self.posture.shape[0] != idx.size:
            raise InputError(f"{self.name}.posture: expected {idx.size} angles, got "
                             f"{self.posture.shape[0]}")
        if self.posture is not None:
            self._check_limits(self.posture, model, idx)
        lo, hi = np.asarray(model.joint_lower)[idx], np.asarray(model.joint_upper)[idx]
        if self.posture is None and self.reference == "middle" and not (
                np.isfinite(lo).all() and np.isfinite(hi).all()):
            raise InputError(f"{self.name}: reference='middle' needs finite joint limits")
        self._middle = 0.5 * (lo + hi) if self.reference == "middle" else None
        self._idx = idx
        self._jsel = None if idx.tolist() == list(range(model.n_joints)) else compact_index(idx)
        self._A = np.zeros((idx.size, model.nv))
        self._A[np.arange(idx.size), model.n_vehicle + idx] = 1.0
        self._A.setflags(write=False)
        return int(idx.size)

    def _derive(self) -> None:
        super()._derive()
        self._fixed = self.posture if self.posture is not None else self._middle

    def _check_limits(self, posture: FloatArray, model: Model, idx: Any) -> None:
        """Reject a reference angle outside its joint's position limits (where it has any).

        A posture the joint position bounds forbid can never be reached: the task would pull
        the joint against its limit for ever.

        Raises:
            InputError: naming the first such joint, the angle and the limits [rad].
        """
        outside = model.joint_outside_limits(posture, idx)
        if outside is not None:
            raise InputError(f"{self.name}.posture: {outside[1]}")

    def set_target(self, posture: Any) -> None:
        """Set the reference posture ``q_ref`` [rad] of the selected joints (key ``posture``).

        It replaces a held or mid-range reference.

        Raises:
            InputError, ShapeError: the wrong number of angles, an angle outside its limits.
        """
        self.update(posture=posture)

    def error_rows(self, state: State, t: float, slot: TaskSlot
                   ) -> tuple[FloatArray, FloatArray, None]:
        """``(S, q_ref - q, None)`` on the selected joints [rad] (``S`` selects their columns)."""
        q = state.joints if self._jsel is None else state.joints[self._jsel]
        q_ref = self._fixed
        if q_ref is None:  # held: the posture at the first evaluation
            q_ref = slot.held  # type: ignore[attr-defined]
            if q_ref is None:
                q_ref = slot.held = q.copy()  # type: ignore[attr-defined]
        return self._A, q_ref - q, None

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "posture")

    def _check(self, key: str, value: Any) -> Any:
        if key == "posture":
            n = self._idx.size or None
            posture = as_vector(value, f"{self.name}.posture", n).copy()
            if self.model is not None:
                self._check_limits(posture, self.model, self._idx)
            return posture
        return super()._check(key, value)
