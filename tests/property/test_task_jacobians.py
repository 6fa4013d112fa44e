"""Task Jacobians and objective gradients against finite differences on every bundled model.

An error-regulating task asks ``J zeta = x_dot_d + K e`` with ``e = x_d - x``; for a fixed target
``d e / dt = -J zeta``. We move the configuration along ``zeta`` on the manifold
(``model.integrate``) and compare central differences of ``e`` with ``-J zeta``.
"""

from __future__ import annotations

import math
import zlib

import numpy as np
import pinocchio as pin
import pytest

from tests.support.reference_kinematics import reference_manipulability
from uvms_qp.model import bundled_models, load_model
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
from uvms_qp.tasks._common import wrap_angle

MODELS = bundled_models()
H = 1e-6


def _fd_error(task, model, q, zeta, slot, angles=None):
    """Central difference of the task error along zeta, wrapping angle rows (``slot``: the
    task's memory, holding what it held at ``q``)."""
    e_plus = task.compute_error(model.state(model.integrate(q, zeta, H)), 0.0, slot).copy()
    e_minus = task.compute_error(model.state(model.integrate(q, -zeta, H)), 0.0, slot).copy()
    diff = e_plus - e_minus
    if angles is not None:
        diff[angles] = wrap_angle(diff[angles])
    return diff / (2 * H)


def _error_tasks(model, rng):
    tasks = []
    q_target = model.random_configuration(rng)
    T = model.frame_pose(q_target, "tool")
    tasks.append(EndEffectorTask(position=T[:3, 3], gain=1.0, name="ee_pos"))
    if model.vehicle_kind != "planar":
        tasks.append(EndEffectorTask(mode="pose", position=T[:3, 3], rotation=T[:3, :3],
                                     name="ee_pose"))
        tasks.append(EndEffectorTask(mode="orientation", rotation=T[:3, :3], axes=["rx", "rz"],
                                     name="ee_rot"))
    else:
        tasks.append(EndEffectorTask(mode="pose", position=T[:3, 3], rotation=T[:3, :3],
                                     name="ee_pose"))
    # targets fixed in moving frames: the rows regulate the frame relative to them
    T_rel = np.linalg.solve(model.frame_pose(q_target, "vehicle"), T)
    mode = "position" if model.vehicle_kind == "planar" else "pose"
    tasks.append(EndEffectorTask(mode=mode, reference="vehicle", target=T_rel, name="ee_veh"))
    tasks.append(EndEffectorTask(reference="arm_base", position=[0.3, 0.1, -0.2],
                                 name="ee_base"))
    tasks.append(EndEffectorTask(mode="pose", reference=model.frames[4], target=np.eye(4),
                                 name="ee_link"))
    tasks.append(PostureTask(posture=list(model.split(q_target)[1]), name="posture"))
    if model.vehicle_kind != "fixed":
        eta_t = model.split(q_target)[0]
        axes = ["x", "y", "psi"] if model.vehicle_kind == "planar" else ["x", "y", "z", "psi"]
        idx = [0, 1, 2] if model.vehicle_kind == "planar" else [0, 1, 2, 5]
        tasks.append(StationKeepingTask(axes=axes, target=list(eta_t[idx]), name="station"))
        tasks.append(CurrentAlignmentTask(heading=float(rng.uniform(-3, 3)), name="current"))
    if model.vehicle_kind == "spatial" and {"p", "q"} <= set(model.actuated):
        tasks.append(VehicleAttitudeTask(roll=0.1, pitch=-0.05, name="attitude"))
    return tasks


@pytest.mark.parametrize("name", MODELS)
def test_error_task_jacobians_match_finite_differences(name):
    model = load_model(name)
    rng = np.random.default_rng(zlib.crc32(name.encode()))  # stable across processes
    for _ in range(2):
        tasks = [t.bind(model) for t in _error_tasks(model, rng)]
        q = model.random_configuration(rng)
        state = model.state(q)
        for task in tasks:
            slot = task.new_slot()
            J = np.array(task.error_rows(state, 0.0, slot)[0])
            assert J.shape == (task.dim, model.nv)
            for _ in range(2):
                zeta = rng.normal(size=model.nv)
                angles = None
                if isinstance(task, StationKeepingTask):
                    angles = np.array([a == "psi" for a in task.axes])
                elif isinstance(task, CurrentAlignmentTask | VehicleAttitudeTask):
                    angles = slice(None)
                fd = _fd_error(task, model, q, zeta, slot, angles)
                J = np.array(task.error_rows(state, 0.0, slot)[0])
                np.testing.assert_allclose(fd, -J @ zeta, atol=2e-6 * (1 + np.abs(fd).max()),
                                           err_msg=f"{name}: {task.name}")


class _Spin:
    """Trajectory: straight line plus rotation at a constant world angular velocity."""

    def __init__(self, p0, v, R0, w):
        self.p0, self.v, self.R0, self.w = map(np.asarray, (p0, v, R0, w))
        self.duration = 10.0

    def sample(self, t):
        class S:
            pass

        s = S()
        s.position = self.p0 + self.v * t
        s.velocity = self.v
        s.rotation = pin.exp3(self.w * t) @ self.R0
        s.angular_velocity = self.w
        return s


@pytest.mark.parametrize("reference", ["world", "vehicle", "link2"])
@pytest.mark.parametrize("name", ["bluerov2_heavy_alpha5", "wang_9dof"])
def test_feedforward_matches_target_time_derivative(name, reference):
    """At fixed q, d e/dt along the trajectory equals the feed-forward term of the rows."""
    model = load_model(name)
    if reference not in model.frames:
        reference = model.frames[5]
    rng = np.random.default_rng(3)
    R0 = pin.exp3(rng.normal(size=3))
    traj = _Spin(rng.normal(size=3), rng.normal(size=3), R0, rng.normal(size=3))
    task = EndEffectorTask(mode="pose", trajectory=traj, reference=reference).bind(model)
    state = model.state(model.random_configuration(rng))
    t = 0.7
    e_plus = task.compute_error(state, t + H).copy()
    de = (e_plus - task.compute_error(state, t - H).copy()) / (2 * H)
    ff = task.error_rows(state, t, task.new_slot())[2]
    np.testing.assert_allclose(de, ff, atol=1e-6 * (1 + np.abs(de).max()))


def _fd_gradient(value, model, q):
    """Central differences of a scalar objective over each arm joint, through integrate."""
    out = np.zeros(model.n_joints)
    for i in range(model.n_joints):
        zeta = np.zeros(model.nv)
        zeta[model.n_vehicle + i] = 1.0
        out[i] = (value(model.state(model.integrate(q, zeta, H)))
                  - value(model.state(model.integrate(q, -zeta, H)))) / (2 * H)
    return out


@pytest.mark.parametrize("name", MODELS)
def test_objective_gradients_match_finite_differences(name):
    model = load_model(name)
    rng = np.random.default_rng(7)
    planar = model.vehicle_kind == "planar"
    objectives = [
        ManipulabilityTask(mode="ascend", name="w_pos"),
        ManipulabilityTask(mode="ascend", axes=["x", "y", "z", "rx", "ry", "rz"], name="w_twist"),
        PayloadMomentTask(force=25.0),
    ]
    if planar:
        objectives.append(ManipulabilityTask(mode="ascend", axes=["x", "y", "rz"], name="w_xyr"))
    finite = np.isfinite(model.joint_lower) & np.isfinite(model.joint_upper)
    if finite.any():
        objectives.append(JointLimitTask(mode="gradient", strength=3.0))
    for task in objectives:
        task.bind(model)
    checked = 0
    for _ in range(3):
        q = model.random_configuration(rng)
        if finite.any():  # keep away from the limits where the index blows up
            lo, hi = model.joint_lower[finite], model.joint_upper[finite]
            eta, joints = model.split(q)
            joints[finite] = lo + (hi - lo) * rng.uniform(0.2, 0.8, finite.sum())
            q = model.configuration(eta, joints)
        state = model.state(q)
        for task in objectives:
            value, grad = task.compute_value(state)
            fd = _fd_gradient(lambda s, task=task: task.compute_value(s)[0], model, q)
            scale = 1.0 + np.abs(fd).max()
            np.testing.assert_allclose(grad, fd, atol=2e-6 * scale,
                                       err_msg=f"{name}: {task.name} at q={q}")
            assert math.isfinite(value)
            checked += 1
    assert checked >= 9


def _planar_2r_jacobian(q1: float, q2: float) -> np.ndarray:
    """Twist Jacobian (6, 2) of a planar 2R arm with unit links in world axes, columns [v; w]."""
    p1 = np.array([math.cos(q1), math.sin(q1), 0.0])
    p = p1 + np.array([math.cos(q1 + q2), math.sin(q1 + q2), 0.0])
    z = np.array([0.0, 0.0, 1.0])
    J6 = np.zeros((6, 2))
    J6[:3, 0], J6[3:, 0] = np.cross(z, p), z
    J6[:3, 1], J6[3:, 1] = np.cross(z, p - p1), z
    return J6


def test_manipulability_reference_values():
    """Planar 2R arm with unit links: w = l1 l2 |sin q2| and dw/dq = [0, cos q2] (q2 in (0, pi))."""
    for q2 in (0.3, 1.0, 2.5):
        w, g = manipulability_and_gradient(_planar_2r_jacobian(0.4, q2), [0, 1])
        assert w == pytest.approx(abs(math.sin(q2)), rel=1e-12)
        np.testing.assert_allclose(g, [0.0, math.cos(q2)], atol=1e-12)



@pytest.mark.parametrize("rows", [None, (0, 1, 2), [0, 1, 2], np.arange(3), (0, 2), [0, 1],
                                  (3, 4, 5), range(6), (1, 0, 2)])
@pytest.mark.parametrize("name", ["bluerov2_heavy_alpha5", "wang_9dof"])
def test_manipulability_gradient_equals_the_trace_formula_for_any_row_sequence(name, rows):
    """Eq. (19) with a pseudoinverse and explicit column derivatives (independent oracle)."""
    model = load_model(name)
    rng = np.random.default_rng(8)
    ref_rows = [0, 1, 2] if rows is None else list(rows)
    for _ in range(10):
        J6 = np.array(model.state(model.random_configuration(rng)).arm_jacobian("tool"))
        w, g = manipulability_and_gradient(J6, rows)
        w_ref, g_ref = reference_manipulability(J6, ref_rows)
        assert w == pytest.approx(w_ref, rel=1e-10, abs=1e-14)
        scale = max(np.abs(g_ref).max(), 1e-12)
        np.testing.assert_allclose(g / scale, g_ref / scale, atol=1e-9)


@pytest.mark.parametrize("rows", [None, [0, 1], (3, 4, 5), range(6)])
def test_manipulability_at_a_rank_deficient_jacobian_is_zero_with_a_finite_gradient(rows):
    """Exactly singular ``J_S`` (two selected rows equal; for six rows on four joints, two equal
    columns): w = 0 and a finite gradient equal to the trace formula's (the pseudoinverse)."""
    model = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng(3)
    ref_rows = [0, 1, 2] if rows is None else list(rows)
    for _ in range(5):
        J6 = np.array(model.state(model.random_configuration(rng)).arm_jacobian("tool"))
        if len(ref_rows) > J6.shape[1]:
            J6[:, 1] = J6[:, 0]  # J_S' J_S singular
        else:
            J6[ref_rows[-1]] = J6[ref_rows[0]]  # J_S J_S' singular
        w, g = manipulability_and_gradient(J6, rows)
        w_ref, g_ref = reference_manipulability(J6, ref_rows)
        scale = np.abs(J6[ref_rows]).max() ** min(len(ref_rows), J6.shape[1])
        assert np.isfinite(g).all()
        assert w == pytest.approx(w_ref, abs=1e-7 * scale)
        assert w <= 1e-7 * scale
        np.testing.assert_allclose(g, g_ref, atol=1e-7 * scale)


@pytest.mark.parametrize("q2", [1e-4, 1e-3, math.pi - 1e-3])
def test_manipulability_near_a_stretched_arm_keeps_its_gradient(q2):
    """Planar 2R arm, unit links, next to the stretched (or folded) configuration: w = |sin q2|
    is small, but dw/dq = [0, cos q2] is not (it points away from the singularity)."""
    w, g = manipulability_and_gradient(_planar_2r_jacobian(0.4, q2), [0, 1])
    assert w == pytest.approx(abs(math.sin(q2)), rel=1e-6)
    np.testing.assert_allclose(g, [0.0, math.cos(q2)], atol=1e-6)


def test_tuple_rows_select_rows_not_an_element():
    model = load_model("wang_9dof")
    J6 = np.array(model.state(model.random_configuration(9)).arm_jacobian("tool"))
    w_t, g_t = manipulability_and_gradient(J6, (0, 2))
    w_l, g_l = manipulability_and_gradient(J6, np.array([0, 2]))
    assert w_t == w_l
    np.testing.assert_array_equal(g_t, g_l)
    w_default, g_default = manipulability_and_gradient(J6)
    w_tuple, g_tuple = manipulability_and_gradient(J6, (0, 1, 2))
    assert w_default == w_tuple
    np.testing.assert_array_equal(g_default, g_tuple)
