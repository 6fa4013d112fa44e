"""Plain-float fast paths of the state update equal the Pinocchio reference computations.

``Vehicle.eta_values`` / ``State.eta`` and ``State.vehicle_pose_jacobian`` avoid building
Pinocchio objects every tick; these tests compare them with the matrix forms they replace
(``pin.Quaternion(...).toRotationMatrix()``, ``pin.rpy.matrixToRpy``, ``pin.rpy.rpyToMatrix``).
"""

import math

import numpy as np
import pinocchio as pin
import pytest

from uvms_qp import bundled_models, load_model
from uvms_qp.model import Model, Vehicle
from uvms_qp.model.vehicle import quaternion_to_rotation, rotation_to_rpy, rpy_to_rotation

MODELS = {name: load_model(name) for name in bundled_models()}


def _unit_quaternions(rng, n):
    """Random unit quaternions plus the special ones (zero components, half turns)."""
    quats = [q / np.linalg.norm(q) for q in rng.normal(size=(n, 4))]
    for q in rng.normal(size=(n // 4, 4)):
        q[rng.integers(4)] = 0.0
        quats.append(q / np.linalg.norm(q))
    s = math.sqrt(0.5)
    quats += [np.array(v, dtype=float) for v in (
        (0, 0, 0, 1), (1, 0, 0, 0), (0, 1, 0, 0), (0, 0, 1, 0), (0, s, 0, s), (0, -s, 0, s),
        (s, 0, 0, s), (0, 0, s, s), (0.5, 0.5, 0.5, 0.5))]
    return quats


def _reference_pose_jacobian(eta):
    """Fossen's ``blkdiag(R(Theta), T(Theta))`` through Pinocchio's rpyToMatrix."""
    phi, theta, psi = eta[3], eta[4], eta[5]
    J = np.zeros((6, 6))
    J[:3, :3] = pin.rpy.rpyToMatrix(phi, theta, psi)
    sphi, cphi = math.sin(phi), math.cos(phi)
    ctheta, ttheta = math.cos(theta), math.tan(theta)
    J[3:, 3:] = ((1.0, sphi * ttheta, cphi * ttheta), (0.0, cphi, -sphi),
                 (0.0, sphi / ctheta, cphi / ctheta))
    return J


def test_quaternion_rotation_and_rpy_equal_pinocchio():
    rng = np.random.default_rng(0)
    for x, y, z, w in _unit_quaternions(rng, 2000):
        R_ref = pin.Quaternion(w, x, y, z).toRotationMatrix()
        R = np.array(quaternion_to_rotation(x, y, z, w)).reshape(3, 3)
        np.testing.assert_array_equal(R, R_ref)
        rpy_ref = pin.rpy.matrixToRpy(R_ref)
        rpy = np.array(rotation_to_rpy(R.ravel().tolist()))
        # same operations as Pinocchio; a tolerance only in case a future Eigen reorders them
        np.testing.assert_allclose(rpy, rpy_ref, rtol=0.0, atol=1e-12)
        np.testing.assert_allclose(pin.rpy.rpyToMatrix(*rpy), R_ref, atol=1e-12)


def test_rpy_to_rotation_equals_pinocchio():
    rng = np.random.default_rng(1)
    angles = list(rng.uniform(-math.pi, math.pi, size=(2000, 3)))
    angles += [np.array(a, dtype=float) for a in ((0, 0, 0), (math.pi, 0, 0), (0, math.pi / 2, 0),
                                     (0, -math.pi / 2, math.pi), (1.0, 0.5, -math.pi))]
    for r, p, y in angles:
        np.testing.assert_allclose(np.array(rpy_to_rotation(r, p, y)).reshape(3, 3),
                                   pin.rpy.rpyToMatrix(r, p, y), rtol=0.0, atol=1e-15)


@pytest.mark.parametrize("name", sorted(MODELS))
def test_state_eta_and_pose_jacobian_equal_the_matrix_forms(name):
    model = MODELS[name]
    rng = np.random.default_rng(2)
    for _ in range(50):
        q = model.random_configuration(rng)
        state = model.state(q)
        qv = state.q[: model.nq_vehicle]
        if model.vehicle_kind == "spatial":
            R = pin.Quaternion(qv[6], qv[3], qv[4], qv[5]).toRotationMatrix()
            eta_ref = np.concatenate((qv[:3], pin.rpy.matrixToRpy(R)))
            full = _reference_pose_jacobian(eta_ref)
        elif model.vehicle_kind == "planar":
            eta_ref = np.array([qv[0], qv[1], math.atan2(qv[3], qv[2])])
            c, s = math.cos(eta_ref[2]), math.sin(eta_ref[2])
            full = np.array(((c, -s, 0.0), (s, c, 0.0), (0.0, 0.0, 1.0)))
        else:
            eta_ref = np.zeros(0)
            full = np.zeros((0, 0))
        np.testing.assert_allclose(state.eta, eta_ref, rtol=0.0, atol=1e-12)
        J_ref = np.zeros((model.eta_size, model.nv))
        J_ref[:, : model.n_vehicle] = full[:, list(model.vehicle.actuated_indices)]
        J = state.vehicle_pose_jacobian()
        np.testing.assert_allclose(J, J_ref, rtol=0.0, atol=1e-14)
        np.testing.assert_allclose(model.vehicle.pose_jacobian(state.eta), full,
                                   rtol=0.0, atol=1e-14)
        assert J is state.vehicle_pose_jacobian()  # computed once per state
        assert not J.flags.writeable


def test_pose_jacobian_of_a_vehicle_with_passive_roll_and_pitch_keeps_actuated_columns():
    model = Model.from_dh([{"a": 0.5, "alpha": 0.0, "d": 0.0, "theta": 0.0}],
                          vehicle=Vehicle("spatial", actuated=("u", "v", "w", "r")))
    q = model.configuration([0.1, -0.2, 0.3, 0.2, -0.3, 1.0], [0.4])
    state = model.state(q)
    full = _reference_pose_jacobian(state.eta)
    np.testing.assert_allclose(state.vehicle_pose_jacobian()[:, :4], full[:, [0, 1, 2, 5]],
                               atol=1e-14)
    assert not state.vehicle_pose_jacobian()[:, 4:].any()
