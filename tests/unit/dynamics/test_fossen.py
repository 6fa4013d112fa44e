"""The vehicle against Fossen's equations integrated apart (scipy, tight tolerance).

With the arm's links massless and volumeless, the plant is one rigid vehicle;
``tests/support/floating.py`` writes Fossen's model of that vehicle in the book's matrices and
``solve_ivp`` integrates it in Euler angles. With the arm held still, the UVMS is one rigid body
whose parts keep their own added mass, damping, weight and buoyancy: the same equations with
composite matrices. Both published sets are used: von
Benzon et al. (origin at the CG) and Wu (CG 2 cm below the origin: the ``M_RB`` and ``C_RB``
couplings), with weight != buoyancy, damping, a wrench and a current that is not horizontal.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tests.support.floating import BodyParameters, FossenVehicle, LockedUVMS, run
from uvms_qp.dynamics import FloatingPlant

WRENCH = np.array([6.0, -4.0, 3.0, 0.3, -0.4, 0.5])
CURRENT = np.array([0.25, -0.15, 0.05])
ETA0 = np.array([0.5, -0.3, 2.0, 0.15, -0.1, 0.4])
NU0 = np.array([0.3, 0.1, -0.2, 0.2, 0.1, -0.3])


def _vehicle_only(params):
    empty = BodyParameters(0.0, np.zeros(3), np.zeros(3), 0.0, np.zeros(3), np.zeros(6),
                           np.zeros(6), np.zeros(6), "test")
    return params.with_changes(links={k: empty for k in params.links})


def _reference(params, duration):
    model = FossenVehicle(params.vehicle, params.water_density, params.gravity, WRENCH, CURRENT)
    sol = solve_ivp(model.rhs, (0.0, duration), np.concatenate((ETA0, NU0)), method="DOP853",
                    rtol=1e-12, atol=1e-12)
    assert sol.success
    return sol.y[:, -1]


def _plant_error(rov, params, duration, dt, expected):
    plant = FloatingPlant(rov, params, current=CURRENT)
    q = rov.configuration(ETA0, rov.home()[7:])
    v = np.concatenate((NU0, np.zeros(rov.n_joints)))
    q, v = run(plant, q, v, duration, wrench=WRENCH, dt=dt)
    error = np.concatenate((rov.vehicle.eta_from_q(q[:7]), v[:6])) - expected
    error[3:6] = (error[3:6] + np.pi) % (2.0 * np.pi) - np.pi  # Euler angles modulo a turn
    return np.abs(error).max()


@pytest.mark.parametrize("name", ["heavy", "wu"])
def test_vehicle_alone_matches_fossens_equations(rov, request, name):
    # measured: 1.4e-9 (heavy) and 3.1e-9 (wu) at the default 5 ms step after 3 s
    params = _vehicle_only(request.getfixturevalue(name))
    expected = _reference(params, 3.0)
    assert _plant_error(rov, params, 3.0, 0.005, expected) < 2e-8


@pytest.mark.parametrize("name", ["heavy", "wu"])
def test_the_error_shrinks_at_fourth_order_with_the_step(rov, request, name):
    # without the kink of |nu| nu at zero (quadratic damping off) the order is clean: errors
    # 1.3e-5, 8.4e-7, 5.3e-8 at 40, 20, 10 ms for wu (ratio 16 = 2^4)
    params = _vehicle_only(request.getfixturevalue(name)).scaled(
        {"vehicle.quadratic_damping": 0.0})
    expected = _reference(params, 3.0)
    errors = [_plant_error(rov, params, 3.0, dt, expected) for dt in (0.04, 0.02, 0.01)]
    orders = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert orders.min() > 3.8, (errors, orders)


@pytest.mark.parametrize("name", ["heavy", "wu"])
def test_uvms_with_the_arm_held_still_matches_fossens_equations(rov, request, name):
    params = request.getfixturevalue(name)
    joints = rov.home()[7:]
    locked = LockedUVMS(rov, params, joints, WRENCH, CURRENT)
    sol = solve_ivp(locked.rhs, (0.0, 2.0), np.concatenate((ETA0, NU0)), method="DOP853",
                    rtol=1e-11, atol=1e-11)
    assert sol.success
    plant = FloatingPlant(rov, params, current=CURRENT)
    q = rov.configuration(ETA0, joints)
    v = np.concatenate((NU0, np.zeros(rov.n_joints)))
    q, v = run(plant, q, v, 2.0, wrench=WRENCH)
    np.testing.assert_array_equal(q[7:], joints)  # the servos held the arm
    error = np.concatenate((rov.vehicle.eta_from_q(q[:7]), v[:6])) - sol.y[:, -1]
    error[3:6] = (error[3:6] + np.pi) % (2.0 * np.pi) - np.pi
    assert np.abs(error).max() < 3e-8  # measured 3.0e-9 (heavy), 1.1e-8 (wu) at 5 ms
