"""BlueROV2 Heavy + Reach Alpha 5 against an independent reading of the public facts.

The reference chain below is written from the facts table (joint origins xyz/rpy, axes, ROS FLU
body frame) with plain numpy, and converted to the FRD body frame by hand.
"""

import math

import numpy as np
import pytest

from uvms_qp import load_model
from uvms_qp.model.bundled import bluerov2_heavy_alpha5, bluerov2_urdf_path

# (child link, joint name or None for fixed, origin xyz, origin rpy, axis)
FACTS = [
    ("m3_inline_link", None, (0, 0, 0), (0, 0, 0), None),
    ("m2_1_1_link", "axis_e", (0, 0, 0.014), (0, 0, 0), (0, 0, 1)),
    ("m2_joint_link", "axis_d", (-0.02, 0, 0.033), (0, 0, 0), (0, 1, 0)),
    ("m2_1_2_link", "axis_c", (-0.04, 0, -0.1453), (0, 0, 3.14159), (0, 1, 0)),
    ("m1_link", "axis_b", (0.02, 0, 0.033), (0, 0, 2.09439), (0, 0, -1)),
    ("jaws_base_link", None, (0, 0, 0.09975), (0, 0, 0), None),
]
MOUNT_FLU = (0.24, -0.099, 0.029)
LIMITS = {"axis_e": 6.3, "axis_d": 3.8, "axis_c": 3.5, "axis_b": 6.2}


def _rot(axis, angle):
    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _rpy(r, p, y):
    return _rot((0, 0, 1), y) @ _rot((0, 1, 0), p) @ _rot((1, 0, 0), r)


def _pose(R, p):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def _reference(eta, joints):
    """Link poses and joint axes (world) from the facts; FLU -> FRD done by hand."""
    T = _pose(_rpy(*eta[3:]), eta[:3])  # world NED <- body FRD
    flu_in_frd = _pose(np.diag([1.0, -1.0, -1.0]), np.zeros(3))  # FRD <- FLU, same origin
    T = T @ flu_in_frd @ _pose(np.eye(3), MOUNT_FLU)  # arm base_link, mount rpy = 0
    poses, axes = {"base_link": T}, {}
    angles = dict(zip(["axis_e", "axis_d", "axis_c", "axis_b"], joints, strict=True))
    for child, joint, xyz, rpy, axis in FACTS:
        T = T @ _pose(_rpy(*rpy), xyz)
        if joint is not None:
            axes[joint] = (T[:3, :3] @ np.asarray(axis, float), T[:3, 3].copy())
            T = T @ _pose(_rot(axis, angles[joint]), np.zeros(3))
        poses[child] = T
    return poses, axes


def test_model_layout_matches_the_facts():
    model = load_model("bluerov2_heavy_alpha5")
    assert model.joint_names == ("axis_e", "axis_d", "axis_c", "axis_b")
    assert model.actuated == ("u", "v", "w", "p", "q", "r")
    assert (model.n_vehicle, model.n_joints, model.nv, model.nq) == (6, 4, 10, 11)
    np.testing.assert_allclose(model.joint_lower, 0.0)
    np.testing.assert_allclose(model.joint_upper, [LIMITS[j] for j in model.joint_names])
    np.testing.assert_allclose(model.joint_rate_limit, 0.5)
    assert model.vehicle_rate_limit[0] == 1.5
    # the published FLU mount (0.24, -0.099, 0.029) is (0.24, 0.099, -0.029) in FRD: the arm
    # base is starboard of and above the body origin, its z axis pointing up
    np.testing.assert_allclose(model.mount[:3, 3], [0.24, 0.099, -0.029])
    np.testing.assert_allclose(model.mount[:3, :3], np.diag([1.0, -1.0, -1.0]), atol=1e-15)
    assert bluerov2_urdf_path().is_file()


def test_forward_kinematics_matches_the_facts_chain():
    model = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng(5)
    for _ in range(10):
        eta = np.concatenate(
            (rng.uniform(-2, 2, 3), rng.uniform(-0.5, 0.5, 2), [rng.uniform(-3, 3)])
        )
        joints = rng.uniform(model.joint_lower, model.joint_upper)
        state = model.state(model.configuration(eta, joints))
        poses, _ = _reference(eta, joints)
        for link, T in poses.items():
            np.testing.assert_allclose(state.pose(link), T, atol=1e-12, err_msg=link)
        np.testing.assert_allclose(state.pose("tool"), poses["jaws_base_link"], atol=1e-12)
        np.testing.assert_allclose(state.pose("arm_base"), poses["base_link"], atol=1e-12)


def test_each_joint_turns_the_tool_about_its_stated_axis():
    # column k of the tool Jacobian is the screw of joint k: omega = axis (world), and the
    # tool origin moves as axis x (p_tool - p_joint)
    model = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng(8)
    eta = np.array([0.5, -0.3, 2.0, 0.2, -0.3, 1.0])
    joints = rng.uniform(model.joint_lower, model.joint_upper)
    state = model.state(model.configuration(eta, joints))
    _, axes = _reference(eta, joints)
    p_tool = state.position("tool")
    J = state.jacobian("tool")
    for k, name in enumerate(model.joint_names):
        axis, point = axes[name]
        np.testing.assert_allclose(J[3:, 6 + k], axis, atol=1e-12, err_msg=name)
        np.testing.assert_allclose(J[:3, 6 + k], np.cross(axis, p_tool - point), atol=1e-12)


def test_axis_e_points_up_on_a_level_vehicle():
    # FLU z up is FRD -z: on a level vehicle axis_e turns the arm about the world up axis
    model = load_model("bluerov2_heavy_alpha5")
    state = model.state(model.home())
    assert state.jacobian("tool")[3:, 6] == pytest.approx([0.0, 0.0, -1.0], abs=1e-12)


def test_home_reaches_forward_within_limits():
    model = load_model("bluerov2_heavy_alpha5")
    joints = model.home()[7:]
    assert np.all(joints >= model.joint_lower) and np.all(joints <= model.joint_upper)
    reach = model.state(model.home()).pose_in("tool", "arm_base")[:3, 3]
    assert reach[0] > 0.2  # ahead of the arm base
    assert np.linalg.norm(reach) < 0.45  # the Alpha 5 reaches about 0.4 m


def test_mount_is_a_parameter():
    default = bluerov2_heavy_alpha5()
    shifted_mount = default.mount.copy()
    shifted_mount[:3, 3] += (0.1, 0.0, 0.05)
    shifted = bluerov2_heavy_alpha5(mount=shifted_mount)
    q = default.home()
    delta = shifted.frame_pose(q, "tool")[:3, 3] - default.frame_pose(q, "tool")[:3, 3]
    np.testing.assert_allclose(delta, [0.1, 0.0, 0.05], atol=1e-12)
