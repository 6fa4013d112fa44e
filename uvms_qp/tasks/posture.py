"""Arm posture: drive (some) arm joints toward a reference posture."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from .._validation import FloatArray, as_vector
from ..errors import InputError
from ..model.selection import check_joint_list, compact_index, joint_indices
from ._common import check_choice
from .task import ErrorTask

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


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
        activation: Initial activation in [0, 1] (1: in the stack; see
            :class:`~uvms_qp.tasks.Task`).
    """

    type_name = "posture"
    error_unit = "rad"
    rate_unit = "rad/s"

    def __init__(
        self,
        *,
        posture: list[float] | None = None,
        reference: Literal["activation", "middle"] = "activation",
        joints: list[str] | None = None,
        gain: float | list[float] = 1.0,
        weight: float = 1.0,
        name: str | None = None,
        activation: float = 1.0,
    ) -> None:
        super().__init__(name=name, weight=weight, gain=gain, activation=activation)
        self.reference = check_choice(reference, ("activation", "middle"),
                                      f"{self.name}.reference")
        self.joints = check_joint_list(joints, f"{self.name}.joints")
        self._posture_arg = None if posture is None else as_vector(posture, f"{self.name}.posture")
        self._idx = np.zeros(0, dtype=int)
        self._jsel: Any = self._idx
        self._q_ref: FloatArray | None = None
        self._A = np.zeros((0, 0))

    def _bind(self, model: Model) -> int:
        idx = joint_indices(model, self.joints, f"{self.name}.joints")
        if idx.size == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no arm joints")
        if self._posture_arg is not None and self._posture_arg.shape[0] != idx.size:
            raise InputError(f"{self.name}.posture: expected {idx.size} angles, got "
                             f"{self._posture_arg.shape[0]}")
        if self._posture_arg is not None:
            self._check_limits(self._posture_arg, model, idx)
        if self._posture_arg is None and self.reference == "middle":
            lo, hi = np.asarray(model.joint_lower)[idx], np.asarray(model.joint_upper)[idx]
            if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
                raise InputError(f"{self.name}: reference='middle' needs finite joint limits")
            self._posture_arg = 0.5 * (lo + hi)
        self._idx = idx
        self._jsel = None if idx.tolist() == list(range(model.n_joints)) else compact_index(idx)
        self._A = np.zeros((idx.size, model.nv))
        self._A[np.arange(idx.size), model.n_vehicle + idx] = 1.0
        self._A.setflags(write=False)
        self._set_reference(self._posture_arg)
        return int(idx.size)

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

    def _set_reference(self, value: FloatArray | None) -> None:
        """Set ``q_ref`` (a copy), or None."""
        self._q_ref = None if value is None else value.copy()

    def _reset(self) -> None:
        """Forget the activation posture."""
        self._set_reference(self._posture_arg)

    def error_rows(self, state: State, t: float) -> tuple[FloatArray, FloatArray, None]:
        """``(S, q_ref - q, None)`` on the selected joints [rad] (``S`` selects their columns)."""
        q = state.joints if self._jsel is None else state.joints[self._jsel]
        if self._q_ref is None:
            self._set_reference(q)
        return self._A, self._q_ref - q, None  # type: ignore[operator]

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "posture")

    def _apply_update(self, key: str, value: Any) -> None:
        if key == "posture":
            n = self._idx.size or None
            posture = as_vector(value, f"{self.name}.posture", n)
            if self.model is not None:
                self._check_limits(posture, self.model, self._idx)
            self._posture_arg = posture
            self._set_reference(self._posture_arg)
        else:
            super()._apply_update(key, value)
