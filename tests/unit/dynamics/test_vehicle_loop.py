"""The vehicle's body-velocity loop: gains, convergence, anti-windup, feed-forward, bad input.

The plant models here are written in the test: one surge axis ``m u' = -d u + F + f_dist`` with
the thrust ``F`` following the command through a first-order lag, integrated at 1 ms under the
loop's 100 Hz, with a force limit standing in for the allocation (what the limit cuts off is the
unmet wrench).
"""

import math

import numpy as np
import pytest

from uvms_qp.dynamics import ThrusterLayout, VelocityLoop, pole_placement_gains
from uvms_qp.errors import InputError, NonFiniteError, ShapeError

# von Benzon, Sorensen, Uth, Ouerghi, Gabrielsson, Johansen (2022), J. Mar. Sci. Eng. 10(12):1898
MASS = 13.5
INERTIA = (0.26, 0.23, 0.37)
ADDED = np.array([6.36, 7.12, 18.68, 0.189, 0.135, 0.222])
LINEAR = np.array([13.7, 0.0, 33.0, 0.0, 0.8, 0.0])
QUADRATIC = np.array([141.0, 217.0, 190.0, 1.19, 0.47, 1.5])
TOTAL = np.array([MASS, MASS, MASS, *INERTIA]) + ADDED

DT = 0.01  # loop period [s]
PHYSICS = 0.001  # plant step [s]
LAG = 0.03  # thrust time constant [s]


def run_axis(loop, axis, reference, duration, *, disturbance=0.0, limit=math.inf,
             feed_unmet=True, velocity=0.0):
    """Velocity of DOF ``axis`` over time under ``loop`` (references ``reference(t)``)."""
    m, d = TOTAL[axis], LINEAR[axis]
    thrust = 0.0
    unmet = np.zeros(6)
    decay = math.exp(-PHYSICS / LAG)
    out = []
    substeps = round(DT / PHYSICS)
    for k in range(round(duration / DT)):
        t = k * DT
        nu_ref = np.zeros(6)
        nu_ref[axis] = reference(t)
        nu = np.zeros(6)
        nu[axis] = velocity
        wrench = loop.step(nu_ref, nu, unmet=unmet if feed_unmet else None)
        command = min(max(wrench[axis], -limit), limit)
        unmet = np.zeros(6)
        unmet[axis] = wrench[axis] - command
        for _ in range(substeps):
            thrust = command + (thrust - command) * decay
            # semi-implicit in the damping: stable and first-order accurate at 1 ms
            velocity = (m * velocity + PHYSICS * (thrust + disturbance)) / (m + PHYSICS * d)
        out.append(velocity)
    return np.array(out)


def default_loop(**kwargs):
    return VelocityLoop.for_body(MASS, INERTIA, ADDED, LINEAR, dt=DT, **kwargs)


# --- gains ------------------------------------------------------------------------------------


def test_pole_placement_places_the_poles():
    kp, ki = pole_placement_gains(TOTAL, LINEAR, bandwidth=4.0, damping_ratio=0.8)
    for j in range(6):
        poles = np.roots([TOTAL[j], LINEAR[j] + kp[j], ki[j]])
        expected = np.roots([1.0, 2 * 0.8 * 4.0, 16.0])
        np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(expected), rtol=1e-9)
    # surge with the default recipe: kp = 2 * 4 * 19.86 - 13.7, ki = 16 * 19.86
    kp, ki = pole_placement_gains(TOTAL, LINEAR)
    assert kp[0] == pytest.approx(8 * 19.86 - 13.7)
    assert ki[0] == pytest.approx(16 * 19.86)


def test_pole_placement_takes_a_matrix_diagonal_and_per_dof_bandwidths():
    _, ki = pole_placement_gains(np.diag(TOTAL), LINEAR, bandwidth=[1, 2, 3, 4, 5, 6])
    assert ki[5] == pytest.approx(36 * TOTAL[5])


def test_pole_placement_refuses_a_bandwidth_below_the_open_loop():
    with pytest.raises(InputError, match="DOF w is slower than its open loop"):
        pole_placement_gains(TOTAL, LINEAR, bandwidth=0.5)


def test_for_body_uses_rigid_plus_added_inertia():
    loop = default_loop()
    kp, ki = pole_placement_gains(TOTAL, LINEAR)
    np.testing.assert_allclose(loop.kp, kp)
    np.testing.assert_allclose(loop.ki, ki)


@pytest.mark.parametrize("axis", range(6))
def test_default_gains_settle_every_axis_with_the_thruster_lag(axis):
    # a step of the reference: the PI's zero gives exp(-2) = 13.5 % overshoot in the ideal
    # loop; the lag and the 100 Hz sampling add a little (17.6 % on the undamped axes)
    loop = default_loop(damping_feedforward=False)
    v = run_axis(loop, axis, lambda t: 0.1, 4.0)
    overshoot = v.max() / 0.1 - 1.0
    assert overshoot < 0.2
    settled = np.flatnonzero(np.abs(v / 0.1 - 1.0) > 0.02)
    assert (settled[-1] + 1) * DT < 1.8  # 1.45 s in the ideal loop
    assert abs(v[-1] - 0.1) < 1e-3


# --- convergence, disturbance, anti-windup ----------------------------------------------------


def test_zero_steady_state_error_under_a_constant_disturbance():
    loop = default_loop()
    v = run_axis(loop, 0, lambda t: 0.3, 15.0, disturbance=-25.0)
    assert abs(v[-1] - 0.3) < 1e-6
    assert np.abs(v[-100:] - 0.3).max() < 1e-5
    # the integral holds the disturbance (the damping at the reference is fed forward)
    assert loop.ki[0] * loop.integral[0] == pytest.approx(25.0, rel=1e-3)


def test_without_integral_action_the_disturbance_leaves_an_error():
    loop = VelocityLoop(pole_placement_gains(TOTAL, LINEAR)[0], np.zeros(6), dt=DT,
                        linear_damping=LINEAR)
    v = run_axis(loop, 0, lambda t: 0.3, 15.0, disturbance=-25.0)
    assert abs(v[-1] - 0.3) > 0.05


def test_anti_windup_bounds_the_overshoot_after_saturation():
    # a 0.6 m/s step against a disturbance with 20 N of thrust: saturated for about a second
    loop = default_loop()
    v = run_axis(loop, 0, lambda t: 0.6, 12.0, disturbance=-5.0, limit=20.0)
    assert abs(v[-1] - 0.6) < 1e-4
    guarded = v.max() / 0.6 - 1.0
    assert guarded < 0.02
    # the same loop without anti-windup winds up and overshoots
    loop = default_loop()
    v = run_axis(loop, 0, lambda t: 0.6, 12.0, disturbance=-5.0, limit=20.0, feed_unmet=False)
    assert v.max() / 0.6 - 1.0 > 0.2


def test_integral_term_is_clamped_to_the_integral_limit():
    loop = VelocityLoop(np.zeros(6), np.full(6, 100.0), dt=DT, integral_limit=np.full(6, 30.0))
    for _ in range(500):
        loop.step(np.full(6, 1.0), np.zeros(6))
    np.testing.assert_allclose(100.0 * loop.integral, 30.0)
    wrench = loop.step(-np.full(6, 1.0), np.zeros(6))
    np.testing.assert_allclose(wrench, 30.0 - 100.0 * DT)  # unwinds at once


def test_for_body_bounds_the_integral_by_the_layout():
    layout = ThrusterLayout.bluerov2_heavy()
    loop = default_loop(layout=layout)
    for _ in range(3000):
        loop.step([2.0, 0, 0, 0, 0, 0], np.zeros(6))
    assert loop.ki[0] * loop.integral[0] == pytest.approx(layout.wrench_upper[0])


def test_unmet_wrench_holds_only_the_dof_it_concerns():
    loop = VelocityLoop(np.ones(6), np.ones(6), dt=DT)
    error = np.array([1.0, 1.0, -1.0, 1.0, 1.0, 1.0])
    loop.step(error, np.zeros(6), unmet=[5.0, -5.0, -5.0, 1e-4, 0.0, 0.0])
    # u: unmet along its error (held); v: unmet against it (integrates, it unwinds the demand);
    # w: along (held); p: below the round-off tolerance (integrates)
    np.testing.assert_allclose(loop.integral, [0.0, DT, 0.0, DT, DT, DT])


# --- passive DOFs and feed-forward ------------------------------------------------------------


def test_passive_dofs_receive_no_wrench():
    loop = default_loop(actuated=("u", "v", "w", "r"), restoring=lambda q: np.arange(1.0, 7.0))
    wrench = loop.step(np.full(6, 0.2), np.zeros(6), q=np.zeros(7))
    assert wrench[3] == 0.0 and wrench[4] == 0.0
    assert np.all(wrench[[0, 1, 2, 5]] != 0.0)
    assert loop.last_error[3] == 0.0


def test_feed_forward_of_restoring_and_damping_at_rest_error():
    calls = []

    def restoring(q):
        calls.append(q)
        return np.array([0.0, 0.0, -2.6, 0.3, -1.2, 0.0])

    loop = VelocityLoop(np.full(6, 7.0), np.full(6, 3.0), dt=DT, restoring=restoring,
                        linear_damping=LINEAR, quadratic_damping=QUADRATIC)
    nu_ref = np.array([0.3, -0.1, 0.05, 0.0, 0.02, -0.2])
    q = np.arange(7.0)
    wrench = loop.step(nu_ref, nu_ref, q=q)  # no error: feed-forward only
    expected = restoring(q) + (LINEAR + QUADRATIC * np.abs(nu_ref)) * nu_ref
    np.testing.assert_allclose(wrench, expected)
    assert calls[0] is q


def test_told_the_water_the_damping_is_fed_forward_at_the_relative_velocity():
    # the plant's damping acts on the velocity relative to the water: holding station in a
    # head current needs the drag of the current, which the loop feeds forward when told it
    loop = VelocityLoop(np.full(6, 7.0), np.full(6, 3.0), dt=DT, linear_damping=LINEAR,
                        quadratic_damping=QUADRATIC)
    nu_ref = np.array([0.3, -0.1, 0.05, 0.0, 0.02, -0.2])
    water = np.array([-0.2, 0.1, 0.0, 0.0, 0.0, 0.0])  # body frame [m/s]
    relative = nu_ref - water
    wrench = loop.step(nu_ref, nu_ref, water=water)  # no error: feed-forward only
    np.testing.assert_allclose(wrench, (LINEAR + QUADRATIC * np.abs(relative)) * relative)
    # not told the water: still water is assumed
    np.testing.assert_allclose(loop.step(nu_ref, nu_ref),
                               (LINEAR + QUADRATIC * np.abs(nu_ref)) * nu_ref)


def test_reset_clears_the_integral():
    loop = default_loop()
    loop.step([0.1, 0, 0, 0, 0, 0], np.zeros(6))
    assert loop.integral[0] > 0.0
    loop.reset()
    np.testing.assert_array_equal(loop.integral, 0.0)


def test_set_gains_replaces_both_or_neither():
    loop = default_loop()
    before = loop.kp
    with pytest.raises(InputError, match="ki: expected gains >= 0, got -1 on DOF q"):
        loop.set_gains(np.ones(6), [1, 1, 1, 1, -1, 1])
    np.testing.assert_array_equal(loop.kp, before)
    loop.set_gains(np.full(6, 2.0), np.zeros(6))
    np.testing.assert_array_equal(loop.kp, 2.0)


# --- bad input --------------------------------------------------------------------------------


@pytest.mark.parametrize(("kwargs", "error", "words"), [
    ({"kp": [1, 1, 1, -2, 1, 1]}, InputError, "kp: expected gains >= 0, got -2 on DOF p"),
    ({"ki": [1, 1, 1]}, ShapeError, "ki: expected length 6"),
    ({"dt": 0.0}, InputError, "dt: expected a positive number"),
    ({"actuated": ("u", "yaw")}, InputError, "actuated: unknown DOF 'yaw'"),
    ({"restoring": 3.0}, InputError, "restoring: expected a callable"),
    ({"linear_damping": [1, 1, -1, 1, 1, 1]}, InputError,
     "linear_damping: expected magnitudes >= 0, got -1 on DOF w"),
    ({"quadratic_damping": np.ones(6)}, InputError, "given without linear_damping"),
    ({"integral_limit": [1, 1, 1, 1, 1, 0]}, InputError,
     "integral_limit: expected positive bounds, got 0 on DOF r"),
])
def test_construction_errors_name_the_culprit(kwargs, error, words):
    args = {"kp": np.ones(6), "ki": np.ones(6), "dt": DT, **kwargs}
    with pytest.raises(error, match=words.replace("(", r"\(")):
        VelocityLoop(**args)


def test_step_errors_name_the_culprit():
    loop = VelocityLoop(np.ones(6), np.ones(6), dt=DT, restoring=lambda q: np.zeros(3))
    with pytest.raises(ShapeError, match="nu_ref: expected length 6"):
        loop.step(np.zeros(4), np.zeros(6), q=0)
    with pytest.raises(NonFiniteError, match="nu contains NaN"):
        loop.step(np.zeros(6), [0, 0, float("nan"), 0, 0, 0], q=0)
    with pytest.raises(InputError, match="q: required"):
        loop.step(np.zeros(6), np.zeros(6))
    with pytest.raises(ShapeError, match=r"restoring\(q\): expected length 6"):
        loop.step(np.zeros(6), np.zeros(6), q=0)
    with pytest.raises(NonFiniteError, match="unmet contains"):
        VelocityLoop(np.ones(6), np.ones(6), dt=DT).step(
            np.zeros(6), np.zeros(6), unmet=[math.inf, 0, 0, 0, 0, 0])


# --- stability margins of the default gains ---------------------------------------------------


def thruster_lag(s, third_order):
    if third_order:  # von Benzon et al. (2022)'s identified T200 response
        return (6136 * s + 108700) / (s ** 3 + 89 * s ** 2 + 9258 * s + 108700)
    return 1.0 / (LAG * s + 1.0)


def phase_margin(axis, *, third_order=False, inertia_scale=1.0):
    """Phase margin [deg] of one axis: PI, thrust lag, a half-period hold delay, the plant."""
    kp, ki = pole_placement_gains(TOTAL, LINEAR)
    w = np.logspace(-2, 3, 100001)
    s = 1j * w
    loop = ((kp[axis] + ki[axis] / s) * thruster_lag(s, third_order) * np.exp(-s * DT / 2)
            / (inertia_scale * TOTAL[axis] * s + LINEAR[axis]))
    crossing = np.argmin(np.abs(np.abs(loop) - 1.0))
    return 180.0 + np.degrees(np.angle(loop[crossing])), w[crossing]


@pytest.mark.parametrize("axis", range(6))
def test_default_gains_keep_a_phase_margin(axis):
    margin, crossover = phase_margin(axis)
    assert margin > 59.0  # 60.2 deg on the undamped axes
    assert crossover < 0.3 / LAG  # well below the thrusters' bandwidth
    assert phase_margin(axis, third_order=True)[0] > 60.0
    assert phase_margin(axis, inertia_scale=0.5)[0] > 50.0  # half the modelled inertia
