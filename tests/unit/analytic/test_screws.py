import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.analytic import (
    davies_direct,
    davies_solve,
    kinematic_constraint_inverse,
    network_matrix,
    planar_chain_points,
    planar_chain_screws,
    planar_rows,
    planar_uvms_screws,
    ppps_screws,
    prismatic_screw,
    revolute_screw,
    screw_jacobian,
    screw_to_twist_at,
    screw_transform,
    singularity_robust_task_priority,
)
from uvms_qp.errors import InputError, ShapeError

LINKS = np.array([2.0, 2.0, 2.0])
MOUNT = (2.5, 0.0)


def test_revolute_screw_gives_velocity_of_origin_point():
    # axis z through (1, 0, 0), unit rate: the body point at the origin moves with -y velocity
    s = revolute_screw([0, 0, 2.0], [1.0, 0.0, 0.0])
    assert np.allclose(s, [0, 0, 1, 0, -1, 0])
    assert np.allclose(prismatic_screw([0, 3.0, 0]), [0, 0, 0, 0, 1, 0])


def test_screw_transform_moves_screws_like_their_axes():
    rng = np.random.default_rng(1)
    R = pin.rpy.rpyToMatrix(*rng.uniform(-1, 1, 3))
    p = rng.normal(size=3)
    axis, point = rng.normal(size=3), rng.normal(size=3)
    local = revolute_screw(axis, point)
    assert np.allclose(screw_transform(R, p) @ local, revolute_screw(R @ axis, R @ point + p))


def test_paper001_initial_end_effector_pose():
    points, angles = planar_chain_points([1.47, -1.0, 0.3], LINKS, MOUNT, 0.0)
    assert np.allclose(points[-1, :2], [5.92, 4.29], atol=5e-3)
    assert np.isclose(angles[-1], 0.77)


def _pin_planar_chain(n):
    model = pin.Model()
    parent = 0
    for i in range(n):
        placement = pin.SE3(np.eye(3), np.array([0.0 if i == 0 else LINKS[i - 1], 0.0, 0.0]))
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"j{i}")
    model.addFrame(
        pin.Frame(
            "tip",
            parent,
            0,
            pin.SE3(np.eye(3), np.array([LINKS[n - 1], 0, 0])),
            pin.FrameType.OP_FRAME,
        )
    )
    return model


@given(st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3))
def test_screw_jacobian_equals_pinocchio_frame_jacobian(q):
    model = _pin_planar_chain(3)
    data = model.createData()
    q = np.array(q)
    fid = model.getFrameId("tip")
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J_pin = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
    J_screw = planar_chain_screws(q, LINKS)
    tip = planar_chain_points(q, LINKS)[0][-1]
    assert np.allclose(data.oMf[fid].translation, tip)
    assert np.allclose(screw_to_twist_at(J_screw, tip), J_pin, atol=1e-12)


def test_screw_jacobian_general_axes_and_prismatic():
    J = screw_jacobian([[0, 0, 1], [1, 0, 0]], [[1, 1, 0], [9, 9, 9]], ["revolute", "prismatic"])
    assert np.allclose(J[:, 1], [0, 0, 0, 1, 0, 0])
    assert np.allclose(J[:, 0], [0, 0, 1, 1, -1, 0])
    with pytest.raises(InputError, match="kinds"):
        screw_jacobian([[0, 0, 1]], [[0, 0, 0]], ["helical"])
    with pytest.raises(InputError, match="axis"):
        revolute_screw([0, 0, 0], [0, 0, 0])


def test_ppps_screws_are_eq6_and_the_virtual_magnitudes_are_end_effector_velocity():
    assert np.allclose(
        ppps_screws(), np.block([[np.zeros((3, 3)), np.eye(3)], [np.eye(3), np.zeros((3, 3))]])
    )
    E = np.array([1.0, 2.0, 3.0])
    v_E, w = np.array([0.1, -0.2, 0.3]), np.array([0.5, 0.0, -0.4])
    twist_O = ppps_screws(centre=E) @ np.concatenate([v_E, w])
    # twist at the origin: omega, and V_O = v_E + omega x (O - E)
    assert np.allclose(twist_O, np.concatenate([w, v_E + np.cross(w, -E)]))


def _planar_fk(eta, q):
    x, y, psi = eta
    c, s = np.cos(psi), np.sin(psi)
    base = np.array([x + c * MOUNT[0] - s * MOUNT[1], y + s * MOUNT[0] + c * MOUNT[1]])
    points, angles = planar_chain_points(q, LINKS, base, psi)
    return np.array([points[-1, 0], points[-1, 1], angles[-1]])


@given(
    st.lists(st.floats(-2.0, 2.0), min_size=6, max_size=6),
    st.lists(st.floats(-1, 1), min_size=6, max_size=6),
)
def test_davies_direct_kinematics_matches_finite_differences(state, rates):
    eta, q = np.array(state[:3]), np.array(state[3:])
    eta_dot, q_dot = np.array(rates[:3]), np.array(rates[3:])
    V, A, E = planar_uvms_screws(eta, q, LINKS, MOUNT)
    # virtual magnitudes in (px, py, rz) = (x_E_dot, y_E_dot, psi_E_dot)
    ee = davies_direct(V, A, E, eta_dot, q_dot)
    h = 1e-6
    fd = (
        _planar_fk(eta + h * eta_dot, q + h * q_dot) - _planar_fk(eta - h * eta_dot, q - h * q_dot)
    ) / (2 * h)
    assert np.allclose(ee, fd, atol=1e-6)


def test_kinematic_constraint_inverse_keeps_vehicle_at_rest_and_tracks():
    eta, q = np.zeros(3), np.array([1.47, -1.0, 0.3])
    V, A, E = planar_uvms_screws(eta, q, LINKS, MOUNT)
    ee_rate = np.array([0.3, -0.1, 0.0])
    vehicle = np.array([0.0, 0.0, 0.78 * 1.0])  # at rest, yaw rate toward the current
    qd = kinematic_constraint_inverse(V, A, E, ee_rate, vehicle)
    assert np.allclose(davies_direct(V, A, E, vehicle, qd), ee_rate)
    # the same through the generic Davies solve of Eq. (17)-(18): loop closes
    N = network_matrix(V, A, E)
    psi = np.concatenate([vehicle, qd, ee_rate])
    assert np.allclose(N @ psi, 0.0)
    # SR task priority (Eq. 28) on the same rows moves the vehicle: J = [V, A]
    J = np.hstack([V, A])
    # rows of J map rates to the end-effector twist at the origin: use E^-1 for the ee rates
    Jp = np.linalg.solve(E, J)
    sr = singularity_robust_task_priority(Jp, ee_rate, np.eye(3, 6), np.zeros(3))
    assert np.allclose(Jp @ sr, ee_rate)
    assert np.linalg.norm(sr[:3]) > 1e-3  # the vehicle moves although asked to rest


def test_davies_solve_errors():
    V, A, E = planar_uvms_screws(np.zeros(3), [0.0, 0.0, 0.0], LINKS, MOUNT)  # stretched arm
    with pytest.raises(InputError, match="singular"):
        kinematic_constraint_inverse(V, A, E, [0.1, 0.0, 0.0], [0.0, 0.0, 0.0])
    N = network_matrix(V, A, E)
    with pytest.raises(InputError, match="impose exactly"):
        davies_solve(N, [0, 1], [0.0, 0.0])
    with pytest.raises(InputError, match="distinct"):
        davies_solve(N, [0, 0, 1, 2, 3, 4], np.zeros(6))
    with pytest.raises(ShapeError, match="arm"):
        network_matrix(np.eye(3), np.eye(6), np.eye(3))
    with pytest.raises(ShapeError, match="J_screw"):
        planar_rows(np.eye(3))
