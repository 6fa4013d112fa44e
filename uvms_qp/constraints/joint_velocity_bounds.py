"""Joint rate limits as a box on the arm columns of zeta."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._validation import FloatArray, as_scalar, as_vector
from ..errors import InputError
from ..tasks._common import check_joint_list, joint_indices
from .constraint import Constraint

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


class JointVelocityBounds(Constraint):
    r"""Hard joint rate limits ``|qdot_i| <= scale * qdot_max,i`` [rad/s].

    Args:
        limits: Rate limits [rad/s] for the selected joints (default: the model's
            ``joint_rate_limit``; joints with an infinite limit stay unconstrained).
        scale: Factor applied to the limits, ``0 < scale``.
        joints: Joint names (default: all arm joints).
        name: Name (default ``"joint_velocity_bounds"``).
    """

    type_name = "joint_velocity_bounds"
    unit = "rad/s"
    has_box = True
    is_static = True

    def __init__(self, *, limits: list[float] | None = None, scale: float = 1.0,
                 joints: list[str] | None = None, name: str | None = None) -> None:
        super().__init__(name=name)
        self.scale = as_scalar(scale, f"{self.name}.scale", positive=True)
        self.joints = check_joint_list(joints, f"{self.name}.joints")
        self._limits_arg = None if limits is None else as_vector(limits, f"{self.name}.limits",
                                                                 allow_inf=True)
        if self._limits_arg is not None and np.any(self._limits_arg <= 0.0):
            raise InputError(f"{self.name}.limits: expected positive rate limits")
        self._cols = np.zeros(0, dtype=int)
        self._lim = np.zeros(0)

    def _bind(self, model: Model) -> int:
        idx = joint_indices(model, self.joints, f"{self.name}.joints")
        if self._limits_arg is None:
            lim = np.asarray(model.joint_rate_limit, dtype=float)[idx]
        else:
            if self._limits_arg.shape[0] != idx.size:
                raise InputError(f"{self.name}.limits: expected {idx.size} values, got "
                                 f"{self._limits_arg.shape[0]}")
            lim = self._limits_arg
        lim = self.scale * lim
        finite = np.isfinite(lim)
        self._cols = model.n_vehicle + idx[finite]
        self._lim = lim[finite]
        return 0

    def fill_box(self, state: State, dt: float, lower: FloatArray, upper: FloatArray) -> None:
        """Intersect ``[-limit, limit]`` into the box."""
        cols = self._cols
        lower[cols] = np.maximum(lower[cols], -self._lim)
        upper[cols] = np.minimum(upper[cols], self._lim)
