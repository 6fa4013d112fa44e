"""Vehicle motion minimisation with the motion distribution of Wang et al. (2017)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from .._validation import FloatArray, as_scalar
from ..errors import InputError
from ._checks import check_flag
from .slot import TaskSlot
from .task import Task

if TYPE_CHECKING:  # pragma: no cover
    from ..model import Model, State


def motion_distribution_weights(model: Any, beta: float = 0.5, w_max: float = 1.0) -> FloatArray:
    r"""Diagonal metric ``W`` (nv,) of the motion distribution of Wang et al. (2017).

    Eq. (14) gives the inverse weights ``w^{-1} = diag((1 - beta) w_max I_v, beta I_n)``, so
    ``W = diag(1 / ((1 - beta) w_max) I_v, 1 / beta I_n)``: a large ``beta`` makes vehicle motion
    expensive (the arm does the work). Usable as ``Controller(..., metric=W)``.

    Args:
        model: Model (gives ``n_vehicle`` and ``nv``).
        beta: Motion distribution factor, strictly between 0 and 1.
        w_max: Maximum vehicle weight factor, ``0 < w_max <= 1``.
    """
    beta = as_scalar(beta, "beta")
    w_max = as_scalar(w_max, "w_max", positive=True)
    if not 0.0 < beta < 1.0:
        raise InputError(f"beta: expected 0 < beta < 1, got {beta} (use hard vehicle rate bounds "
                         "of zero to forbid vehicle motion)")
    if w_max > 1.0:
        raise InputError(f"w_max: expected 0 < w_max <= 1, got {w_max}")
    W = np.full(model.nv, 1.0 / beta)
    W[: model.n_vehicle] = 1.0 / ((1.0 - beta) * w_max)
    return W


class VehicleMotionTask(Task):
    r"""Minimise vehicle motion, weighted by the motion distribution of Wang et al. (2017).

    Rows ``zeta_i = 0`` with per-row weights from Wang et al. (2017), Eq. (14): vehicle
    rows weigh ``1 / ((1 - beta) w_max)``, arm rows ``1 / beta`` (the level then minimises
    ``zeta' W zeta``, the metric of the paper's weighted pseudoinverse, Eq. (12)-(13)). With
    ``include_arm=False`` only the vehicle rows are emitted (all weight 1). Rows [m/s, rad/s].

    Args:
        beta: Motion distribution factor, ``0 < beta < 1`` (larger: arm preferred).
        w_max: Maximum vehicle weight factor, ``0 < w_max <= 1``.
        include_arm: Also emit the arm joint-rate rows.
        weight: Weight within the level.
        name: Task name (default ``"vehicle_motion"``).
    """

    type_name = "vehicle_motion"
    error_unit = "m/s, rad/s"
    rate_unit = "m/s, rad/s"

    def __init__(self, *, beta: float = 0.5, w_max: float = 1.0, include_arm: bool = True,
                 weight: float = 1.0, name: str | None = None) -> None:
        super().__init__(name=name, weight=weight)
        self.include_arm = check_flag(include_arm, f"{self.name}.include_arm")
        self.beta = self._check("beta", beta)
        self.w_max = self._check("w_max", w_max)
        self._A = np.zeros((0, 0))

    def _bind(self, model: Model) -> int:
        if model.n_vehicle == 0:
            raise InputError(f"{self.name}: model {model.name!r} has no actuated vehicle DOF")
        m = model.nv if self.include_arm else model.n_vehicle
        self._A = np.eye(m, model.nv)
        self._A.setflags(write=False)
        return m

    def _derive(self) -> None:
        super()._derive()
        if self.include_arm:
            self.row_weights = self.weight * motion_distribution_weights(
                self.model, self.beta, self.w_max)

    def evaluate(self, state: State, t: float, slot: TaskSlot) -> tuple[FloatArray, float, float]:
        """``zeta_i = 0`` on the vehicle (and arm) rows (no error: ``slot.error`` stays None)."""
        return self._A, 0.0, 0.0

    def updatable(self) -> tuple[str, ...]:
        """Parameters accepted by :meth:`update`."""
        return (*super().updatable(), "beta", "w_max")

    def _check(self, key: str, value: Any) -> Any:
        if key == "beta":
            beta = as_scalar(value, f"{self.name}.beta")
            if not 0.0 < beta < 1.0:
                raise InputError(f"{self.name}.beta: expected 0 < beta < 1, got {beta} (use hard "
                                 "vehicle rate bounds of zero to forbid vehicle motion)")
            return beta
        if key == "w_max":
            w_max = as_scalar(value, f"{self.name}.w_max", positive=True)
            if w_max > 1.0:
                raise InputError(f"{self.name}.w_max: expected 0 < w_max <= 1, got {w_max}")
            return w_max
        return super()._check(key, value)
