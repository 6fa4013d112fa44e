import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.analytic import (
    DEFAULT_RULES,
    FuzzyRules,
    fuzzy_weights,
    joint_limit_gradient,
    joint_limit_index,
    joint_limit_weights,
    motion_distribution,
    multi_objective_gradient_projection,
    payload_moment,
    payload_objective,
    payload_objective_gradient,
    pinv,
    static_tilt,
    vehicle_payload_moment,
    weighted_pinv,
)
from uvms_qp.errors import BoundsError, InputError, ShapeError

LOWER = np.deg2rad([-60, -90, -110, -120, -120])
UPPER = -LOWER
C = [10, 6, 10, 10, 10]


def planar_arm(q, lengths=(0.33, 0.33, 0.242)):
    a = np.cumsum(q)
    p = np.array([np.sum(lengths * np.cos(a)), np.sum(lengths * np.sin(a)), 0.0])
    J = np.zeros((3, len(q)))
    for j in range(len(q)):
        J[0, j] = -np.sum(np.asarray(lengths)[j:] * np.sin(a[j:]))
        J[1, j] = np.sum(np.asarray(lengths)[j:] * np.cos(a[j:]))
    return p, J


def test_motion_distribution_eq14():
    w = motion_distribution(0.7, 4, 5, 0.02)
    assert np.allclose(w, [0.3 * 0.02] * 4 + [0.7] * 5)
    assert np.allclose(motion_distribution(1.0, 4, 5)[:4], 0.0)  # arm only
    assert np.allclose(motion_distribution(0.0, 4, 5)[4:], 0.0)  # vehicle only
    jw = np.array([1.0, 0.5, 1.0, 1.0, 0.1])
    assert np.allclose(motion_distribution(0.5, 4, 5, joint_weights=jw)[4:], 0.5 * jw)
    # beta = 1 through the weighted inverse: the vehicle does not move
    J = np.random.default_rng(0).normal(size=(3, 9))
    x = weighted_pinv(J, inverse_weights=motion_distribution(1.0, 4, 5)) @ [0.1, 0.0, 0.0]
    assert np.allclose(x[:4], 0.0) and np.allclose(J @ x, [0.1, 0, 0])
    with pytest.raises(InputError, match="beta"):
        motion_distribution(1.5, 4, 5)
    with pytest.raises(InputError, match="w_max"):
        motion_distribution(0.5, 4, 5, w_max=2.0)


def test_joint_limit_index_mid_range_and_hand_value():
    mid = 0.5 * (LOWER + UPPER)
    assert np.isclose(joint_limit_index(mid, LOWER, UPPER, C), np.sum(4.0 / np.array(C)))
    assert np.allclose(joint_limit_gradient(mid, LOWER, UPPER, C), 0.0)
    assert np.allclose(joint_limit_weights(mid, LOWER, UPPER, C), 1.0)
    # one joint, limits [0, 2], C = 1, q = 1.5: H = 4 / (0.5 * 1.5)
    assert np.isclose(joint_limit_index([1.5], [0.0], [2.0], 1.0), 4.0 / 0.75)


@given(st.lists(st.floats(-0.95, 0.95), min_size=5, max_size=5))
def test_joint_limit_gradient_matches_finite_differences(frac):
    q = 0.5 * (LOWER + UPPER) + np.array(frac) * 0.5 * (UPPER - LOWER)
    g = joint_limit_gradient(q, LOWER, UPPER, C)
    h = 1e-7
    fd = [
        (
            joint_limit_index(q + h * e, LOWER, UPPER, C)
            - joint_limit_index(q - h * e, LOWER, UPPER, C)
        )
        / (2 * h)
        for e in np.eye(5)
    ]
    assert np.allclose(g, fd, rtol=1e-5, atol=1e-5)
    w = joint_limit_weights(q, LOWER, UPPER, C)
    assert np.all((w > 0) & (w <= 1))


def test_joint_limit_index_rejects_configuration_on_limit():
    with pytest.raises(BoundsError, match="joint 2"):
        joint_limit_index([0, 0, UPPER[2], 0, 0], LOWER, UPPER, C)
    with pytest.raises(BoundsError):
        joint_limit_index([0.0], [1.0], [0.0])
    with pytest.raises(InputError, match="C"):
        joint_limit_index([0.0], [-1.0], [1.0], 0.0)


@given(st.lists(st.floats(-2.0, 2.0), min_size=3, max_size=3), st.floats(1.0, 100.0))
def test_payload_gradient_matches_finite_differences(q, F):
    q = np.array(q)
    p, J = planar_arm(q)
    g = payload_objective_gradient(p, J, F)
    h = 1e-6
    fd = [
        (
            payload_objective(planar_arm(q + h * e)[0], F)
            - payload_objective(planar_arm(q - h * e)[0], F)
        )
        / (2 * h)
        for e in np.eye(3)
    ]
    assert np.allclose(g, fd, atol=1e-6 * F)


def test_payload_values():
    assert payload_objective([0.3, 0.4, -0.36], 10.0) == pytest.approx(2.5)
    assert payload_moment([0.3, 0.4, -0.36], 10.0) == pytest.approx(5.0)
    with pytest.raises(ShapeError, match="position_jacobian"):
        payload_objective_gradient([0.3, 0.4, 0.0], np.ones((2, 3)), 1.0)


def test_fuzzy_weights_follow_the_papers_text():
    grid = np.linspace(0, 1, 21)
    betas = np.array([[fuzzy_weights(m, f).beta for f in grid] for m in grid])
    assert np.all(np.diff(betas, axis=0) >= -1e-12)  # beta rises with manipulability
    assert np.all(np.diff(betas, axis=1) <= 1e-12)  # and falls with payload
    a1 = [fuzzy_weights(m).alpha_1 for m in grid]
    assert np.all(np.diff(a1) <= 1e-12)  # alpha_1 grows as manipulability falls
    a2 = [fuzzy_weights(0.5, f).alpha_2 for f in grid]
    assert np.all(np.diff(a2) >= -1e-12)  # alpha_2 grows with payload
    high, low = fuzzy_weights(1.0, 0.0), fuzzy_weights(0.0, 0.0)
    assert high.beta > 0.9 and high.alpha_1 < 0.1 and high.alpha_2 == 0.0
    assert low.beta < 0.2 and low.alpha_1 == 1.0
    assert fuzzy_weights(0.5, 0.5) == fuzzy_weights(0.5, 0.5, DEFAULT_RULES)
    with pytest.raises(InputError, match="mu_centres"):
        FuzzyRules(mu_centres=(0.5, 0.2, 0.8))


def test_eq23_keeps_end_effector_rate():
    rng = np.random.default_rng(5)
    J = rng.normal(size=(3, 9))
    w_inv = motion_distribution(0.6, 4, 5)
    g1 = np.concatenate([np.zeros(4), rng.normal(size=5)])
    g2 = np.concatenate([np.zeros(4), rng.normal(size=5)])
    x = multi_objective_gradient_projection(
        J, [0.1, 0.0, 0.0], [g1, g2], [0.8, -0.3], 0.2, inverse_weights=w_inv
    )
    assert np.allclose(J @ x, [0.1, 0.0, 0.0])


def _eq23_case(seed):
    rng = np.random.default_rng(seed)
    J = rng.normal(size=(3, 9))
    w_inv = motion_distribution(0.9, 4, 5)  # vehicle 2e-3, arm 0.9
    g = np.concatenate([np.zeros(4), rng.normal(size=5)])
    return J, w_inv, g


@pytest.mark.parametrize("seed", range(5))
def test_both_projectors_keep_the_tool_rate_and_differ_as_documented(seed):
    J, w_inv, g = _eq23_case(seed)
    xdot = np.array([0.1, -0.2, 0.05])
    particular = weighted_pinv(J, inverse_weights=w_inv) @ xdot
    steps = {}
    for projector in ("weighted", "euclidean"):
        x = multi_objective_gradient_projection(J, xdot, [g], [1.0], 0.2, inverse_weights=w_inv,
                                                projector=projector)
        assert np.allclose(J @ x, xdot)
        steps[projector] = x - particular
    unit = 0.2 * g / np.linalg.norm(g)
    # Euclidean: the orthogonal projection I - J^+ J of the step (independent oracle: pinv)
    assert np.allclose(steps["euclidean"], unit - pinv(J) @ (J @ unit))
    # weighted: the step corrected along W^-1 J^T, so the vehicle (tiny W^-1) barely moves
    correction = unit - steps["weighted"]
    lam = np.linalg.lstsq((w_inv[:, None] * J.T), correction, rcond=None)[0]
    assert np.allclose(w_inv * (J.T @ lam), correction)
    assert np.linalg.norm(steps["weighted"][:4]) < 0.05 * np.linalg.norm(steps["euclidean"][:4])


def test_projectors_agree_without_a_metric_and_unknown_ones_are_refused():
    J, _, g = _eq23_case(0)
    a, b = (multi_objective_gradient_projection(J, np.zeros(3), [g], [1.0], 0.2, projector=p)
            for p in ("weighted", "euclidean"))
    assert np.allclose(a, b)
    with pytest.raises(InputError, match="projector"):
        multi_objective_gradient_projection(J, np.zeros(3), [g], [1.0], 0.2, projector="oblique")


def test_vehicle_payload_moment_hand_values():
    # 10 N down, 2 m ahead and 0.5 m to starboard: nose down (-20 N m), roll to starboard (+5 N m)
    assert np.allclose(vehicle_payload_moment([2.0, 0.5, 0.3], 10.0), [5.0, -20.0])


def test_static_tilt_balances_the_restoring_moment():
    weight, bg = 2000.0, 0.05  # restoring stiffness W BG = 100 N m
    phi, theta = static_tilt([3.0, -20.0], weight, bg)
    assert 100.0 * np.sin(theta) == pytest.approx(-20.0)
    assert 100.0 * np.cos(theta) * np.sin(phi) == pytest.approx(3.0)
    # small moments: tilt = moment / (W GM), with separate transverse and longitudinal heights
    small = static_tilt([0.01, 0.02], weight, [0.05, 0.1])
    assert np.allclose(small, [0.01 / 100.0, 0.02 / 200.0], rtol=1e-6)


def test_static_tilt_refuses_a_moment_it_cannot_balance():
    with pytest.raises(InputError, match="pitch moment"):
        static_tilt([0.0, 120.0], 2000.0, 0.05)
    with pytest.raises(InputError, match="roll moment"):
        static_tilt([101.0, 0.0], 2000.0, 0.05)
    with pytest.raises(InputError, match="metacentric_height"):
        static_tilt([0.0, 1.0], 2000.0, [0.05, -0.1])
    with pytest.raises(InputError, match="weight"):
        static_tilt([0.0, 1.0], 0.0, 0.05)
