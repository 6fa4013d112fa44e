import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.analytic import damped_pinv, null_space_projector, pinv, weighted_pinv
from uvms_qp.errors import InputError, NonFiniteError, ShapeError


def _random(seed, m, n):
    rng = np.random.default_rng(seed)
    return rng.normal(size=(m, n)), rng.uniform(0.1, 10.0, n)


def test_pinv_of_two_link_arm_at_hand_checkable_pose():
    # planar 2-link arm, l1 = l2 = 1, q = (0, pi/2): J = [[-1, -1], [1, 0]]
    J = np.array([[-1.0, -1.0], [1.0, 0.0]])
    assert np.allclose(pinv(J), np.array([[0.0, 1.0], [-1.0, -1.0]]))


def test_pinv_rank_deficient_is_truncated_not_blown_up():
    J = np.array([[1.0, 0.0], [0.0, 1e-14]])
    assert np.allclose(pinv(J), np.diag([1.0, 0.0]))


@given(st.integers(0, 10_000), st.integers(1, 5), st.integers(0, 4))
def test_weighted_pinv_equals_closed_form_of_eq17(seed, m, extra):
    J, w = _random(seed, m, m + extra)
    Winv = np.diag(1.0 / w)
    expected = Winv @ J.T @ np.linalg.inv(J @ Winv @ J.T)
    assert np.allclose(weighted_pinv(J, w), expected, atol=1e-8)
    # same metric given as a full matrix and as the inverse diagonal (Wang et al.'s (2017) form)
    assert np.allclose(weighted_pinv(J, np.diag(w)), expected, atol=1e-8)
    assert np.allclose(weighted_pinv(J, inverse_weights=1.0 / w), expected, atol=1e-8)


@given(st.integers(0, 10_000))
def test_weighted_pinv_is_min_weighted_norm_solution(seed):
    J, w = _random(seed, 3, 6)
    rng = np.random.default_rng(seed + 1)
    b = rng.normal(size=3)
    x = weighted_pinv(J, w) @ b
    assert np.allclose(J @ x, b)
    z = np.linalg.svd(J)[2][3:].T @ rng.normal(size=3)  # any kernel direction
    assert x @ (w * x) <= (x + 0.1 * z) @ (w * (x + 0.1 * z)) + 1e-12


def test_inverse_weight_zero_locks_variable():
    J = np.array([[1.0, 1.0, 1.0]])
    x = weighted_pinv(J, inverse_weights=[0.0, 1.0, 1.0]) @ [2.0]
    assert np.allclose(x, [0.0, 1.0, 1.0])


def test_damped_pinv_matches_regularised_normal_equations_and_limits():
    J, w = _random(3, 3, 5)
    eta = 0.3
    expected = J.T @ np.linalg.inv(J @ J.T + eta**2 * np.eye(3))
    assert np.allclose(damped_pinv(J, eta), expected)
    assert np.allclose(damped_pinv(J, 0.0), pinv(J))
    # weighted damped inverse: minimiser of |Jx-b|^2 + eta^2 x'Wx
    Wd = np.diag(w)
    exp_w = np.linalg.solve(J.T @ J + eta**2 * Wd, J.T)
    assert np.allclose(damped_pinv(J, eta, w), exp_w)


def test_damped_pinv_bounded_at_singularity():
    J = np.array([[1.0, 1.0], [1.0, 1.0]])
    assert np.abs(damped_pinv(J, 0.1)).max() < 10.0


def test_projector_properties_in_weighted_metric():
    J, w = _random(5, 2, 5)
    N = null_space_projector(J, w)
    assert np.allclose(J @ N, 0.0, atol=1e-12)
    assert np.allclose(N @ N, N)
    assert np.allclose(np.diag(w) @ N, (np.diag(w) @ N).T)  # W-orthogonal


def test_validation_errors():
    with pytest.raises(ShapeError, match="J"):
        pinv(np.ones(3))
    with pytest.raises(NonFiniteError, match="J"):
        pinv([[1.0, np.nan]])
    with pytest.raises(InputError, match="weights"):
        weighted_pinv(np.ones((1, 2)), [1.0, -1.0])
    with pytest.raises(ShapeError, match="weights"):
        weighted_pinv(np.ones((1, 2)), [1.0, 1.0, 1.0])
    with pytest.raises(InputError, match="positive-definite"):
        weighted_pinv(np.ones((1, 2)), [[1.0, 2.0], [2.0, 1.0]])
    with pytest.raises(InputError, match="not both"):
        weighted_pinv(np.ones((1, 2)), [1.0, 1.0], inverse_weights=[1.0, 1.0])
    with pytest.raises(InputError, match="damping"):
        damped_pinv(np.ones((1, 2)), -1.0)
