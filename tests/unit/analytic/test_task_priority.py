import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_qp.analytic import (
    closed_loop_reference,
    davies_solve,
    gradient_projection,
    multi_objective_gradient_projection,
    normalized_gradient,
    pinv,
    recursive_task_priority,
    singularity_robust_task_priority,
    sr_task_priority_closed_loop,
    task_priority,
    weighted_pinv,
)
from uvms_qp.errors import InputError, ShapeError


def _problem(seed, n=7, m1=2, m2=3):
    rng = np.random.default_rng(seed)
    return (
        rng.normal(size=(m1, n)),
        rng.normal(size=m1),
        rng.normal(size=(m2, n)),
        rng.normal(size=m2),
        rng.uniform(0.2, 5.0, n),
    )


def _eq10(J1, x1, J2, x2):
    J1p = pinv(J1)
    N1 = np.eye(J1.shape[1]) - J1p @ J1
    return J1p @ x1 + N1 @ pinv(J2 @ N1) @ (x2 - J2 @ J1p @ x1)


@given(st.integers(0, 10_000))
def test_recursive_with_two_tasks_equals_eq10(seed):
    J1, x1, J2, x2, _ = _problem(seed)
    expected = _eq10(J1, x1, J2, x2)
    assert np.allclose(task_priority(J1, x1, J2, x2), expected, atol=1e-9)
    assert np.allclose(recursive_task_priority([(J1, x1), (J2, x2)]), expected, atol=1e-9)


@given(st.integers(0, 10_000))
def test_recursive_is_lexicographic_in_weighted_metric(seed):
    rng = np.random.default_rng(seed)
    n = 9
    tasks = [(rng.normal(size=(m, n)), rng.normal(size=m)) for m in (2, 3, 2)]
    w = rng.uniform(0.2, 5.0, n)
    x = recursive_task_priority(tasks, w)
    # feasible stack (7 rows <= 9 vars): every task is met exactly
    for J, b in tasks:
        assert np.allclose(J @ x, b, atol=1e-8)
    # and x is the minimum-W-norm solution of the stacked system
    A = np.vstack([J for J, _ in tasks])
    b = np.concatenate([b for _, b in tasks])
    assert np.allclose(x, weighted_pinv(A, w) @ b, atol=1e-8)


def test_recursive_infeasible_lower_task_is_least_squares_in_null_space():
    # 2 variables: task 1 fixes x0 = 1, task 2 asks x0 = 0 and x1 = 2: x0 stays 1
    x = recursive_task_priority([(np.array([[1.0, 0.0]]), [1.0]), (np.eye(2), [0.0, 2.0])])
    assert np.allclose(x, [1.0, 2.0])


@given(st.integers(0, 10_000))
def test_sr_equals_tp_when_tasks_do_not_conflict(seed):
    rng = np.random.default_rng(seed)
    # secondary task acting on the kernel of the primary only: J2 = C N1 style decoupling
    J1 = np.hstack([rng.normal(size=(2, 3)), np.zeros((2, 3))])
    J2 = np.hstack([np.zeros((3, 3)), np.eye(3) + 0.3 * rng.uniform(-1, 1, (3, 3))])
    x1, x2 = rng.normal(size=2), rng.normal(size=3)
    tp = task_priority(J1, x1, J2, x2)
    sr = singularity_robust_task_priority(J1, x1, J2, x2)
    assert np.allclose(sr, tp, atol=1e-9)
    # damping -> 0 recovers it too
    srd = singularity_robust_task_priority(J1, x1, J2, x2, damping=1e-7)
    assert np.allclose(srd, tp, atol=1e-5)


def test_sr_differs_from_tp_under_conflict_but_keeps_primary():
    J1, x1, J2, x2, w = _problem(11, n=4, m1=2, m2=3)
    tp = task_priority(J1, x1, J2, x2)
    sr = singularity_robust_task_priority(J1, x1, J2, x2)
    assert not np.allclose(sr, tp)
    assert np.allclose(J1 @ sr, x1) and np.allclose(J1 @ tp, x1)
    # the secondary residual of TP is optimal: SR's cannot be smaller
    assert np.linalg.norm(J2 @ tp - x2) <= np.linalg.norm(J2 @ sr - x2) + 1e-12
    srw = singularity_robust_task_priority(J1, x1, J2, x2, w)
    assert np.allclose(J1 @ srw, x1)


def test_sr_matches_eq15_formula_with_weights():
    J1, x1, J2, x2, w = _problem(4)
    J1w = weighted_pinv(J1, w)
    expected = J1w @ x1 + (np.eye(7) - J1w @ J1) @ weighted_pinv(J2, w) @ x2
    assert np.allclose(singularity_robust_task_priority(J1, x1, J2, x2, w), expected)


def test_paper000_closed_loop_with_selection_secondary():
    # Soylu et al. (2007) set-up: q = [x, y, psi, q1, q2, q3], J_s = [I 0], W = diag(10,10,10,1,1,1)
    rng = np.random.default_rng(2)
    Jp = rng.normal(size=(2, 6))
    Js = np.hstack([np.eye(3), np.zeros((3, 3))])
    W = [10, 10, 10, 1, 1, 1]
    e_p, e_s = np.array([0.01, -0.02]), np.array([0.0, 0.0, 0.01])
    xd = np.array([0.1, 0.2])
    q = sr_task_priority_closed_loop(Jp, xd, e_p, [10, 10], Js, np.zeros(3), e_s, [10, 10, 100], W)
    assert np.allclose(Jp @ q, xd + 10 * e_p)
    assert np.allclose(closed_loop_reference(np.zeros(3), e_s, [10, 10, 100]), [0, 0, 1.0])


@given(st.integers(0, 10_000), st.floats(-5, 5))
def test_gradient_projection_leaves_primary_unchanged(seed, gain):
    J1, x1, _, _, w = _problem(seed)
    g = np.random.default_rng(seed).normal(size=7)
    for weights in (None, w):
        q = gradient_projection(J1, x1, g, gain, weights)
        assert np.allclose(J1 @ q, x1, atol=1e-8)
    # with W = I it is exactly Eq. (4)
    J1p = pinv(J1)
    assert np.allclose(
        gradient_projection(J1, x1, g, gain), J1p @ x1 + (np.eye(7) - J1p @ J1) @ (gain * g)
    )


def test_gradient_projection_ascends_objective_when_gain_positive():
    J = np.array([[1.0, 1.0, 0.0]])
    g = np.array([0.0, 0.0, 1.0])
    q = gradient_projection(J, [0.0], g, 2.0)
    assert np.allclose(q, [0.0, 0.0, 2.0])


def test_multi_objective_normalises_and_signs():
    J = np.array([[1.0, 0.0, 0.0]])
    g1 = np.array([0.0, 100.0, 0.0])  # huge gradient does not dominate after Eq. (11)
    g2 = np.array([0.0, 0.0, 1e-3])
    q = multi_objective_gradient_projection(J, [0.5], [g1, g2], [1.0, -1.0], 0.2)
    assert np.allclose(q, [0.5, 0.2, -0.2])
    assert np.allclose(normalized_gradient(np.zeros(3)), 0.0)
    # motion distribution as inverse weights keeps the task
    qw = multi_objective_gradient_projection(
        J, [0.5], [g1, g2], [1.0, -1.0], 0.2, inverse_weights=[0.02, 1.0, 1.0]
    )
    assert np.isclose(qw[0], 0.5)


def test_task_priority_validation():
    with pytest.raises(ShapeError, match="J2"):
        task_priority(np.ones((1, 3)), [1.0], np.ones((1, 4)), [1.0])
    with pytest.raises(ShapeError, match="x1"):
        task_priority(np.ones((1, 3)), [1.0, 2.0], np.ones((1, 3)), [1.0])
    with pytest.raises(InputError, match="tasks"):
        recursive_task_priority([])
    with pytest.raises(ShapeError, match=r"tasks\[1\]"):
        recursive_task_priority([(np.ones((1, 3)), [1.0]), (np.ones((1, 2)), [1.0])])
    with pytest.raises(InputError, match="alphas"):
        multi_objective_gradient_projection(np.ones((1, 2)), [1.0], [np.ones(2)], [1.0, 2.0], 1.0)
    with pytest.raises(ShapeError, match="gradient"):
        gradient_projection(np.ones((1, 2)), [1.0], np.ones(3), 1.0)


def test_bad_sequences_name_the_item() -> None:
    with pytest.raises(InputError, match="tasks"):
        recursive_task_priority(None)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"tasks\[0\]"):
        recursive_task_priority([None])  # type: ignore[list-item]
    N = np.array([[1.0, 2.0]])
    with pytest.raises(InputError, match=r"primary\[0\]"):
        davies_solve(N, ["a"], [1.0])  # type: ignore[list-item]
    # Psi_1 = -N_1^{-1} N_0 Psi_0 = -(1 / 2) * 1
    np.testing.assert_allclose(davies_solve(N, [0], [1.0]), [1.0, -0.5])
