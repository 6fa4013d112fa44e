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
