"""Infeasible situations at run time: degrade truthfully, recover, never leave the hard box."""

from __future__ import annotations

import math

import numpy as np
import pytest

from uvms_qp.constraints import (
    JointPositionBounds,
    JointVelocityBounds,
    LinearInequality,
    VehicleRateBounds,
)
from uvms_qp.controller import Controller
from uvms_qp.errors import NoSolutionFound
from uvms_qp.hqp import Status
from uvms_qp.model import load_model
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, JointLimitTask, PostureTask, StationKeepingTask

DT = 0.05  # [s]


@pytest.fixture(scope="module")
def rov():
    return load_model("bluerov2_heavy_alpha5")


@pytest.mark.parametrize("offset", [1e-6, 1e-3, 0.1])
@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
def test_joint_outside_its_limit_recovers_monotonically(rov, offset, solver):
    """axis_d starts ``offset`` below its lower limit; the joint-limit level pulls it back at
    the allowed rate (rate bound 0.5 rad/s), a tool task below keeps pulling the other way."""
    rate = float(rov.joint_rate_limit[1])
    lower = float(rov.joint_lower[1])
    joints = np.array([3.0, lower - offset, 1.7, 3.0])
    q = rov.configuration(np.zeros(6), joints)
    stack = Stack(levels=[Level(JointLimitTask(mode="margin", margin=0.05, gain=1.0 / DT)),
                          Level(EndEffectorTask(position=[0.2, 0.0, 0.8], gain=2.0))],
                  constraints=[JointPositionBounds(gain=0.5), JointVelocityBounds(),
                               VehicleRateBounds(linear=0.3, angular=0.3)])
    ctrl = Controller(rov, stack, solver=solver, dt=DT)
    outside = [offset]
    for _ in range(40):
        res = ctrl.step(rov.state(q), 0.0)
        assert res.stage == "primary", res.summary()
        assert np.all(np.abs(res.zeta[6:]) <= rov.joint_rate_limit)
        q = rov.integrate(q, res.zeta, DT)
        outside.append(max(lower - float(rov.split(q)[1][1]), 0.0))
    d = np.array(outside)
    assert np.all(np.diff(d) <= 0.0), d  # monotone: never further out
    needed = math.ceil(offset / (rate * DT))  # steps at the full allowed rate
    assert np.all(d[needed:] <= 1e-12), d  # back inside (to round-off), and stays
    if offset >= rate * DT:  # a full-rate step while far outside
        assert d[0] - d[1] == pytest.approx(rate * DT, rel=1e-6)


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
def test_zero_rate_bound_on_a_dof_a_level_needs(rov, solver):
    """Station keeping needs surge; surge is bounded to exactly zero: the level is reported
    unmet, surge is exactly 0, the higher level is unaffected, and no fallback is needed."""
    q = rov.configuration([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [3.0, 1.2, 1.7, 3.0])
    stack = Stack(levels=[Level(PostureTask(gain=1.0)),
                          Level(StationKeepingTask(axes=["x"], target=[1.0],
                                                   gain=1.0))],
                  constraints=[VehicleRateBounds(limits=[0.0, 0.3, 0.3, 0.3, 0.3, 0.3]),
                               JointVelocityBounds()])
    res = Controller(rov, stack, solver=solver, dt=DT).step(rov.state(q), 0.0)
    assert res.stage == "primary"
    assert res.zeta[0] == 0.0
    assert res.status == Status.OPTIMAL and res.hierarchy.infeasible_level == 1
    assert res.level_violations[0] <= 1e-9
    assert res.task_residuals["station_keeping"][0] == pytest.approx(1.0, rel=1e-6)


@pytest.mark.parametrize("solver", ["daqp", "cascade:quadprog"])
def test_bounds_that_become_mutually_infeasible_at_run_time(rov, solver):
    """A hard row ``u >= 0.2`` [m/s] is compatible with the rate bound 0.3 m/s until it is
    raised to 0.5 at run time: the step degrades to zero (inside the box) with status
    ``hard_infeasible``, strict mode raises, and restoring the row restores the primary solve."""
    q = rov.configuration(np.zeros(6), [3.0, 1.2, 1.7, 3.0])
    row = LinearInequality(A=[[1.0]], lower=[0.2], columns=["u"])
    stack = Stack(levels=[Level(PostureTask(gain=1.0))],
                  constraints=[VehicleRateBounds(linear=0.3, angular=0.3), JointVelocityBounds(),
                               row])
    ctrl = Controller(rov, stack, solver=solver, dt=DT)
    twin = stack.copy()
    strict = Controller(rov, twin, solver=solver, dt=DT, strict=True)
    state = rov.state(q)
    ok = ctrl.step(state, 0.0)
    assert ok.stage == "primary" and ok.zeta[0] >= 0.2 - 1e-9
    row.lower[:] = 0.5
    twin.constraints[-1].lower[:] = 0.5
    bad = ctrl.step(state, 0.05)
    assert bad.status == Status.HARD_INFEASIBLE and bad.stage in ("zero", "decayed_previous")
    assert np.all(bad.zeta >= bad.lower) and np.all(bad.zeta <= bad.upper)
    assert any("admit no point" in a for a in bad.attempts)
    with pytest.raises(NoSolutionFound):
        strict.step(state, 0.05)
    row.lower[:] = 0.2
    again = ctrl.step(state, 0.1)
    assert again.stage == "primary" and again.ok
