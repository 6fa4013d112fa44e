"""Every frame Jacobian of every bundled model against finite differences through ``integrate``.

Random states include non-zero roll and pitch (spatial vehicles) and any yaw. The reference
twist of a frame is the central difference of its pose along ``q(t) = integrate(q, zeta, t)``:
``v = (p(h) - p(-h)) / 2h`` and ``omega = log(R(h) R(-h)^T) / 2h`` (world axes).
"""

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from uvms_qp import bundled_models

H = 1e-6
TOL = 1e-6


def _fd_twists(model, q, zeta):
    plus = model.state(model.integrate(q, zeta, H))
    minus = model.state(model.integrate(q, -zeta, H))
    out = {}
    for frame in model.frames:
        v = (plus.position(frame) - minus.position(frame)) / (2 * H)
        w = pin.log3(plus.rotation(frame) @ minus.rotation(frame).T) / (2 * H)
        out[frame] = np.concatenate((v, w))
    eta_rate = (model.split(plus.q)[0] - model.split(minus.q)[0]) / (2 * H)
    return out, eta_rate


@pytest.mark.parametrize("name", sorted(bundled_models()))
@settings(max_examples=12)
@given(seed=st.integers(0, 2**32 - 1))
def test_frame_jacobians_match_finite_differences(models, name, seed):
    model = models[name]
    rng = np.random.default_rng(seed)
    q = model.random_configuration(rng, tilt=0.5)
    zeta = rng.uniform(-1.0, 1.0, model.nv)
    state = model.state(q)
    twists, eta_rate = _fd_twists(model, q, zeta)
    for frame, twist in twists.items():
        J = state.jacobian(frame)
        np.testing.assert_allclose(J @ zeta, twist, atol=TOL, err_msg=f"{name}:{frame} world")
        R = state.rotation(frame)
        local = np.concatenate((R.T @ twist[:3], R.T @ twist[3:]))
        np.testing.assert_allclose(
            state.jacobian(frame, axes="local") @ zeta, local, atol=TOL, err_msg=f"{frame} local"
        )
        np.testing.assert_array_equal(state.jacobian(frame, rows="position"), J[:3])
        np.testing.assert_array_equal(state.jacobian(frame, rows="orientation"), J[3:])
        assert J.shape == (6, model.nv)
    if model.eta_size:
        np.testing.assert_allclose(state.vehicle_pose_jacobian() @ zeta, eta_rate, atol=TOL)


@pytest.mark.parametrize("name", sorted(bundled_models()))
def test_arm_jacobian_is_the_joint_columns_in_arm_base_axes(models, name):
    model = models[name]
    rng = np.random.default_rng(7)
    for _ in range(5):
        state = model.state(model.random_configuration(rng))
        R_wb = state.rotation("arm_base")
        for frame in model.frames:
            J = state.jacobian(frame)[:, model.n_vehicle :]
            expected = np.vstack((R_wb.T @ J[:3], R_wb.T @ J[3:]))
            np.testing.assert_allclose(state.arm_jacobian(frame), expected, atol=1e-12)
        assert state.arm_jacobian("tool", rows="position").shape == (3, model.n_joints)


@pytest.mark.parametrize("name", sorted(bundled_models()))
def test_arm_jacobian_matches_finite_differences_of_the_arm_alone(models, name):
    # joint-rate motion with the vehicle still, seen from the arm base
    model = models[name]
    rng = np.random.default_rng(11)
    q = model.random_configuration(rng)
    rates = rng.uniform(-1.0, 1.0, model.n_joints)
    zeta = np.concatenate((np.zeros(model.n_vehicle), rates))
    plus = model.state(model.integrate(q, zeta, H)).pose_in("tool", "arm_base")
    minus = model.state(model.integrate(q, -zeta, H)).pose_in("tool", "arm_base")
    v = (plus[:3, 3] - minus[:3, 3]) / (2 * H)
    w = pin.log3(plus[:3, :3] @ minus[:3, :3].T) / (2 * H)
    J_arm = model.state(q).arm_jacobian("tool")
    np.testing.assert_allclose(J_arm @ rates, np.concatenate((v, w)), atol=TOL)


def test_vehicle_pose_jacobian_is_fossen_for_a_full_spatial_vehicle(models):
    # Wang et al. (2017), Eq. (2)-(3), written out independently
    model = models["bluerov2_heavy_alpha5"]
    phi, theta, psi = 0.3, -0.2, 2.0
    state = model.state(model.configuration([1.0, 2.0, 3.0, phi, theta, psi], model.home()[7:]))
    c, s, t = np.cos, np.sin, np.tan
    J1 = np.array(
        [
            [c(psi) * c(theta), -s(psi) * c(phi) + c(psi) * s(theta) * s(phi),
             s(psi) * s(phi) + c(psi) * c(phi) * s(theta)],
            [s(psi) * c(theta), c(psi) * c(phi) + s(phi) * s(theta) * s(psi),
             -c(psi) * s(phi) + s(theta) * s(psi) * c(phi)],
            [-s(theta), c(theta) * s(phi), c(theta) * c(phi)],
        ]
    )  # fmt: skip
    J2 = np.array(
        [
            [1.0, s(phi) * t(theta), c(phi) * t(theta)],
            [0.0, c(phi), -s(phi)],
            [0.0, s(phi) / c(theta), c(phi) / c(theta)],
        ]
    )
    J_eta = state.vehicle_pose_jacobian()
    np.testing.assert_allclose(J_eta[:3, :3], J1, atol=1e-12)
    np.testing.assert_allclose(J_eta[3:, 3:6], J2, atol=1e-12)
    np.testing.assert_array_equal(J_eta[:, 6:], 0.0)
    np.testing.assert_array_equal(J_eta[:3, 3:6], 0.0)
