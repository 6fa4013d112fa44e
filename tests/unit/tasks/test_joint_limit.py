"""JointLimitTask gradient form at, just inside and just outside the joint limits.

The exact index of Wang et al. (2017), Eq. (15)-(16), is infinite at a limit; the task
saturates it (distances clipped at 1 % of the range). Rows must stay finite and bounded, keep the
direction of the exact gradient, and equal it away from the limits; every back-end must then
solve a stack holding such rows.
"""

from __future__ import annotations

import numpy as np
import pytest

from uvms_qp.analytic import LIMIT_CLEARANCE, joint_limit_gradient_bound
from uvms_qp.controller import Controller
from uvms_qp.stack import Level, Stack
from uvms_qp.tasks import EndEffectorTask, JointLimitTask

C = np.array([10.0, 6.0, 10.0, 10.0])
GAIN = 2.0


def exact_gradient(q, lo, hi, c):
    """Eq. (16) written out independently (finite wherever q is not exactly at a limit)."""
    return (hi - lo) ** 2 * (2 * q - hi - lo) / (c * (hi - q) ** 2 * (q - lo) ** 2)


def _rows_at(rov, joints):
    task = JointLimitTask(mode="gradient", strength=list(C), gain=GAIN).bind(rov)
    state = rov.state(rov.configuration(np.zeros(6), joints))
    return task.rows(state)


# offsets from the limit as fractions of the range: outside, at, just inside (inside the
# clearance), farther inside (exact region)
@pytest.mark.parametrize("offset", [-0.2, -1e-9, 0.0, 1e-9, 1e-3, 5e-3])
@pytest.mark.parametrize("side", ["lower", "upper"])
def test_gradient_rows_near_a_limit_are_finite_bounded_and_point_back(rov, offset, side):
    lo, hi = rov.joint_lower, rov.joint_upper
    span = hi - lo
    joints = lo + span * offset if side == "lower" else hi - span * offset
    rows = _rows_at(rov, joints)
    cols = rows.A[:, rov.n_vehicle:]
    np.testing.assert_array_equal(cols, np.eye(4))
    assert np.all(np.isfinite(rows.lower)) and np.array_equal(rows.lower, rows.upper)
    bound = GAIN * joint_limit_gradient_bound(lo, hi, C)
    assert np.all(np.abs(rows.lower) <= bound * (1 + 1e-12))
    assert bound.max() < 1e4  # instead of ~1e17 for a joint at its limit
    # the request pushes the joint back toward mid-range (qdot > 0 at/below the lower limit)
    expected_sign = 1.0 if side == "lower" else -1.0
    assert np.all(np.sign(rows.lower) == expected_sign)
    if offset != 0.0:  # the exact gradient exists off the limit (also outside): same direction
        exact = -GAIN * exact_gradient(joints, lo, hi, C)
        assert np.all(np.sign(rows.lower) == np.sign(exact))
    if offset > 0.0:  # inside, saturation only ever lowers the magnitude
        assert np.all(np.abs(rows.lower) <= np.abs(exact) * (1 + 1e-12))


def test_gradient_rows_are_exact_outside_the_clearance(rov):
    lo, hi = rov.joint_lower, rov.joint_upper
    span = hi - lo
    for frac in (1.01 * LIMIT_CLEARANCE, 0.05, 0.3, 0.5, 0.9, 1 - 1.01 * LIMIT_CLEARANCE):
        joints = lo + frac * span
        rows = _rows_at(rov, joints)
        np.testing.assert_allclose(rows.lower, -GAIN * exact_gradient(joints, lo, hi, C),
                                   rtol=1e-12, atol=1e-12)


def test_gradient_grows_toward_the_limit_and_stays_near_the_bound_beyond_it(rov):
    lo, hi = rov.joint_lower, rov.joint_upper
    span = hi - lo
    fracs = np.linspace(0.3, -0.1, 81)  # from inside, through the upper limit, to outside
    values = np.array([-_rows_at(rov, hi - f * span).lower for f in fracs])
    inside = fracs >= 0.0
    # |grad| grows toward the limit (continuously through the clearance)...
    assert np.all(np.diff(values[inside], axis=0) >= -1e-9 * np.abs(values[inside][1:]))
    # ...and beyond it stays within [0.9, 1] of the bound: the push back never fades
    bound = GAIN * joint_limit_gradient_bound(lo, hi, C)
    assert np.all(values[~inside] <= bound) and np.all(values[~inside] >= 0.9 * bound)


@pytest.mark.parametrize("solver", ["daqp", "nullspace", "cascade:quadprog", "cascade:proxqp",
                                    "cascade:osqp", "cascade:piqp", "cascade:clarabel"])
def test_every_backend_solves_a_stack_with_joints_at_their_limits(rov, solver):
    joints = np.array([0.0, 3.8, 1.0, 6.2])  # two joints exactly at a limit, one at the other
    q = rov.configuration(np.zeros(6), joints)
    target = rov.frame_pose(q, "tool")[:3, 3] + [0.1, 0.0, 0.0]
    stack = Stack(levels=[Level(EndEffectorTask(position=list(target), gain=1.0)),
                          Level(JointLimitTask(mode="gradient", gain=GAIN))])
    result = Controller(rov, stack, solver=solver, dt=0.05).step(rov.state(q), 0.0)
    assert result.ok, result.summary()
    assert np.all(np.isfinite(result.zeta))
    assert result.step_time < 5.0
    # the tool level is met; the joints at their limits are driven back inside
    assert result.level_violations[0] < 1e-5, result.summary()
    qd = result.zeta[rov.n_vehicle:]
    assert qd[0] > 0 and qd[1] < 0 and qd[3] < 0


def test_margin_rows_on_a_joint_subset_and_outside_the_limits(rov):
    task = JointLimitTask(mode="margin", margin=0.1, gain=1.5,
                          joints=["axis_b", "axis_e"]).bind(rov)
    idx = task.joint_indices
    lo_lim, hi_lim = rov.joint_lower[idx], rov.joint_upper[idx]
    rng = np.random.default_rng(14)
    span = rov.joint_upper - rov.joint_lower
    for _ in range(10):
        eta, _ = rov.split(rov.random_configuration(rng))
        joints = rng.uniform(rov.joint_lower - 0.2 * span, rov.joint_upper + 0.2 * span)
        state = rov.state(rov.configuration(eta, joints))
        slot = task.new_slot()
        rows = task.rows(state, slot=slot)
        q = state.joints[idx]
        np.testing.assert_allclose(rows.lower, 1.5 * (lo_lim + 0.1 - q), rtol=1e-14)
        np.testing.assert_allclose(rows.upper, 1.5 * (hi_lim - 0.1 - q), rtol=1e-14)
        assert slot.last_error[0] == np.minimum(q - lo_lim, hi_lim - q).min()
