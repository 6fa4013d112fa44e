"""Integration on the configuration manifold: exact zero-order hold, passive attitude, drift."""

from __future__ import annotations

import math

import numpy as np
import pytest

import uvms_qp
from uvms_qp.errors import InputError
from uvms_qp.sim.current import ConstantCurrent, wrap_angle
from uvms_qp.sim.integrators import Integrator


@pytest.fixture(scope="module")
def bluerov():
    return uvms_qp.load_model("bluerov2_heavy_alpha5")


@pytest.fixture(scope="module")
def wang():
    return uvms_qp.load_model("wang_9dof")  # 4-DOF vehicle: roll and pitch passive


def test_euler_is_the_model_exponential_map(bluerov):
    q = bluerov.configuration([1.0, -0.5, 2.0, 0.1, -0.2, 0.7], [3.0, 1.5, 2.0, 3.0])
    zeta = np.array([0.3, -0.1, 0.2, 0.05, -0.02, 0.2, 0.1, -0.3, 0.2, 0.4])
    q1 = Integrator(bluerov).step(q, zeta, 0.1)
    np.testing.assert_allclose(q1, bluerov.integrate(q, zeta, 0.1), atol=1e-15)
    # a held body twist: ten small steps equal one big step (exact exponential map)
    q10 = q.copy()
    for _ in range(10):
        q10 = Integrator(bluerov).step(q10, zeta, 0.01)
    np.testing.assert_allclose(q10, q1, atol=1e-12)


def test_rk4_with_a_constant_rate_field_equals_euler(bluerov):
    q = bluerov.configuration([0, 0, 0, 0, 0, 0.3], [3.0, 1.5, 2.0, 3.0])
    zeta = np.linspace(-0.2, 0.3, 10)
    rk4 = Integrator(bluerov, method="rk4").step(q, zeta, 0.05, 0.0, lambda q_, t_: zeta)
    np.testing.assert_allclose(rk4, bluerov.integrate(q, zeta, 0.05), atol=1e-14)
    with pytest.raises(InputError, match="rates"):
        Integrator(bluerov, method="rk4").step(q, zeta, 0.05)


def test_rk4_is_fourth_order_on_a_linear_joint_field(bluerov):
    # joint rates qdot = -k (q - q_ref): exact solution decays as exp(-k t)
    k = 2.0
    q_ref = np.array([3.0, 1.5, 2.0, 3.0])
    q0 = bluerov.configuration(np.zeros(6), q_ref + 0.5)

    def rates(q, t):
        zeta = np.zeros(10)
        zeta[6:] = -k * (bluerov.split(q)[1] - q_ref)
        return zeta

    integ = Integrator(bluerov, method="rk4")

    def one_step_error(h):
        q1 = integ.step(q0, rates(q0, 0.0), h, 0.0, rates)
        return np.abs(bluerov.split(q1)[1] - (q_ref + 0.5 * math.exp(-k * h))).max()

    # local error O(h^5): halving the step divides it by about 32 (Euler: by 4)
    ratio = one_step_error(0.1) / one_step_error(0.05)
    assert 28.0 < ratio < 36.0
    assert one_step_error(0.1) < 2e-6


def test_passive_roll_pitch_held_or_restored(wang):
    eta = [0.0, 0.0, 1.0, 0.2, -0.1, 0.5]
    q = wang.configuration(eta, np.zeros(5))
    zeta = np.zeros(wang.nv)
    held = Integrator(wang, passive="hold").step(q, zeta, 0.5)
    np.testing.assert_allclose(wang.split(held)[0], eta, atol=1e-12)
    tau, dt = 2.0, 0.5
    restored = Integrator(wang, passive="restore", restore_time_constant=tau).step(q, zeta, dt)
    phi, theta = wang.split(restored)[0][3:5]
    decay = math.exp(-dt / tau)
    assert phi == pytest.approx(0.2 * decay, abs=1e-9)
    assert theta == pytest.approx(-0.1 * decay, abs=1e-9)
    np.testing.assert_allclose(wang.split(restored)[0][[0, 1, 2, 5]], [0, 0, 1, 0.5], atol=1e-9)


def test_restore_does_not_touch_actuated_attitude(bluerov):
    eta = [0.0, 0.0, 0.0, 0.2, -0.1, 0.5]
    q = bluerov.configuration(eta, [3.0, 1.5, 2.0, 3.0])
    out = Integrator(bluerov, passive="restore").step(q, np.zeros(10), 0.5)
    np.testing.assert_allclose(bluerov.split(out)[0], eta, atol=1e-12)


def test_current_drift_moves_the_vehicle(bluerov):
    current = ConstantCurrent(direction=math.pi / 2, speed=0.4, drift=0.5)
    np.testing.assert_allclose(current.drift_velocity(), [0.0, 0.2, 0.0], atol=1e-15)
    q = bluerov.configuration(np.zeros(6), [3.0, 1.5, 2.0, 3.0])
    out = Integrator(bluerov, current=current).step(q, np.zeros(10), 0.5)
    np.testing.assert_allclose(bluerov.split(out)[0], [0, 0.1, 0, 0, 0, 0], atol=1e-12)


def test_current_validation_and_heading_wrap():
    assert ConstantCurrent(direction=3 * math.pi / 2).heading == pytest.approx(-math.pi / 2)
    assert wrap_angle(-math.pi) == pytest.approx(math.pi)
    with pytest.raises(InputError, match=r"^drift"):
        ConstantCurrent(direction=0.0, drift=1.5)
    with pytest.raises(InputError, match=r"^speed"):
        ConstantCurrent(direction=0.0, speed=-1.0)


def test_integrator_rejects_unknown_options(bluerov):
    with pytest.raises(InputError, match=r"^method"):
        Integrator(bluerov, method="heun")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^passive"):
        Integrator(bluerov, passive="free")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"^restore_time_constant"):
        Integrator(bluerov, restore_time_constant=0.0)
