"""A task that pushes the arm joints on at fixed rates: the way tests drive joints into limits.

A reference posture may not lie outside the joint limits (``PostureTask`` rejects it), so a test
that needs a task pulling a joint against its limit for ever asks for a joint rate instead.
"""

from __future__ import annotations

import numpy as np

from uvms_qp.tasks import Task


class JointRateTask(Task):
    """Rows ``qdot = rates`` over every arm joint [rad/s] (equality rows, one per joint)."""

    type_name = "joint_rate"
    error_unit = "rad/s"
    rate_unit = "rad/s"

    def __init__(self, rates, name: str = "joint_rate") -> None:
        super().__init__(name=name)
        self.rates = np.asarray(rates, dtype=float)
        self._A = np.zeros((0, 0))

    def _bind(self, model) -> int:
        n = model.n_joints
        assert self.rates.shape == (n,), (self.rates.shape, n)
        self._A = np.zeros((n, model.nv))
        self._A[np.arange(n), model.n_vehicle + np.arange(n)] = 1.0
        return n

    def evaluate(self, state, t, slot):
        return self._A, self.rates, self.rates
