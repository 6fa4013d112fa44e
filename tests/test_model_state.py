"""State semantics: cached kinematics, independence of states, conversions, integration."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import uvms_qp
from uvms_qp import State, bundled_models, load_model

MODELS = {name: load_model(name) for name in bundled_models()}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_every_model_has_the_standard_frames_and_consistent_sizes(name):
    model = MODELS[name]
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
    s2 = model.state(q2)  # takes over the model's Pinocchio buffers
    fresh1 = load_model("wang_9dof").state(q1)
    fresh2 = load_model("wang_9dof").state(q2)
    # frames that s1 never asked for before s2 existed
    np.testing.assert_allclose(s1.jacobian("link3"), fresh1.jacobian("link3"), atol=1e-14)
    np.testing.assert_allclose(s2.pose("link4"), fresh2.pose("link4"), atol=1e-14)
    np.testing.assert_allclose(s1.arm_jacobian("link5"), fresh1.arm_jacobian("link5"))
    np.testing.assert_allclose(s2.arm_jacobian("link5"), fresh2.arm_jacobian("link5"))
    np.testing.assert_allclose(s1.pose("tool"), fresh1.pose("tool"), atol=1e-14)


def test_returned_arrays_are_read_only_and_q_is_copied():
    model = load_model("bluerov2_heavy_alpha5")
    q = model.home()
    state = State(model, q)
    q[0] = 100.0  # the caller's array is not the state's
    assert state.q[0] == 0.0
    for array in (state.q, state.pose("tool"), state.jacobian("tool"), state.arm_jacobian(),
                  state.eta, state.joints):  # fmt: skip
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
def test_configuration_split_round_trip_spatial(eta):
    model = MODELS["bluerov2_heavy_alpha5"]
    joints = model.home()[7:]
    q = model.configuration(eta, joints)
    eta2, joints2 = model.split(q)
    np.testing.assert_allclose(eta2, eta, atol=1e-9)
    np.testing.assert_allclose(joints2, joints)
    state = model.state(q)
    np.testing.assert_allclose(state.eta, eta, atol=1e-9)
    np.testing.assert_array_equal(state.joints, joints)


def test_integrate_moves_the_vehicle_along_its_body_axes():
    model = MODELS["bluerov2_heavy_alpha5"]
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


def test_planar_integration_is_exact_for_constant_body_rates():
    model = MODELS["soylu_planar"]
    q = model.configuration([0, 0, 0], [0, 0, 0])
    zeta = np.array([1.0, 0.0, math.pi / 2, 0, 0, 0])  # drive a quarter circle of radius 2/pi
    eta, _ = model.split(model.integrate(q, zeta, 1.0))
    r = 2 / math.pi
    np.testing.assert_allclose(eta, [r, r, math.pi / 2], atol=1e-12)


def test_pose_in_and_frame_pose_agree():
    model = MODELS["wang_9dof"]
    q = model.random_configuration(4)
    state = model.state(q)
    T_ref, T = state.pose("link2"), state.pose("tool")
    np.testing.assert_allclose(state.pose_in("tool", "link2"), np.linalg.inv(T_ref) @ T, atol=1e-12)
    np.testing.assert_allclose(model.frame_pose(q, "tool"), T)
    np.testing.assert_allclose(state.position("tool"), T[:3, 3])
    np.testing.assert_allclose(state.rotation("tool"), T[:3, :3])


def test_neutral_and_fixed_base_layout():
    arm = MODELS["nenchev_pa10_arm"]
    assert arm.nq == arm.nv == arm.n_joints == 4
    assert arm.vehicle_kind == "fixed" and arm.actuated == () and arm.eta_size == 0
    state = arm.state(arm.neutral())
    np.testing.assert_array_equal(state.pose("vehicle"), np.eye(4))
    assert state.vehicle_pose_jacobian().shape == (0, 4)
    assert state.eta.shape == (0,)
    rov = MODELS["bluerov2_heavy_alpha5"]
    np.testing.assert_allclose(rov.neutral()[3:7], [0, 0, 0, 1])


def test_public_surface_is_reachable_from_the_package():
    assert uvms_qp.Model is type(MODELS["soylu_planar"])
    assert uvms_qp.load_model("soylu_planar").name == "soylu_planar"
    assert uvms_qp.bundled_models() == [
        "soylu_planar", "santos_planar", "wang_9dof", "nenchev_pa10_arm", "bluerov2_heavy_alpha5",
    ]  # fmt: skip
    assert "soylu_planar" in repr(MODELS["soylu_planar"])
