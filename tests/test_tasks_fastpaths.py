"""Fused per-tick ``fill`` paths of the tasks equal their reference computations.

Every task's ``fill`` (the controller's hot path) is compared with the rows rebuilt from the
task's own ``compute_error`` / ``compute_jacobian`` / ``compute_feedforward`` (error tasks) or
``compute_value`` (objective tasks), and the manipulability gradient with an independent numpy
evaluation of ``000_7b5f597fe4e36aa4.txt, Eq. (19)`` (pseudoinverse and explicit column
derivatives).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from reference_kinematics import reference_manipulability

from uvms_qp.constraints import JointPositionBounds
from uvms_qp.errors import InputError
from uvms_qp.model import load_model
from uvms_qp.tasks import (
    CurrentAlignmentTask,
    EndEffectorTask,
    JointLimitTask,
    ManipulabilityTask,
    PayloadMomentTask,
    PostureTask,
    StationKeepingTask,
    VehicleAttitudeTask,
    manipulability_and_gradient,
)
from uvms_qp.tasks._common import wrap_angle, wrap_angles_in_place

BLUEROV = load_model("bluerov2_heavy_alpha5")
WANG = load_model("wang_9dof")


class _Line:
    """A straight-line trajectory with a feed-forward velocity."""

    def __init__(self, start, velocity):
        self.start, self.v = np.asarray(start, float), np.asarray(velocity, float)
        self.duration = 10.0

    def sample(self, t):
        class S:
            pass

        s = S()
        s.position, s.velocity = self.start + t * self.v, self.v.copy()
        s.rotation = s.angular_velocity = None
        return s


def _states(model, n=25, seed=0):
    rng = np.random.default_rng(seed)
    return [model.state(model.random_configuration(rng)) for _ in range(n)]


def _fill(task, state, t=0.0):
    A = np.full((task.dim, task.model.nv), np.nan)  # stale buffers: every entry must be written
    lo = np.full(task.dim, np.nan)
    hi = np.full(task.dim, np.nan)
    task.fill(state, t, A, lo, hi)
    return A, lo, hi


def _error_task_reference(task, state, t):
    e = task.compute_error(state, t).copy()
    J = np.array(task.compute_jacobian(state, t))
    ff = task.compute_feedforward(state, t)
    b = np.multiply(task.gain, e) + (0.0 if ff is None else ff)
    return J, b, e


ERROR_TASKS = [
    lambda: EndEffectorTask(trajectory=_Line([0.5, 0.1, 0.2], [0.1, -0.2, 0.05]), gain=2.0),
    lambda: EndEffectorTask(axes=["x", "z"], position=[0.5, 0.1, 0.2], gain=[1.0, 3.0]),
    lambda: EndEffectorTask(axes=["z", "x"], trajectory=_Line([0.5, 0.1, 0.2], [0.3, 0.2, 0.1])),
    lambda: EndEffectorTask(mode="pose", position=[0.5, 0.1, 0.2], rotation=[0.1, 0.2, 0.3]),
    lambda: StationKeepingTask(target=[0.1, -0.2, 0.3, 3.1], gain=[1.0, 2.0, 3.0, 4.0]),
    lambda: StationKeepingTask(axes=["psi", "x", "phi", "theta"], target=[-3.1, 0.1, 3.0, -3.0]),
    lambda: CurrentAlignmentTask(heading=3.0, offset=0.5, gain=0.7),
    lambda: CurrentAlignmentTask(heading=-3.1, offset=-0.2, gain=[1.3]),
    lambda: VehicleAttitudeTask(roll=3.1, pitch=-0.2, gain=[1.0, 2.0]),
    lambda: VehicleAttitudeTask(axes=["theta"], pitch=0.3),
    lambda: PostureTask(joints=["axis_b", "axis_d"], posture=[1.0, 2.0], gain=0.3),
]


@pytest.mark.parametrize("make", ERROR_TASKS)
def test_fused_error_task_rows_equal_the_compute_methods(make):
    task = make().bind(BLUEROV)
    for k, state in enumerate(_states(BLUEROV, seed=1)):
        t = 0.1 * k
        A, lo, hi = _fill(task, state, t)
        J, b, e = _error_task_reference(task, state, t)
        np.testing.assert_array_equal(A, J)
        np.testing.assert_array_equal(lo, b)
        np.testing.assert_array_equal(hi, b)
        np.testing.assert_array_equal(task.last_error, e)


def test_the_kept_error_is_a_new_array_every_tick():
    """A step result keeps a reference to the task error: the next tick must not overwrite it."""
    task = EndEffectorTask(position=[0.5, 0.1, 0.2]).bind(BLUEROV)
    s1, s2 = _states(BLUEROV, n=2, seed=2)
    _fill(task, s1)
    e1 = task.last_error
    kept = e1.copy()
    _fill(task, s2)
    assert task.last_error is not e1
    np.testing.assert_array_equal(e1, kept)


def test_wrapping_per_entry_equals_the_vector_wrap():
    rng = np.random.default_rng(3)
    e = rng.uniform(-20.0, 20.0, 12)
    e[:4] = (math.pi, -math.pi, 3 * math.pi, 0.0)
    ref = e.copy()
    positions = [0, 1, 2, 3, 5, 8, 11]
    ref[positions] = wrap_angle(ref[positions])
    wrap_angles_in_place(e, positions)
    np.testing.assert_array_equal(e, ref)


@pytest.mark.parametrize(("mode", "normalize"),
                         [("reduce", False), ("reduce", True), ("bound", False)])
def test_payload_rows_equal_compute_value(mode, normalize):
    task = PayloadMomentTask(mode=mode, force=12.0, gain=0.4, maximum=0.2,
                             normalize=normalize).bind(BLUEROV)
    nvh = BLUEROV.n_vehicle
    for state in _states(BLUEROV, seed=4):
        A, lo, hi = _fill(task, state)
        M, g = task.compute_value(state)
        assert task.value == M
        if mode == "bound":
            np.testing.assert_array_equal(A[0, nvh:], g)
            assert not A[0, :nvh].any()
            assert lo[0] == -np.inf and hi[0] == 0.4 * (0.2 - M)
        else:
            np.testing.assert_array_equal(A[:, nvh:], np.eye(BLUEROV.n_joints))
            assert not A[:, :nvh].any()
            scale = -0.4 / np.linalg.norm(g) if normalize else -0.4
            np.testing.assert_allclose(lo, scale * g, rtol=1e-15, atol=0.0)
            np.testing.assert_array_equal(hi, lo)


@pytest.mark.parametrize("model", [BLUEROV, WANG], ids=lambda m: m.name)
def test_joint_limit_margin_rows_equal_the_band_formula(model):
    task = JointLimitTask(mode="margin", margin=0.1, gain=2.0).bind(model)
    idx = task.joint_indices
    lo_lim, hi_lim = model.joint_lower[idx], model.joint_upper[idx]
    for state in _states(model, seed=5):
        A, lo, hi = _fill(task, state)
        np.testing.assert_array_equal(A[:, model.n_vehicle + idx], np.eye(idx.size))
        assert np.count_nonzero(A) == idx.size
        q = state.joints[idx]
        np.testing.assert_array_equal(lo, 2.0 * (lo_lim + 0.1 - q))
        np.testing.assert_array_equal(hi, 2.0 * (hi_lim - 0.1 - q))
        assert task.last_error[0] == np.minimum(q - lo_lim, hi_lim - q).min()
    task.update(margin=0.2)
    state = _states(model, n=1, seed=6)[0]
    _, lo, hi = _fill(task, state)
    np.testing.assert_array_equal(lo, 2.0 * (lo_lim + 0.2 - state.joints[idx]))


def test_joint_position_bounds_fill_box_equals_joint_band():
    con = JointPositionBounds(gain=0.5, margin=0.05).bind(BLUEROV)
    nvh = BLUEROV.n_vehicle
    for state in _states(BLUEROV, seed=7):
        lower, upper = con.box(state, 0.05)
        band_lo, band_hi = con.joint_band(state.joints, 0.05)
        np.testing.assert_array_equal(lower[nvh:], band_lo)
        np.testing.assert_array_equal(upper[nvh:], band_hi)
        assert np.all(np.isinf(lower[:nvh])) and np.all(np.isinf(upper[:nvh]))


# ------------------------------------------------------------------------- manipulability
def _cross_columns(a, b):
    return np.cross(a.T, b.T).T


@pytest.mark.parametrize("rows", [None, (0, 1, 2), [0, 1, 2], np.arange(3), (0, 2), [0, 1],
                                  (3, 4, 5), range(6), (1, 0, 2)])
@pytest.mark.parametrize("model", [BLUEROV, WANG], ids=lambda m: m.name)
def test_manipulability_gradient_equals_the_trace_formula_for_any_row_sequence(model, rows):
    ref_rows = [0, 1, 2] if rows is None else list(rows)
    for state in _states(model, n=10, seed=8):
        J6 = np.array(state.arm_jacobian("tool"))
        w, g = manipulability_and_gradient(J6, rows)
        w_ref, g_ref = reference_manipulability(J6, ref_rows)
        assert w == pytest.approx(w_ref, rel=1e-10, abs=1e-14)
        scale = max(np.abs(g_ref).max(), 1e-12)
        np.testing.assert_allclose(g / scale, g_ref / scale, atol=1e-9)


def test_tuple_rows_select_rows_not_an_element():
    J6 = np.array(_states(WANG, n=1, seed=9)[0].arm_jacobian("tool"))
    w_t, g_t = manipulability_and_gradient(J6, (0, 2))
    w_l, g_l = manipulability_and_gradient(J6, np.array([0, 2]))
    assert w_t == w_l
    np.testing.assert_array_equal(g_t, g_l)
    w_default, g_default = manipulability_and_gradient(J6)
    w_tuple, g_tuple = manipulability_and_gradient(J6, (0, 1, 2))
    assert w_default == w_tuple
    np.testing.assert_array_equal(g_default, g_tuple)


@pytest.mark.parametrize("mode", ["floor", "ascend"])
def test_manipulability_rows_use_the_gradient(mode):
    task = ManipulabilityTask(mode=mode, minimum=0.002, gain=2.0).bind(BLUEROV)
    nvh = BLUEROV.n_vehicle
    for state in _states(BLUEROV, n=10, seed=10):
        A, lo, hi = _fill(task, state)
        w, g = manipulability_and_gradient(np.array(state.arm_jacobian("tool")))
        assert task.value == w
        if mode == "floor":
            np.testing.assert_array_equal(A[0, nvh:], g)
            assert not A[0, :nvh].any()
            assert lo[0] == 2.0 * (0.002 - w) and hi[0] == np.inf
        else:
            np.testing.assert_array_equal(A[:, nvh:], np.eye(BLUEROV.n_joints))
            np.testing.assert_array_equal(lo, 2.0 * g)
            np.testing.assert_array_equal(hi, lo)


def _outside_states(model, n=10, seed=11):
    """States with joints drawn up to 20 % of the range beyond either limit."""
    rng = np.random.default_rng(seed)
    lo, hi = model.joint_lower, model.joint_upper
    span = hi - lo
    out = []
    for _ in range(n):
        eta, _ = model.split(model.random_configuration(rng))
        joints = rng.uniform(lo - 0.2 * span, hi + 0.2 * span)
        out.append(model.state(model.configuration(eta, joints)))
    return out


@pytest.mark.parametrize("joints", [None, ["axis_d", "axis_b"]])
def test_joint_position_bounds_intersect_a_filled_box_like_numpy(joints):
    """The per-joint float path equals ``max(box, min(band, 0))`` / ``min(box, max(band, 0))``."""
    con = JointPositionBounds(gain=0.7, margin=0.02, joints=joints).bind(BLUEROV)
    cols = BLUEROV.n_vehicle + np.array(
        [BLUEROV.joint_names.index(j) for j in (joints or BLUEROV.joint_names)])
    rng = np.random.default_rng(12)
    for state in _states(BLUEROV, n=10, seed=13) + _outside_states(BLUEROV):
        box_lo = -rng.uniform(0.0, 3.0, BLUEROV.nv)
        box_hi = rng.uniform(0.0, 3.0, BLUEROV.nv)
        lower, upper = box_lo.copy(), box_hi.copy()
        con.fill_box(state, 0.05, lower, upper)
        q = state.joints[cols - BLUEROV.n_vehicle]
        k = 0.7 / 0.05
        band_lo = np.minimum((BLUEROV.joint_lower[cols - BLUEROV.n_vehicle] + 0.02 - q) * k, 0.0)
        band_hi = np.maximum((BLUEROV.joint_upper[cols - BLUEROV.n_vehicle] - 0.02 - q) * k, 0.0)
        ref_lo, ref_hi = box_lo.copy(), box_hi.copy()
        ref_lo[cols] = np.maximum(box_lo[cols], band_lo)
        ref_hi[cols] = np.minimum(box_hi[cols], band_hi)
        np.testing.assert_array_equal(lower, ref_lo)
        np.testing.assert_array_equal(upper, ref_hi)
        assert np.all(lower <= 0.0) and np.all(upper >= 0.0)


def test_joint_limit_margin_on_a_joint_subset_and_outside_the_limits():
    task = JointLimitTask(mode="margin", margin=0.1, gain=1.5,
                          joints=["axis_b", "axis_e"]).bind(BLUEROV)
    idx = task.joint_indices
    lo_lim, hi_lim = BLUEROV.joint_lower[idx], BLUEROV.joint_upper[idx]
    for state in _outside_states(BLUEROV, seed=14):
        _, lo, hi = _fill(task, state)
        q = state.joints[idx]
        np.testing.assert_array_equal(lo, 1.5 * (lo_lim + 0.1 - q))
        np.testing.assert_array_equal(hi, 1.5 * (hi_lim - 0.1 - q))
        assert task.last_error[0] == np.minimum(q - lo_lim, hi_lim - q).min()


def test_vehicle_attitude_set_point_update_reaches_the_fused_rows():
    task = VehicleAttitudeTask(roll=0.0, pitch=0.0, gain=[1.0, 2.0]).bind(BLUEROV)
    task.update(roll=-3.0, pitch=3.1)
    for state in _states(BLUEROV, n=10, seed=15):
        _, lo, _ = _fill(task, state)
        phi, theta = state.eta[3], state.eta[4]
        ref = wrap_angle(np.array([-3.0 - phi, 3.1 - theta])) * np.array([1.0, 2.0])
        np.testing.assert_array_equal(lo, ref)


def test_payload_lever_arm_is_the_tool_position_in_the_arm_base_frame():
    task = PayloadMomentTask(force=5.0).bind(BLUEROV)
    for state in _states(BLUEROV, n=10, seed=16):
        x, y = task._lever_arm(state)
        T = state.pose_in("tool", "arm_base")
        np.testing.assert_allclose([x, y], T[:2, 3], rtol=0.0, atol=1e-15)
        M, _ = task.compute_value(state)
        assert pytest.approx(5.0 * (T[0, 3] ** 2 + T[1, 3] ** 2), rel=1e-14) == M


def test_current_alignment_fill_without_heading_names_the_task():
    task = CurrentAlignmentTask(name="yaw").bind(BLUEROV)
    with pytest.raises(InputError, match="yaw"):
        _fill(task, _states(BLUEROV, n=1)[0])
