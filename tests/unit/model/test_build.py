"""Model construction: DH (both conventions) versus URDF, mounts, vehicles, tool offsets."""

import math

import numpy as np
import pinocchio as pin
import pytest

from uvms_qp import Model
from uvms_qp.model import DHRow, Vehicle, transform

# --- an independent DH -> URDF writer (own matrices, own rpy extraction) ---------------------


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _trans(x, y, z):
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def _origin(T):
    R = T[:3, :3]
    pitch = math.asin(-R[2, 0])
    roll = math.atan2(R[2, 1], R[2, 2])
    yaw = math.atan2(R[1, 0], R[0, 0])
    x, y, z = (float(v) for v in T[:3, 3])
    return f'<origin xyz="{x!r} {y!r} {z!r}" rpy="{roll!r} {pitch!r} {yaw!r}"/>'


def _urdf_from_dh(rows, convention, tool):
    """URDF whose link i frame is DH frame i; joint i sits at the frame where it moves."""
    links = ['<link name="base"/>']
    joints = []
    previous = np.eye(4)  # constant transform from the previous link frame to the joint frame
    for i, (a, alpha, d, theta) in enumerate(rows, start=1):
        if convention == "standard":  # Rz(theta + q) Tz(d) Tx(a) Rx(alpha)
            to_joint, after = _rz(theta), _trans(0, 0, d) @ _trans(a, 0, 0) @ _rx(alpha)
        else:  # Rx(alpha) Tx(a) Rz(theta + q) Tz(d)
            to_joint, after = _rx(alpha) @ _trans(a, 0, 0) @ _rz(theta), _trans(0, 0, d)
        parent = "base" if i == 1 else f"l{i - 1}"
        links += [f'<link name="j{i}_frame"/>', f'<link name="l{i}"/>']
        joints.append(
            f'<joint name="q{i}" type="revolute"><parent link="{parent}"/>'
            f'<child link="j{i}_frame"/>{_origin(previous @ to_joint)}<axis xyz="0 0 1"/>'
            f'<limit lower="-3" upper="3" velocity="2" effort="1"/></joint>'
        )
        joints.append(
            f'<joint name="f{i}" type="fixed"><parent link="j{i}_frame"/>'
            f'<child link="l{i}"/>{_origin(after)}</joint>'
        )
        previous = np.eye(4)
    n = len(rows)
    links.append('<link name="tip"/>')
    joints.append(
        f'<joint name="ft" type="fixed"><parent link="l{n}"/><child link="tip"/>'
        f"{_origin(tool)}</joint>"
    )
    return '<?xml version="1.0"?><robot name="dh">' + "".join(links + joints) + "</robot>"


STANDARD = [(0.1, math.pi / 2, 0.3, 0.2), (0.5, 0.0, -0.1, -0.4), (0.4, -math.pi / 2, 0.05, 0.0)]
MODIFIED = [(0.0, 0.0, 0.1, 0.0), (0.2, math.pi / 2, 0.0, 0.3), (0.45, 0.0, 0.07, -0.2)]


@pytest.mark.parametrize(("convention", "rows"), [("standard", STANDARD), ("modified", MODIFIED)])
@pytest.mark.parametrize("vehicle", ["spatial", "planar", "fixed"])
def test_dh_arm_and_equivalent_urdf_agree(tmp_path, convention, rows, vehicle):
    tool = transform((0.0, 0.02, 0.11), (0.1, 0.0, -0.3))
    mount = transform((0.3, -0.1, 0.2), (math.pi, 0.0, 0.4))
    path = tmp_path / f"dh_{convention}.urdf"
    path.write_text(_urdf_from_dh(rows, convention, tool))
    dh = Model.from_dh(
        [DHRow(a=a, alpha=al, d=d, theta=th, name=f"q{i}") for i, (a, al, d, th) in
         enumerate(rows, start=1)],
        convention,
        vehicle=vehicle,
        mount=mount,
        tool=tool,
    )  # fmt: skip
    urdf = Model.from_urdf(path, vehicle=vehicle, mount=mount, tool="tip")
    assert dh.nq == urdf.nq and dh.nv == urdf.nv
    assert dh.joint_names == urdf.joint_names == ("q1", "q2", "q3")
    rng = np.random.default_rng(3)
    for _ in range(10):
        q = dh.random_configuration(rng)
        a, b = dh.state(q), urdf.state(q)
        for i in (1, 2, 3):  # DH frame i is URDF link l<i>
            np.testing.assert_allclose(a.pose(f"link{i}"), b.pose(f"l{i}"), atol=1e-12)
        for frame in ("tool", "arm_base", "vehicle"):
            np.testing.assert_allclose(a.pose(frame), b.pose(frame), atol=1e-12)
            np.testing.assert_allclose(a.jacobian(frame), b.jacobian(frame), atol=1e-12)
        np.testing.assert_allclose(a.arm_jacobian(), b.arm_jacobian(), atol=1e-12)
    np.testing.assert_allclose(urdf.joint_lower, -3.0)
    np.testing.assert_allclose(urdf.joint_rate_limit, 2.0)


def test_standard_and_modified_tables_of_one_planar_arm_agree():
    links = (1.0, 0.7, 0.4)
    standard = Model.from_dh([DHRow(a=l) for l in links], "standard", vehicle="fixed")
    modified = Model.from_dh(
        [DHRow(a=0.0), DHRow(a=links[0]), DHRow(a=links[1]), DHRow(a=links[2], kind="fixed")],
        "modified",
        vehicle="fixed",
    )
    assert modified.n_joints == 3
    for joints in ([0.0, 0.0, 0.0], [0.3, -1.2, 2.0], [-2.0, 0.5, 0.1]):
        q = standard.configuration([], joints)
        np.testing.assert_allclose(
            standard.frame_pose(q, "tool"), modified.frame_pose(q, "tool"), atol=1e-12
        )
        c = np.cumsum(joints)
        expected = [np.dot(links, np.cos(c)), np.dot(links, np.sin(c)), 0.0]
        assert standard.frame_pose(q, "tool")[:3, 3] == pytest.approx(expected, abs=1e-12)


def test_prismatic_dh_joint_moves_along_z():
    for convention in ("standard", "modified"):
        model = Model.from_dh(
            [DHRow(kind="prismatic", d=0.2, lower=0.0, upper=0.5)], convention, vehicle="fixed"
        )
        for extension in (0.0, 0.3):
            q = model.configuration([], [extension])
            assert model.frame_pose(q, "tool")[:3, 3] == pytest.approx([0, 0, 0.2 + extension])
        assert model.joint_upper[0] == 0.5


def test_mount_moves_the_arm_rigidly_with_the_vehicle():
    rows = [DHRow(a=0.5), DHRow(a=0.3, alpha=math.pi / 2)]
    mount = transform((0.4, 0.1, 0.25), (0.0, 0.3, -0.5))
    a = Model.from_dh(rows, vehicle="spatial")
    b = Model.from_dh(rows, vehicle="spatial", mount=mount)
    q = a.configuration([1.0, -2.0, 0.5, 0.2, -0.1, 1.3], [0.4, -0.7])
    T_wv = b.frame_pose(q, "vehicle")
    np.testing.assert_allclose(b.frame_pose(q, "arm_base"), T_wv @ mount, atol=1e-12)
    # tool relative to the arm base does not depend on the mount
    np.testing.assert_allclose(
        b.state(q).pose_in("tool", "arm_base"), a.state(q).pose_in("tool", "arm_base"), atol=1e-12
    )
    np.testing.assert_allclose(b.mount, mount)


def test_vehicle_frame_follows_eta_in_ned():
    model = Model.from_dh([DHRow(a=1.0)], vehicle="spatial")
    eta = [1.0, 2.0, 3.0, 0.1, -0.2, 0.3]
    T = model.frame_pose(model.configuration(eta, [0.0]), "vehicle")
    cr, sr, cp, sp, cy, sy = (f(a) for a in eta[3:] for f in (math.cos, math.sin))
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    np.testing.assert_allclose(T[:3, :3], Rz @ Ry @ Rx, atol=1e-12)
    np.testing.assert_allclose(T[:3, 3], eta[:3])


def test_partially_actuated_vehicle_selects_columns():
    vehicle = Vehicle("spatial", actuated=("r", "u", "w", "v"), rate_limit=(1.0, 1.0, 0.5, 0.3))
    model = Model.from_dh([DHRow(a=1.0), DHRow(a=1.0)], vehicle=vehicle)
    assert model.actuated == ("u", "v", "w", "r")  # nu order
    assert model.passive == ("p", "q")
    assert model.zeta_names == ("u", "v", "w", "r", "joint1", "joint2")
    assert (model.nq, model.nv, model.n_vehicle, model.eta_size) == (9, 6, 4, 6)
    np.testing.assert_allclose(model.vehicle_rate_limit, [1.0, 1.0, 0.5, 0.3])
    q = model.configuration([0.0, 0.0, 0.0, 0.2, -0.1, 0.5], [0.3, 0.4])
    zeta = np.array([0.3, -0.2, 0.1, 0.8, 0.5, -0.4])
    moved = model.integrate(q, zeta, 0.7)
    # passive p = q = 0: over the step the body turns about its own z axis only
    R0 = model.frame_pose(q, "vehicle")[:3, :3]
    R1 = model.frame_pose(moved, "vehicle")[:3, :3]
    step = R0.T @ R1
    assert step[2, 2] == pytest.approx(1.0, abs=1e-12)
    assert math.atan2(step[1, 0], step[0, 0]) == pytest.approx(0.8 * 0.7, abs=1e-12)
    # the Jacobian over zeta is Pinocchio's full Jacobian without the p and q columns
    state = model.state(q)
    data = model.pin_model.createData()
    pin.computeJointJacobians(model.pin_model, data, state.q)
    full = pin.getFrameJacobian(
        model.pin_model, data, model.frame_id("tool"), pin.LOCAL_WORLD_ALIGNED
    )
    np.testing.assert_array_equal(state.jacobian("tool"), full[:, [0, 1, 2, 5, 6, 7]])


def test_planar_vehicle_model_layout():
    model = Model.from_dh([DHRow(a=1.0)], vehicle="planar")
    assert (model.nq, model.nv, model.eta_size, model.actuated) == (5, 4, 3, ("u", "v", "r"))
    q = model.configuration([1.0, 2.0, 3.0], [0.5])
    np.testing.assert_allclose(q[:4], [1.0, 2.0, math.cos(3.0), math.sin(3.0)])
    eta, joints = model.split(q)
    np.testing.assert_allclose(eta, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(joints, [0.5])


def test_dh_limits_and_names_from_rows_and_overrides():
    rows = [
        {"a": 1.0, "lower": -1.0, "upper": 2.0, "rate_limit": 0.5, "name": "shoulder"},
        {"a": 1.0, "name": "elbow"},
    ]
    model = Model.from_dh(rows, vehicle="fixed")
    assert model.joint_names == ("shoulder", "elbow")
    np.testing.assert_allclose(model.joint_lower, [-1.0, -np.inf])
    np.testing.assert_allclose(model.joint_rate_limit, [0.5, np.inf])
    override = Model.from_dh(
        rows, vehicle="fixed", joint_names=["a1", "a2"], joint_upper=[1.0, 1.5]
    )
    assert override.joint_names == ("a1", "a2")
    np.testing.assert_allclose(override.joint_upper, [1.0, 1.5])
    assert override.joint_index("a2") == 1
