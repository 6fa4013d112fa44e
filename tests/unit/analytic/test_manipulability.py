import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.analytic import (
    dexterous_task_priority,
    jacobian_derivatives,
    manipulability,
    manipulability_gradient,
    shaping_function,
    sign_switch,
    singularity_robust_task_priority,
    weighted_pinv,
)
from uvms_qp.errors import InputError, NonFiniteError, ShapeError


def two_link_jacobian(q, l1=1.0, l2=1.0):
    s1, c1 = np.sin(q[0]), np.cos(q[0])
    s12, c12 = np.sin(q[0] + q[1]), np.cos(q[0] + q[1])
    return np.array([[-l1 * s1 - l2 * s12, -l2 * s12], [l1 * c1 + l2 * c12, l2 * c12]])


def planar_uvms_position_jacobian(q):
    """Soylu et al.'s (2007) planar UVMS: q = [x, y, psi, q1, q2, q3], r = l = 1 m,
    x_p = [x_e, y_e]."""
    psi = q[2]
    a = psi + np.cumsum(q[3:])
    J = np.zeros((2, 6))
    J[:, :2] = np.eye(2)
    # end effector: (x, y) + r (cos psi, sin psi) + sum_i (cos a_i, sin a_i)
    J[:, 2] = [-np.sin(psi) - np.sin(a).sum(), np.cos(psi) + np.cos(a).sum()]
    for j in range(3):
        J[:, 3 + j] = [-np.sin(a[j:]).sum(), np.cos(a[j:]).sum()]
    return J


def test_two_link_manipulability_is_l1_l2_abs_sin_q2():
    for q2 in (0.3, 1.2, np.pi / 2, 2.5):
        assert np.isclose(manipulability(two_link_jacobian([0.4, q2])), abs(np.sin(q2)))
    assert manipulability(two_link_jacobian([0.4, 0.0])) == pytest.approx(0.0, abs=1e-12)
    assert manipulability(np.ones((3, 2))) == 0.0


@given(st.integers(0, 10_000))
def test_manipulability_gradient_matches_finite_differences(seed):
    q = np.random.default_rng(seed).uniform(-2, 2, 6)
    J_a = lambda q: np.vstack([planar_uvms_position_jacobian(q), np.eye(3, 6)])  # noqa: E731
    rho = lambda q: manipulability(J_a(q))  # noqa: E731
    if rho(q) < 1e-3:
        return
    grad = manipulability_gradient(J_a(q), jacobian_derivatives(J_a, q))
    h = 1e-6
    fd = np.array([(rho(q + h * e) - rho(q - h * e)) / (2 * h) for e in np.eye(6)])
    assert np.allclose(grad, fd, atol=1e-6)


def test_collective_jacobian_manipulability_equals_arm_manipulability():
    # Soylu et al. (2007): J_a = [J_p; J_s], J_s = [I 0]  ->  rho(J_a) = rho(arm columns of J_p)
    q = np.array([0.3, -0.2, 0.5, np.pi / 3, -np.pi / 3, np.pi / 3])
    Jp = planar_uvms_position_jacobian(q)
    J_a = np.vstack([Jp, np.eye(3, 6)])
    assert np.isclose(manipulability(J_a), manipulability(Jp[:, 3:]))
    # the paper's start pose: arm angles (pi/3, -pi/3, pi/3) ends at (3, 1.7321)
    a = np.cumsum([np.pi / 3, -np.pi / 3, np.pi / 3])
    assert np.allclose([1 + np.cos(a).sum(), np.sin(a).sum()], [3.0, 1.7321], atol=1e-4)


def test_shaping_function_regions_and_smoothness():
    rb = 1.3
    assert shaping_function(1.3, rb) == 0.0
    assert shaping_function(5.0, rb) == 0.0
    assert shaping_function(0.64, rb) == 1.0
    assert shaping_function(0.65, rb) == pytest.approx(1.0)
    assert shaping_function(0.975, rb) == pytest.approx(0.5)
    r = np.linspace(0.0, 2.0, 401)
    k = shaping_function(r, rb)
    assert k.shape == r.shape
    assert np.all(np.diff(k) <= 1e-15)  # non-increasing
    assert np.abs(np.diff(k)).max() < 0.02  # continuous
    with pytest.raises(InputError, match="rho_bar"):
        shaping_function(1.0, 0.0)
    with pytest.raises(NonFiniteError, match="rho"):
        shaping_function(np.nan, 1.0)


def test_sign_switch_convention():
    assert sign_switch(0.0) == 1.0
    assert sign_switch(-0.5) == 1.0
    assert sign_switch(1e-9) == 0.0


def test_dexterous_task_priority_regimes():
    q = np.array([0.0, 0.0, 0.0, 0.2, 0.1, 0.1])  # nearly stretched arm
    Jp = planar_uvms_position_jacobian(q)
    Js = np.eye(3, 6)
    W = [10, 10, 10, 1, 1, 1]
    xp, xs = np.array([0.3, 0.1]), np.zeros(3)
    grad = np.array([0, 0, 0, 0.0, 1.0, 0.5])
    sr = singularity_robust_task_priority(Jp, xp, Js, xs, W)
    # rho above threshold: k = 0, Eq. (21) reduces to the weighted SR task priority
    high = dexterous_task_priority(Jp, xp, Js, xs, 2.0, grad, 1.3, 10.0, W)
    assert np.allclose(high, sr)
    # rho below half the threshold and worsening: pure projected gradient
    low = dexterous_task_priority(Jp, xp, Js, xs, 0.1, grad, 1.3, 10.0, W, rho_rate=-1.0)
    Jw = weighted_pinv(Jp, W)
    expected = Jw @ xp + (np.eye(6) - Jw @ Jp) @ (10.0 * grad)
    assert np.allclose(low, expected)
    # improving manipulability switches the gradient off
    off = dexterous_task_priority(Jp, xp, Js, xs, 0.1, grad, 1.3, 10.0, W, rho_rate=+1.0)
    assert np.allclose(off, Jw @ xp)
    for sol in (high, low, off):
        assert np.allclose(Jp @ sol, xp)


def test_manipulability_validation():
    with pytest.raises(ShapeError, match="dJ"):
        manipulability_gradient(np.eye(2), np.zeros((2, 3, 2)))
    with pytest.raises(ShapeError, match="Js"):
        dexterous_task_priority(np.eye(2), [1, 1], np.eye(3), [0, 0, 0], 1, [0, 0], 1.3, 1.0)
