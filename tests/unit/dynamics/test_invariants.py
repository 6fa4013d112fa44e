"""Invariants of the floating plant, measured with references written apart from it.

Momentum of the whole chain with added mass (constant without external forces: catches a wrong
added-mass Coriolis term, which energy cannot), kinetic energy with the arm still, mechanical
energy that damping never increases, the servos' work, the mass matrix, Galilean invariance in
a current. The momentum, energies, mass matrix and restoring wrench of the references are sums
over the bodies (``tests/support/floating.py``).
"""

import numpy as np
import pinocchio as pin
import pytest

from tests.support import floating as ref
from tests.support.floating import run
from uvms_qp.dynamics import FloatingPlant


def _no_forces(params):
    return params.with_changes(gravity=0.0).scaled({
        "vehicle.linear_damping": 0.0, "vehicle.quadratic_damping": 0.0,
        "links.linear_damping": 0.0, "links.quadratic_damping": 0.0})


def _sweep(t):
    return 0.4 * np.sin(np.array([1.1, 1.7, 2.3, 2.9]) * t + np.array([0.0, 0.5, 1.0, 1.5]))


@pytest.fixture
def moving_start(rov):
    rng = np.random.default_rng(7)
    q = rov.configuration([0.2, -0.1, 0.3, 0.2, -0.3, 0.5], rov.home()[7:])
    v = np.concatenate((rng.normal(size=6) * 0.3, rng.normal(size=4) * 0.2))
    return q, v


def test_momentum_of_the_chain_with_added_mass_is_constant_while_the_arm_moves(rov, heavy,
                                                                               moving_start):
    params = _no_forces(heavy)
    plant = FloatingPlant(rov, params)
    q, v = moving_start
    start = ref.world_momentum(rov, params, q, v)
    np.testing.assert_allclose(plant.momentum(q, v), start, rtol=1e-12, atol=1e-12)
    drift = []
    q_end, _ = run(plant, q, v, 3.0, reference=_sweep, observe=lambda t, q, v: drift.append(
        np.abs(ref.world_momentum(rov, params, q, v) - start).max()))
    assert max(drift) < 1e-7 * np.abs(start).max()
    assert np.abs(q_end[7:] - q[7:]).max() > 0.3  # the arm moved


def test_momentum_drift_shrinks_at_fourth_order(rov, heavy, moving_start):
    params = _no_forces(heavy)
    plant = FloatingPlant(rov, params)
    q, v = moving_start
    start = ref.world_momentum(rov, params, q, v)
    drifts = []
    for dt in (0.02, 0.01):
        qe, ve = run(plant, q, v, 2.0, reference=_sweep, dt=dt)
        drifts.append(np.abs(ref.world_momentum(rov, params, qe, ve) - start).max())
    assert drifts[0] / drifts[1] > 12.0  # 2^4 = 16 for a fourth-order scheme


def test_kinetic_energy_is_constant_when_the_arm_is_still(rov, heavy, moving_start):
    params = _no_forces(heavy)
    plant = FloatingPlant(rov, params)
    q, v = moving_start
    v = v.copy()
    v[6:] = 0.0
    start = ref.kinetic_energy(rov, params, q, v)
    assert plant.kinetic_energy(q, v) == pytest.approx(start, rel=1e-12)
    values = []
    run(plant, q, v, 3.0, observe=lambda t, q, v: values.append(
        ref.kinetic_energy(rov, params, q, v)))
    assert max(abs(e - start) for e in values) < 1e-9 * start


def test_with_damping_and_no_thrust_the_mechanical_energy_never_increases(rov, heavy):
    plant = FloatingPlant(rov, heavy)
    q = rov.configuration([0, 0, 0, 0.4, -0.3, 0.2], rov.home()[7:])
    v = np.array([0.4, -0.3, 0.2, 0.5, -0.4, 0.3, 0, 0, 0, 0])

    def energy(q, v):
        return ref.kinetic_energy(rov, heavy, q, v) + ref.potential_energy(rov, heavy, q)

    assert plant.potential_energy(q) == pytest.approx(ref.potential_energy(rov, heavy, q),
                                                      rel=1e-12, abs=1e-12)
    values = [energy(q, v)]
    run(plant, q, v, 4.0, observe=lambda t, q, v: values.append(energy(q, v)))
    steps = np.diff(values)
    assert steps.max() <= 1e-9
    assert values[-1] < values[0] - 0.1  # damping took energy out


def test_the_servos_work_is_the_change_of_mechanical_energy(rov, heavy, moving_start):
    # no damping: dE/dt = tau_q . qd, integrated with the plant's joint torques
    params = heavy.scaled({"vehicle.linear_damping": 0.0, "vehicle.quadratic_damping": 0.0,
                           "links.quadratic_damping": 0.0})
    plant = FloatingPlant(rov, params)
    q, v = moving_start
    dt = 0.002

    def energy(q, v):
        return ref.kinetic_energy(rov, params, q, v) + ref.potential_energy(rov, params, q)

    def power(t, q, v):
        _, torques = plant.accelerations(q, v, np.zeros(6), _sweep(t), t)
        return torques.dot(v[6:])

    start = energy(q, v)
    work, t, p = 0.0, 0.0, power(0.0, q, v)
    for _ in range(int(1.0 / dt)):
        q, v = plant.step(q, v, np.zeros(6), _sweep(t + 0.5 * dt), t, dt)
        t += dt
        p_new = power(t, q, v)
        work += 0.5 * dt * (p + p_new)
        p = p_new
    assert abs(work) > 1e-3
    assert energy(q, v) - start == pytest.approx(work, rel=1e-3, abs=1e-6)


def test_mass_matrix_is_symmetric_positive_definite_and_sums_the_bodies(rov, heavy):
    plant = FloatingPlant(rov, heavy)
    pm = rov.pin_model
    data = pm.createData()
    rng = np.random.default_rng(3)
    for _ in range(40):
        q = rov.random_configuration(rng, tilt=1.2)
        M = plant.mass_matrix(q)
        np.testing.assert_array_equal(M, M.T)
        assert np.linalg.eigvalsh(M)[0] > 0.0
        pin.computeJointJacobians(pm, data, q)
        expected = np.zeros_like(M)
        for jid, body in ref.bodies(rov, heavy):
            J = pin.getJointJacobian(pm, data, jid, pin.ReferenceFrame.LOCAL)
            expected += J.T @ (ref.rigid_inertia(body) + body.added_mass) @ J
        np.testing.assert_allclose(M, expected, rtol=1e-10, atol=1e-12)


def test_restoring_wrench_sums_every_weight_and_buoyancy(rov, heavy):
    plant = FloatingPlant(rov, heavy)
    rng = np.random.default_rng(5)
    for _ in range(10):
        q = rov.random_configuration(rng, tilt=1.0)
        np.testing.assert_allclose(plant.restoring_wrench(q),
                                   ref.restoring_wrench(rov, heavy, q), atol=1e-10)


def test_a_constant_current_is_a_change_of_inertial_frame(rov, wu):
    # Galilean invariance: in a current V_c, the motion relative to the water is the motion in
    # still water; positions differ by V_c t. Gravity, buoyancy and damping on; arm moving.
    current = np.array([0.3, -0.2, 0.15])
    still = FloatingPlant(rov, wu)
    flowing = FloatingPlant(rov, wu, current=current)
    q = rov.configuration([0, 0, 0, 0.3, -0.2, 0.6], rov.home()[7:])
    v_still = np.array([0.2, -0.1, 0.1, 0.4, -0.3, 0.5, 0.1, -0.1, 0.1, 0.0])
    x, y, z, w = q[3:7]
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    v_flow = v_still.copy()
    v_flow[:3] += R.T @ current
    wrench = np.array([3.0, -2.0, 1.0, 0.2, -0.1, 0.3])
    qs, vs = run(still, q, v_still, 3.0, wrench=wrench, reference=_sweep)
    qf, vf = run(flowing, q, v_flow, 3.0, wrench=wrench, reference=_sweep)
    np.testing.assert_allclose(qf[:3] - qs[:3], current * 3.0, atol=1e-9)
    np.testing.assert_allclose(qf[3:], qs[3:], atol=1e-9)
    np.testing.assert_allclose(flowing.relative_velocity(qf, vf, 3.0), vs[:6], atol=1e-9)
    np.testing.assert_allclose(vf[3:], vs[3:], atol=1e-9)
