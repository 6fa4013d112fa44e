"""Vehicle body-rate limits as a box on the vehicle columns of zeta."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._validation import as_scalar, as_vector
from ..errors import InputError
from .constraint import SymmetricRateBox

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model

_LINEAR = ("u", "v", "w")


class VehicleRateBounds(SymmetricRateBox):
    r"""Hard vehicle body-rate limits ``|nu_i| <= limit_i`` on the actuated DOFs.

    Limits come, in order of precedence, from ``limits`` (one per actuated DOF, in the model's
    ``actuated`` order), from the scalars ``linear`` [m/s] (u, v, w) and ``angular`` [rad/s]
    (p, q, r), and otherwise from the model's ``vehicle_rate_limit``. Infinite limits leave the
    DOF free; a zero limit pins it (no motion of that DOF).

    Args:
        linear: Limit on u, v, w [m/s].
        angular: Limit on p, q, r [rad/s].
        limits: Per actuated DOF limits [m/s or rad/s].
        scale: Factor applied to the resulting limits (> 0).
        name: Name (default ``"vehicle_rate_bounds"``).
    """

    type_name = "vehicle_rate_bounds"
    unit = "m/s, rad/s"

    def __init__(self, *, linear: float | None = None, angular: float | None = None,
                 limits: list[float] | None = None, scale: float = 1.0,
                 name: str | None = None) -> None:
        super().__init__(name=name)
        self.linear = None if linear is None else as_scalar(linear, f"{self.name}.linear",
                                                            nonnegative=True, allow_inf=True)
        self.angular = None if angular is None else as_scalar(angular, f"{self.name}.angular",
                                                              nonnegative=True, allow_inf=True)
        self._limits_arg = None if limits is None else as_vector(limits, f"{self.name}.limits",
                                                                 allow_inf=True)
        if self._limits_arg is not None and np.any(self._limits_arg < 0.0):
            raise InputError(f"{self.name}.limits: expected non-negative limits")
        self.scale = as_scalar(scale, f"{self.name}.scale", positive=True)
        self._cols = np.zeros(0, dtype=int)
        self._lim = np.zeros(0)

    def _bind(self, model: Model) -> int:
        nvh = model.n_vehicle
        if self._limits_arg is not None:
            if self._limits_arg.shape[0] != nvh:
                raise InputError(f"{self.name}.limits: expected {nvh} values (actuated "
                                 f"{', '.join(model.actuated)}), got {self._limits_arg.shape[0]}")
            lim = self._limits_arg.copy()
        else:
            lim = np.asarray(model.vehicle_rate_limit, dtype=float).copy()
            for i, dof in enumerate(model.actuated):
                value = self.linear if dof in _LINEAR else self.angular
                if value is not None:
                    lim[i] = value
        self._set_limits(np.arange(lim.shape[0]), self.scale * lim)
        return 0
