"""Problems reported against earlier versions, each pinned by a test.

* An end-effector gain of 1e9 without a vehicle rate bound: a step reported ``backend_error``
  and returned a joint rate of 0.5067 rad/s above the 0.5 rad/s limit. Now every command is
  saturated into the box, whatever the back-end returns.
* Closed-form schemes built ``StepResult`` through private fields: ``StepResult`` now has one
  constructor with public fields, which the schemes use; its reports and ``summary()`` work
  without a hierarchy result.
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.constraints import JointPositionBounds, JointVelocityBounds
from uvms_qp.controller import Controller, StepResult
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


def test_closed_form_results_use_the_one_constructor():
    zeta = np.array([0.1, -0.2, 0.3])
    residuals = {"tool": (0.01, "m"), "posture": (0.2, "rad")}
    a = _make_result("sr_tp", zeta, residuals, 1e-4, 2.5)
    assert isinstance(a, StepResult) and a.hierarchy is None
    assert (a.status, a.t, a.step_time, a.scheme, a.solver, a.stage) == (
        Status.OPTIMAL, 2.5, 1e-4, "sr_tp", "closed-form", "primary")
    assert a.level_names == (("tool", "posture"),)
    assert a.task_residuals == residuals and a.task_errors == residuals
    assert a.level_violations == pytest.approx([np.hypot(0.01, 0.2)])
    assert a.ok and a.bound_violation == 0.0
    assert "sr_tp" in a.summary() and "level 0" in a.summary()


def test_a_result_without_hierarchy_measures_its_box():
    res = StepResult(np.array([0.5, 2.0]), Status.BACKEND_ERROR, None, 0.0, 0.0, "s", "x",
                     np.array([-1.0, -1.0]), np.array([1.0, 1.0]))
    assert res.bound_violation == pytest.approx(1.0) and not res.ok
    assert res.task_residuals == {} and res.level_violations == []
