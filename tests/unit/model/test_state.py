"""State semantics: cached kinematics, independence of states, conversions, integration."""

import gc
import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import uvms_qp
from tests.support.reference_kinematics import Ref
from uvms_qp import State, bundled_models, load_model
from uvms_qp.model.state import POOL_SIZE
from uvms_qp.model.transforms import (
    matrix_to_rpy,
    quaternion_to_rotation,
    rotation_to_rpy,
    rpy_to_matrix,
    rpy_to_rotation,
)


@pytest.mark.parametrize("name", sorted(bundled_models()))
def test_every_model_has_the_standard_frames_and_consistent_sizes(models, name):
    model = models[name]
    for frame in ("world", "vehicle", "arm_base", "tool"):
        assert frame in model.frames
    assert model.nv == model.n_vehicle + model.n_joints == len(model.zeta_names)
    assert model.zeta_names == model.actuated + model.joint_names
    assert model.joint_lower.shape == model.joint_upper.shape == (model.n_joints,)
    assert model.joint_rate_limit.shape == (model.n_joints,)
    assert model.vehicle_rate_limit.shape == (model.n_vehicle,)
    assert np.all(model.joint_lower <= model.home()[model.nq_vehicle :])
    assert np.all(model.home()[model.nq_vehicle :] <= model.joint_upper)
    assert model.eta_size == {"planar": 3, "spatial": 6, "fixed": 0}[model.vehicle_kind]


def test_interleaved_states_keep_their_own_kinematics():
    model = load_model("wang_9dof")
    rng = np.random.default_rng(1)
    q1, q2 = model.random_configuration(rng), model.random_configuration(rng)
    s1 = model.state(q1)
    s2 = model.state(q2)
    fresh1 = load_model("wang_9dof").state(q1)
    fresh2 = load_model("wang_9dof").state(q2)
    # frames that s1 never asked for before s2 existed
    np.testing.assert_allclose(s1.jacobian("link3"), fresh1.jacobian("link3"), atol=1e-14)
    np.testing.assert_allclose(s2.pose("link4"), fresh2.pose("link4"), atol=1e-14)
    np.testing.assert_allclose(s1.arm_jacobian("link5"), fresh1.arm_jacobian("link5"))
    np.testing.assert_allclose(s2.arm_jacobian("link5"), fresh2.arm_jacobian("link5"))
    np.testing.assert_allclose(s1.pose("tool"), fresh1.pose("tool"), atol=1e-14)


@pytest.mark.parametrize("name", sorted(bundled_models()))
def test_every_quantity_equals_pinocchio_on_a_fresh_data(models, name):
    """Poses, Jacobians, ``eta``, ``J_eta`` and arm quantities against an independent oracle."""
    model = models[name]
    rng = np.random.default_rng(3)
    for _ in range(4):
        q = model.random_configuration(rng)
        state, ref = model.state(q), Ref(model, q)
        np.testing.assert_allclose(state.eta, ref.eta, rtol=0, atol=1e-12)
        np.testing.assert_allclose(state.vehicle_pose_jacobian(), ref.eta_jacobian(), rtol=0,
                                   atol=1e-12)
        T_b = ref.pose("arm_base")
        for frame in model.frames:
            np.testing.assert_allclose(state.pose(frame), ref.pose(frame), atol=1e-13)
            np.testing.assert_allclose(state.jacobian(frame), ref.jacobian(frame), atol=1e-13)
            p = T_b[:3, :3].T @ (ref.pose(frame)[:3, 3] - T_b[:3, 3])
            np.testing.assert_allclose(state.arm_position(frame), p, rtol=0, atol=1e-12)
            np.testing.assert_allclose(state.arm_jacobian(frame), ref.arm_jacobian(frame),
                                       atol=1e-12)


def test_a_value_outlives_its_state():
    """Buffers go back to the model's pool when a state dies: values read before stay put."""
    model = load_model("bluerov2_heavy_alpha5")
    rng = np.random.default_rng(2)
    q1, q2 = model.random_configuration(rng), model.random_configuration(rng)
    kept = {"pose": model.state(q1).pose("tool"), "position": model.state(q1).position("tool"),
            "jacobian": model.state(q1).jacobian("tool"),
            "arm": model.state(q1).arm_position("tool"),
            "arm_jacobian": model.state(q1).arm_jacobian("tool")}
    for _ in range(3):
        other = model.state(q2)  # reuses the pooled buffers
        other.pose("tool"), other.jacobian("tool"), other.arm_jacobian("tool")
        other.arm_position("tool")
    fresh = load_model("bluerov2_heavy_alpha5").state(q1)  # another model: other buffers
    for key, value in kept.items():
        want = {"pose": fresh.pose("tool"), "position": fresh.position("tool"),
                "jacobian": fresh.jacobian("tool"), "arm": fresh.arm_position("tool"),
                "arm_jacobian": fresh.arm_jacobian("tool")}[key]
        np.testing.assert_array_equal(value, want, err_msg=key)


def test_the_pool_reuses_buffers_and_stays_small():
    model = load_model("wang_9dof")
    q = model.home()
    model.state(q).arm_jacobian()
    gc.collect()
    data = model._data_pool[-1]
    state = model.state(q)
    assert state._data is data  # taken from the pool, not built
    states = [model.state(q) for _ in range(3 * POOL_SIZE)]
    assert len({id(s._data) for s in states}) == len(states)  # every live state has its own
    del states, state
    gc.collect()
    assert len(model._data_pool) == POOL_SIZE


def test_rotation_conversions_equal_pinocchio():
    """The one implementation of quaternion / matrix / roll-pitch-yaw against Pinocchio's."""
    rng = np.random.default_rng(0)
    quats = rng.normal(size=(2000, 4))
    quats /= np.linalg.norm(quats, axis=1, keepdims=True)
    for x, y, z, w in quats:
        R_ref = pin.Quaternion(w, x, y, z).toRotationMatrix()
        R = np.array(quaternion_to_rotation(x, y, z, w)).reshape(3, 3)
        np.testing.assert_array_equal(R, R_ref)
        rpy = np.array(rotation_to_rpy(R.ravel().tolist()))
        np.testing.assert_allclose(rpy, pin.rpy.matrixToRpy(R_ref), rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(matrix_to_rpy(R), rpy, rtol=0.0, atol=0.0)
    angles = list(rng.uniform(-math.pi, math.pi, size=(2000, 3)))
    angles += [np.array(a, dtype=float) for a in ((0, 0, 0), (math.pi, 0, 0), (0, math.pi / 2, 0),
                                     (0, -math.pi / 2, math.pi), (1.0, 0.5, -math.pi))]
    for r, p, y in angles:
        R = np.array(rpy_to_rotation(r, p, y)).reshape(3, 3)
        np.testing.assert_allclose(R, pin.rpy.rpyToMatrix(r, p, y), rtol=0.0, atol=1e-15)
        np.testing.assert_array_equal(rpy_to_matrix([r, p, y]), R)


def test_vehicle_pose_jacobian_keeps_the_actuated_columns_of_fossen():
    """``J_eta`` of a 4-DOF vehicle: the u, v, w, r columns of the full transformation."""
    vehicle = uvms_qp.model.Vehicle("spatial", actuated=("u", "v", "w", "r"))
    model = uvms_qp.Model.from_dh([{"a": 0.3}], vehicle=vehicle)
    rng = np.random.default_rng(5)
    for _ in range(5):
        state = model.state(model.random_configuration(rng))
        full = model.vehicle.pose_jacobian(state.eta)
        np.testing.assert_allclose(state.vehicle_pose_jacobian()[:, :4], full[:, [0, 1, 2, 5]],
                                   atol=1e-12)
        assert not state.vehicle_pose_jacobian()[:, 4:].any()


def test_returned_arrays_are_read_only_and_q_is_copied():
    model = load_model("bluerov2_heavy_alpha5")
    q = model.home()
    state = State(model, q)
    q[0] = 100.0  # the caller's array is not the state's
    assert state.q[0] == 0.0
    for array in (state.q, state.pose("tool"), state.jacobian("tool"), state.arm_jacobian(),
                  state.eta, state.joints, state.vehicle_pose_jacobian(),
                  state.arm_position("tool"), state.position("tool"),
                  state.pose_in("tool", "vehicle")):  # fmt: skip
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 1.0
    assert state.jacobian("tool") is state.jacobian("tool")  # cached, not recomputed


@settings(max_examples=25)
@given(
    eta=st.tuples(
        st.floats(-5, 5), st.floats(-5, 5), st.floats(-5, 5),
        st.floats(-3.1, 3.1), st.floats(-1.5, 1.5), st.floats(-3.1, 3.1),
    )
)  # fmt: skip
def test_configuration_split_round_trip_spatial(models, eta):
    model = models["bluerov2_heavy_alpha5"]
    joints = model.home()[7:]
    q = model.configuration(eta, joints)
    eta2, joints2 = model.split(q)
    np.testing.assert_allclose(eta2, eta, atol=1e-9)
    np.testing.assert_allclose(joints2, joints)
    state = model.state(q)
    np.testing.assert_allclose(state.eta, eta, atol=1e-9)
    np.testing.assert_array_equal(state.joints, joints)


def test_integrate_moves_the_vehicle_along_its_body_axes(models):
    model = models["bluerov2_heavy_alpha5"]
    psi = math.radians(90.0)
    q = model.configuration([0, 0, 0, 0, 0, psi], model.home()[7:])
    zeta = np.zeros(model.nv)
    zeta[0] = 1.0  # surge 1 m/s while heading east
    eta, _ = model.split(model.integrate(q, zeta, 2.0))
    np.testing.assert_allclose(eta, [0, 2.0, 0, 0, 0, psi], atol=1e-12)
    zeta[:] = 0.0
    zeta[2] = 0.5  # heave: body z is down in FRD and NED
    eta, _ = model.split(model.integrate(q, zeta, 2.0))
    np.testing.assert_allclose(eta[:3], [0, 0, 1.0], atol=1e-12)
    zeta[:] = 0.0
    zeta[6 + 1] = 0.25  # axis_d rate
    _, joints = model.split(model.integrate(q, zeta, 2.0))
    np.testing.assert_allclose(joints - model.home()[7:], [0, 0.5, 0, 0], atol=1e-15)


def test_planar_integration_is_exact_for_constant_body_rates(models):
    model = models["soylu_planar"]
    q = model.configuration([0, 0, 0], [0, 0, 0])
    zeta = np.array([1.0, 0.0, math.pi / 2, 0, 0, 0])  # drive a quarter circle of radius 2/pi
    eta, _ = model.split(model.integrate(q, zeta, 1.0))
    r = 2 / math.pi
    np.testing.assert_allclose(eta, [r, r, math.pi / 2], atol=1e-12)


def test_pose_in_and_frame_pose_agree(models):
    model = models["wang_9dof"]
    q = model.random_configuration(4)
    state = model.state(q)
    T_ref, T = state.pose("link2"), state.pose("tool")
    np.testing.assert_allclose(state.pose_in("tool", "link2"), np.linalg.inv(T_ref) @ T, atol=1e-12)
    np.testing.assert_allclose(model.frame_pose(q, "tool"), T)
    np.testing.assert_allclose(state.position("tool"), T[:3, 3])
    np.testing.assert_allclose(state.rotation("tool"), T[:3, :3])


def test_neutral_and_fixed_base_layout(models):
    arm = models["nenchev_pa10_arm"]
    assert arm.nq == arm.nv == arm.n_joints == 4
    assert arm.vehicle_kind == "fixed" and arm.actuated == () and arm.eta_size == 0
    state = arm.state(arm.neutral())
    np.testing.assert_array_equal(state.pose("vehicle"), np.eye(4))
    assert state.vehicle_pose_jacobian().shape == (0, 4)
    assert state.eta.shape == (0,)
    rov = models["bluerov2_heavy_alpha5"]
    np.testing.assert_allclose(rov.neutral()[3:7], [0, 0, 0, 1])


def test_public_surface_is_reachable_from_the_package(models):
    assert uvms_qp.Model is type(models["soylu_planar"])
    assert uvms_qp.load_model("soylu_planar").name == "soylu_planar"
    assert uvms_qp.bundled_models() == [
        "soylu_planar", "santos_planar", "wang_9dof", "nenchev_pa10_arm", "bluerov2_heavy_alpha5",
    ]  # fmt: skip
    assert "soylu_planar" in repr(models["soylu_planar"])
