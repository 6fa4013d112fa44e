"""Joint rate limits as a box on the arm columns of zeta."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import InputError
from ..model.selection import check_joint_list, joint_indices
from .constraint import SymmetricRateBox

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model


class JointVelocityBounds(SymmetricRateBox):
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
        self._set_limits(model.n_vehicle + idx, self.scale * lim)
        return 0
