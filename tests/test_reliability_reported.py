"""Problems reported against earlier versions, each pinned by a test.

* An end-effector gain of 1e9 without a vehicle rate bound: a step reported ``backend_error``
  and returned a joint rate of 0.5067 rad/s above the 0.5 rad/s limit. Now every command is
  saturated into the box, whatever the back-end returns.
* Closed-form schemes built ``StepResult`` through private fields: ``StepResult.from_command`` is
  the public constructor; it gives the same result as the schemes' own packing, and its
  ``summary()`` works (the private packing leaves the level sizes out, so its summary fails).
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds
from uvms_qp.controller import Controller, StepResult
from uvms_qp.errors import NonFiniteError
from uvms_qp.hqp import Status
from uvms_qp.model import load_model
from uvms_qp.schemes.scheme import _make_result
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, PostureTask


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog", "cascade:proxqp", "cascade:osqp"])
def test_huge_gain_without_vehicle_bound_keeps_the_joint_rate_limit(solver):
    rov = load_model("bluerov2_heavy_alpha5")
    stack = Stack(levels=[Level(EndEffectorTask(position=[1.5, 0.5, 0.5], gain=1e9)),
                          Level(PostureTask())],
                  constraints=[JointPositionBounds(), JointVelocityBounds()])
    ctrl = Controller(rov, stack, solver=solver, dt=0.05, deadline=0.5)
    res = ctrl.step(rov.state(rov.home()), 0.0)
    assert np.all(np.isfinite(res.zeta))
    assert np.all(np.abs(res.zeta[6:]) <= rov.joint_rate_limit)  # exactly, no tolerance
    assert np.all(res.zeta >= res.lower) and np.all(res.zeta <= res.upper)


def test_from_command_matches_the_scheme_packing():
    zeta = np.array([0.1, -0.2, 0.3])
    residuals = {"tool": (0.01, "m"), "posture": (0.2, "rad")}
    a = _make_result("sr_tp", zeta, residuals, 1e-4, 2.5)
    b = StepResult.from_command(zeta, t=2.5, step_time=1e-4, scheme="sr_tp",
                                residuals=residuals, message="closed-form scheme sr_tp")
    for name in ("status", "t", "step_time", "scheme", "solver", "level_names", "stage"):
        assert getattr(a, name) == getattr(b, name), name
    np.testing.assert_array_equal(a.zeta, b.zeta)
    np.testing.assert_array_equal(a.lower, b.lower)
    assert a.task_residuals == b.task_residuals
    assert a.task_errors == b.task_errors
    assert a.hierarchy.message == b.hierarchy.message and b.ok and b.bound_violation == 0.0
    assert "sr_tp" in b.summary() and "level 0" in b.summary()


def test_from_command_rejects_non_finite_and_keeps_a_box():
    with pytest.raises(NonFiniteError, match="my_scheme"):
        StepResult.from_command(np.array([0.0, np.nan]), t=0.0, step_time=0.0,
                                scheme="my_scheme")
    res = StepResult.from_command(np.array([0.5, 2.0]), t=0.0, step_time=0.0, scheme="s",
                                  lower=np.array([-1.0, -1.0]), upper=np.array([1.0, 1.0]),
                                  status=Status.BACKEND_ERROR)
    assert res.bound_violation == pytest.approx(1.0) and not res.ok
