"""The floating plant against closed-form results.

Terminal velocities of ``D(v) v = F``, the period of free roll and pitch from the restoring
stiffness and the total inertia, drift with a current (steady and unsteady). Each expected value
is computed from the parameters, never from the plant.
"""

import math

import numpy as np
import pytest

from tests.support.floating import neutral_links, neutral_vehicle_only, run
from uvms_qp.dynamics import FloatingPlant, SinusoidalCurrent


def terminal_speed(linear: float, quadratic: float, force: float) -> float:
    """Positive root of ``quadratic u^2 + linear u = force``."""
    if quadratic == 0.0:
        return force / linear
    return (-linear + math.sqrt(linear * linear + 4.0 * quadratic * force)) / (2.0 * quadratic)


@pytest.mark.parametrize("axis", range(6))
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_terminal_velocity_per_axis_solves_linear_plus_quadratic_damping(rov, heavy, axis,
                                                                          sign):
    params = neutral_vehicle_only(heavy)
    plant = FloatingPlant(rov, params)
    body = params.vehicle
    speed = 0.5 if axis < 3 else 0.8                         # [m/s] or [rad/s]
    dl, dq = body.linear_damping[axis], body.quadratic_damping[axis]
    force = dl * speed + dq * speed * speed
    wrench = np.zeros(6)
    wrench[axis] = sign * force
    q = rov.configuration([0, 0, 0, 0.1, -0.2, 0.3], rov.home()[7:])
    _, v = run(plant, q, np.zeros(plant.nv), 6.0, wrench=wrench)
    expected = np.zeros(6)
    expected[axis] = sign * terminal_speed(dl, dq, force)
    np.testing.assert_allclose(v[:6], expected, atol=1e-7)


def _zero_crossings(times: np.ndarray, values: np.ndarray) -> np.ndarray:
    k = np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))
    return times[k] - values[k] * (times[k + 1] - times[k]) / (values[k + 1] - values[k])


def _period(plant, q, index: int, duration: float) -> float:
    times, angles = [], []

    def observe(t, q, v):
        times.append(t)
        angles.append(plant.model.vehicle.eta_from_q(q[:7])[index])

    run(plant, q, np.zeros(plant.nv), duration, observe=observe)
    crossings = _zero_crossings(np.array(times), np.array(angles))
    assert len(crossings) >= 5
    return 2.0 * float(np.mean(np.diff(crossings)))


@pytest.mark.parametrize("index", [3, 4], ids=["roll", "pitch"])
def test_free_roll_and_pitch_period_from_stiffness_and_rigid_plus_added_inertia(rov, heavy,
                                                                                 index):
    # von Benzon et al.: body origin at the CG, centre of buoyancy 1 cm above, W = B here.
    params = neutral_vehicle_only(heavy, balanced=False, damping=False)
    body = params.vehicle
    k = index - 3
    weight = body.mass * params.gravity
    stiffness = weight * (body.centre_of_gravity[2] - body.centre_of_buoyancy[2])  # W * BG
    inertia = body.inertia[k, k] + body.added_mass[index, index]
    expected = 2.0 * math.pi * math.sqrt(inertia / stiffness)
    eta = np.zeros(6)
    eta[index] = 0.05
    plant = FloatingPlant(rov, params)
    period = _period(plant, rov.configuration(eta, rov.home()[7:]), index, 3.2 * expected)
    assert period == pytest.approx(expected, rel=5e-4)


def test_free_roll_period_with_the_centre_of_gravity_below_the_origin_couples_sway(rov, wu):
    # Wu (2018): origin at the CB, CG 2 cm below. Sway carries no stiffness, so its momentum
    # m_vv v + m_vp p stays zero and the roll inertia is m_pp - m_vp^2 / m_vv.
    params = neutral_vehicle_only(wu, balanced=False, damping=False)
    body = params.vehicle
    m, zg = body.mass, body.centre_of_gravity[2]
    m_vv = m + body.added_mass[1, 1]
    m_vp = -m * zg
    m_pp = body.inertia[0, 0] + m * zg * zg + body.added_mass[3, 3]
    stiffness = m * params.gravity * (zg - body.centre_of_buoyancy[2])
    expected = 2.0 * math.pi * math.sqrt((m_pp - m_vp * m_vp / m_vv) / stiffness)
    uncoupled = 2.0 * math.pi * math.sqrt(m_pp / stiffness)
    assert abs(expected - uncoupled) > 1e-3 * expected  # the coupling is visible
    plant = FloatingPlant(rov, params)
    period = _period(plant, rov.configuration([0, 0, 0, 0.05, 0, 0], rov.home()[7:]), 3,
                     3.2 * expected)
    assert period == pytest.approx(expected, rel=5e-4)


def _world_velocity(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    x, y, z, w = q[3:7]
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    return R @ v[:3]


def test_without_thrust_a_neutral_uvms_drifts_at_the_current_velocity(rov, wu):
    current = np.array([0.3, -0.2, 0.1])          # world NED, not horizontal [m/s]
    plant = FloatingPlant(rov, neutral_links(wu), current=current)
    q = rov.configuration([0, 0, 0, 0.05, -0.05, 0.4], rov.home()[7:])
    q, v = run(plant, q, np.zeros(plant.nv), 40.0, dt=0.01)  # the steady state, not the path
    np.testing.assert_allclose(_world_velocity(q, v), current, atol=2e-3)
    np.testing.assert_allclose(v[3:6], 0.0, atol=2e-3)
    np.testing.assert_allclose(plant.relative_velocity(q, v), 0.0, atol=2e-3)


def test_a_neutral_uvms_follows_an_accelerating_current_exactly(rov, heavy):
    # Each neutral body obeys (m + M_A) a = (rho V + M_A) a_c: with rho V = m and no relative
    # velocity at the start, it moves with the water (pressure gradient + added mass).
    params = neutral_links(heavy.scaled({"vehicle.linear_damping": 0.0,
                                         "vehicle.quadratic_damping": 0.0,
                                         "links.quadratic_damping": 0.0}))
    current = SinusoidalCurrent([0.1, 0.0, 0.0], [0.3, -0.2, 0.15], period=4.0)
    plant = FloatingPlant(rov, params, current=current)
    q = rov.configuration([0, 0, 0, 0.2, -0.1, 0.7], rov.home()[7:])
    v = np.zeros(plant.nv)
    x, y, z, w = q[3:7]
    R = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                  [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                  [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])
    v[:3] = R.T @ current.velocity(0.0)
    errors = []
    run(plant, q, v, 6.0, observe=lambda t, q, v: errors.append(
        np.abs(_world_velocity(q, v) - current.velocity(t)).max() + np.abs(v[3:]).max()))
    assert max(errors) < 1e-9
